"""Two-parameter curves and basins with an attachment's field as a parameter (issue 33, item 5).

The model: tests/test_two_parameter.py's soft stop (3 modes) with a point mass at beam 1's tip,
its mass the parameter (``attachments1.0.mass``). The independent checks: the period map built
anew at each point's mass (a fold's fixed point and multiplier at +1), the closed-form grazing
frequencies of the linear response at that mass (`grazing_frequencies`: the modes of the beam
with that mass, no shooting), the bare beam's at mass 0, and a direct `simulate` at the mass.
"""


import numpy as np
import pytest
import xarray as xr

import impactbeams as ib
from impactbeams import simulate
from impactbeams.cli import main
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.continuation.twoparameter import BifurcationCurve, continue_curve
from impactbeams.orbits import PeriodMap, basins
from impactbeams.orbits.basin_inputs import continued_orbits
from impactbeams.params import with_parameter
from impactbeams.structure import PointMass
from impactbeams.variables import validate
from test_basins import ends_apart

MASS = "attachments1.0.mass"
STOP = ib.Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                 force_amplitude=1e-4)
# a 0.5 g point mass at the tip: the hysteresis band moves down to 195.6 .. 222.4 rad/s
TIP_MASS = STOP.replace(attachments1=(PointMass(STOP.l1, 5e-4),))
N_MODES = 3
# a curve's point solves the augmented system to Newton's 1e-10 of its scaled unknowns (the
# parameters per their ranges, O(1) here): as tests/test_two_parameter.py's AGREE
AGREE = 1e-9


def at_mass(params, mass):
    return with_parameter(params, MASS, float(mass))


def test_fold_curve_in_a_tip_mass_is_a_fold_of_each_masss_map():
    """The lower fold (195.58 rad/s at 0.5 g) followed down in the mass: every point is a
    fixed point of the period map built at its own mass and Omega, to 1e-10 of the state
    (measured 7.7e-16), with a multiplier at +1 to 1e-10 (measured 3.4e-13: the curve solves
    the minimally augmented test to Newton's tolerance, not the multiplier itself); the
    mass moves the fold (Omega rises 9.8 rad/s as the mass falls to 0.41 g)."""
    continuation = Continuation(TIP_MASS, "omega", 193.0, 230.0, n_modes=N_MODES, subspace=4,
                                max_branches=1)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "fold", MASS, 2e-4, 5e-4,
        direction="down", which=1, max_points=10))
    validate(curve)
    assert curve[MASS].attrs["units"] == "kg" and curve.branch_point.size == 10
    assert curve.omega.values[-1] - curve.omega.values[0] > 5.0
    for mass, omega, z in zip(curve[MASS].values, curve.omega.values,
                              curve.section_state.values, strict=True):
        result = PeriodMap(at_mass(TIP_MASS.replace(omega=float(omega)), mass), N_MODES)(
            z, directions="all", measures=False)
        assert np.linalg.norm(result.state - z) <= 1e-10 * np.linalg.norm(z)
        assert np.abs(np.linalg.eigvals(result.jacobian) - 1.0).min() < 1e-10


CURVE_FILE = f"""n_modes = {N_MODES}
[params]
counterpart = "stop"
contact_stiffness = 100.0
damping_ratio = 0.02
force_amplitude = 1e-4
attachments1 = [{{position = 0.1, mass = 5e-4}}]
[continuation]
parameter = "omega"
min = 193.0
max = 230.0
max_branches = 1
[curve]
kind = "grazing"
second = "{MASS}"
min = 4.3e-4
max = 5e-4
direction = "down"
step = 0.1
max_step = 0.25
max_points = 12
"""


def test_the_command_follows_a_grazing_curve_in_a_tip_mass_the_closed_forms(tmp_path):
    """`impactbeams continue` with ``second = "attachments1.0.mass"``: the grazing (195.67
    rad/s at 0.5 g, past both folds) followed down in the mass to 0.43 g; each point's Omega
    is the closed-form grazing frequency of the linear orbit with the modes at its mass, to
    1e-9 (measured equal)."""
    path, out = tmp_path / "mass.toml", tmp_path / "mass.nc"
    path.write_text(CURVE_FILE)
    assert main(["continue", str(path), "-o", str(out), "--quiet"]) == 0
    with xr.open_dataset(out) as curve:
        validate(curve)
        assert curve.attrs["curve_parameters"] == f"omega {MASS}"
        masses, omegas, ending = curve[MASS].values, curve.omega.values, curve.attrs[
            "curve_ending"]
    assert ending == "bound" and masses[0] == 5e-4 and masses[-1] == 4.3e-4
    for mass, omega in zip(masses, omegas, strict=True):
        (closed,) = ib.grazing_frequencies(at_mass(TIP_MASS, mass), N_MODES, omega - 1.0,
                                           omega + 1.0).omega.values
        assert omega == pytest.approx(closed, rel=AGREE, abs=0.0)
    # the grazing curve in the mass: at each Omega the root of the least gap in the mass
    # (the modes built at each mass Brent's method tries), to round-off, at every other
    # point (measured 6.3e-16 there; 8.8e-16 at all seven)
    closed = ib.grazing_curve(TIP_MASS, N_MODES, MASS, omegas[::2], within=(3e-4, 6e-4))
    assert closed[MASS].attrs["units"] == "kg"
    np.testing.assert_allclose(closed[MASS].values, masses[::2], rtol=1e-13, atol=0.0)


@pytest.mark.parametrize(("within", "parameter", "message"), [
    (None, MASS, "within = None is not allowed: give the range of attachments1.0.mass to "
     "search, within=(low, high)"),
    ((6e-4, 3e-4), MASS, "is empty: need low < high"),
    ((-1e-4, 3e-4), MASS, "attachments1.0.mass = -0.0001 is not allowed: must be a finite "
     "real number >= 0 (kg)"),
    ((0.0, 1.0), "force_amplitude", "within = (0.0, 1.0) is not allowed: is for a part's "
     "field: force_amplitude has a closed form (leave it None)"),
    ((0.0, 1.0), "attachments1.0.stiffness", "parameter = 'attachments1.0.stiffness' is not "
     "allowed: attachments1[0] is a PointMass: its fields are position, mass"),
])
def test_a_grazing_curve_in_a_parts_field_refuses_bad_input_in_one_line(within, parameter,
                                                                        message):
    with pytest.raises(ib.ParameterError) as error:
        ib.grazing_curve(TIP_MASS, N_MODES, parameter, [200.0], within=within)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_a_grazing_curve_from_a_branch_in_the_mass_ends_on_the_bare_beams_grazing():
    """The mass as the first parameter: the branch in the mass at 198 rad/s grazes at 17 mg;
    followed up in Omega, the mass falls to its box's edge at 0, where the curve ends (its
    parameters refused past it: corrected onto the edge, not crept up to) on the bare
    beam's closed-form grazing (201.78 rad/s), to 1e-9 (measured 5.6e-16), and each point on
    the closed form at its mass (measured 7.1e-16)."""
    params = at_mass(STOP.replace(omega=198.0, attachments1=(PointMass(STOP.l1, 0.0),)), 0.0)
    # (from 15 mg, the params' 0 kept: the curve's first parameter starts at 0)
    continuation = Continuation(params, MASS, 0.0, 4e-5, start=1.5e-5, n_modes=N_MODES,
                                max_branches=1, max_points=6, transient_periods=0)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "grazing", "omega", 190.0, 205.0,
        step=0.05, max_step=0.1, max_points=12))
    assert curve.attrs["curve_ending"] == "bound"
    assert curve[MASS].values[-1] == 0.0 and curve.branch_point.size < 12
    (bare,) = ib.grazing_frequencies(STOP, N_MODES, 195.0, 205.0).omega.values
    assert float(curve.omega[-1]) == pytest.approx(bare, rel=AGREE, abs=0.0)
    for mass, omega in zip(curve[MASS].values, curve.omega.values, strict=True):
        (closed,) = ib.grazing_frequencies(at_mass(params, mass), N_MODES, omega - 1.0,
                                           omega + 1.0).omega.values
        assert omega == pytest.approx(closed, rel=AGREE, abs=0.0)


# 210 rad/s inside the band at 0.5 g: the impacting orbit and the non-impacting one coexist
BASIN_MODEL = TIP_MASS.replace(omega=210.0)
BOX = ((-4e-5, 4e-5), (-1.2e-2, 1.2e-2))  # m, m/s


def test_basins_at_a_tip_mass_labelled_by_a_continuation_in_the_mass(tmp_path):
    """A continuation in the mass (0.48 to 0.52 g at 210 rad/s) as the attractors: its orbit at
    0.5 g (Newton on that mass's period map: a fixed point to 1e-10 of the state) labels the
    map first, the impacting orbit is found by running. Cells on both basins end where a
    direct `simulate` of 300 periods at that mass from the cell's state ends: on the cell's
    attractor to 1e-6 of the section points' scale (the transient decays by the attractors'
    |mu| <= 0.904 a period: 0.904^300 = 7e-14) and more than 10 % from the other."""
    continued = tmp_path / "mass.nc"
    continue_orbits(Continuation(BASIN_MODEL, MASS, 4.8e-4, 5.2e-4, n_modes=N_MODES,
                                 max_branches=1)).to_netcdf(continued)
    assert_basins_labelled_by(BASIN_MODEL, continued)


def assert_basins_labelled_by(model, continued):
    """The 7 x 7 map of ``model`` (3 modes, BOX) labelled by the continuation in the file
    ``continued``: its orbit at ``model`` a fixed point of the map to 1e-10 of the state, and
    the impacting orbit found by running; the first cell of each basin ends where `simulate`
    of 300 periods ends (`test_basins.ends_apart`: to 1e-6, and more than 10 % from the
    other)."""
    orbits = continued_orbits(continued, model, N_MODES, "attractors")
    assert len(orbits) == 1
    z = orbits[0].state
    mapped = PeriodMap(model, N_MODES)(z).state
    assert np.linalg.norm(mapped - z) <= 1e-10 * np.linalg.norm(z)
    grid = tuple(np.linspace(low, high, 7) for low, high in BOX)
    dataset = basins(model, grid, n_modes=N_MODES, attractors=orbits, workers=1)
    assert dataset.attractor_given.values.tolist() == [1, 0]
    assert sorted(dataset.attractor_contacts.values.tolist()) == [0, 1]
    labels = dataset.basin.values.ravel()
    assert set(labels) == {0, 1}
    for label in (0, 1):
        cell = int(np.flatnonzero(labels == label)[0])
        # (the map's 3 modes, fewer than simulate's rule for the stop: it warns)
        with pytest.warns(RuntimeWarning, match="does not resolve the spring contact"):
            apart = ends_apart(model, dataset, N_MODES, cell)
        assert apart[label] < 1e-6 and apart[1 - label] > 0.1, (cell, apart)


def test_the_grazing_command_refuses_a_parts_field_in_one_line(tmp_path, capsys):
    (tmp_path / "mass.toml").write_text(CURVE_FILE.split("[continuation]")[0].split(
        "\n", 1)[1])
    assert main(["grazing", MASS, "--omega-min", "150", "--omega-max", "250", "--params",
                 str(tmp_path / "mass.toml"), "-o", str(tmp_path / "g.nc")]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"impactbeams: error: PARAMETER = '{MASS}' is not allowed here: "
                           "a part's field has no closed form")
    assert not (tmp_path / "g.nc").exists()


STEPPED = {"n_modes": 5, "transient_periods": 20, "sampled_periods": 4, "stepping": "up",
           "observables": ["poincare_deflection1", "response_period"],
           "params": {"counterpart": "stop", "contact_stiffness": 100.0, "damping_ratio": 0.02,
                      "force_amplitude": 1e-4, "attachments1": [{"position": STOP.l1}]},
           "axes": {MASS: {"min": 0.0, "max": 5e-4, "num": 2},
                    "omega": {"min": 190.0, "max": 230.0, "num": 3}}}


def test_a_stepped_sweep_along_omega_with_a_mass_axis_is_a_simulate_chain_per_mass():
    """The part's axis as parallel rows of a sweep stepped along Omega: each row is a chain of
    `simulate` runs at its mass, each from the previous run's end state (the first from
    rest), sample for sample to 1e-13 of the largest (measured bit for bit); the two
    masses' rows differ (the tip mass moves the resonance). Stepping along the mass itself
    is refused in one line, saying why."""
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    sweep = sweep_from_mapping(STEPPED)
    up = run_sweep(sweep, parallel=False).sel(sweep_direction="up")
    samples = up.poincare_deflection1.values
    assert np.abs(samples[1] - samples[0]).max() > 0.1 * np.abs(samples).max()
    for i, mass in enumerate(up[MASS].values):
        state = None
        for j, omega in enumerate(up.omega.values):
            params = at_mass(sweep.base, mass).replace(omega=float(omega))
            run = simulate(params, float(sweep.long_time.horizon(params.omega, 20)), n_modes=5,
                           initial_state=state, transient_periods=20,
                           long_time=sweep.long_time)
            assert np.abs(run.poincare_deflection1.values - samples[i, j]).max() <= (
                1e-13 * np.abs(samples).max())
            state = np.concatenate([run.final_displacement.values, run.final_velocity.values])
    with pytest.raises(ib.ParameterError, match="a part's field changes the modes") as error:
        sweep_from_mapping({**STEPPED, "stepped_axis": MASS})
    assert "\n" not in str(error.value)
