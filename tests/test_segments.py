"""Stepped beams in runs (issue 33): Params(segments1=...), files, runs and refusals.

References: the textbook cantilever's run of today's closed forms (a beam of equal segments
is it), the FE model of tests/fe_spring.py with EI and rhoA per element (its own error shown
by refining the mesh), the exact modes of `impactbeams.structure.Cantilever`, themselves
checked against FE models in tests/test_structure_modes.py.
"""

import json

import numpy as np
import pytest
import xarray as xr

from fe_spring import fe_spring_contacts
from impactbeams import simulate
from impactbeams.cli import main
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.continuation.twoparameter import BifurcationCurve, continue_curve
from impactbeams.modes import beam
from impactbeams.orbits import PeriodMap, periodic_orbit
from impactbeams.orbits.grazing import grazing_curve
from impactbeams.params import (
    ParameterError,
    Params,
    named_attributes,
    parameter_value,
    with_parameter,
)
from impactbeams.structure import Cantilever, PointMass, Segment
from impactbeams.structure.user import ModalStructure
from impactbeams.sweep import run_sweep, sweep_from_mapping
from test_attachment_curves import assert_basins_labelled_by
from test_attachments import assert_todays_contacts

EI, RHOA = 9.0167e-3, 1.8402e-2  # the default steel strip (N m^2, kg/m)
# a stiffer, heavier root (3 EI, 1.5 rhoA over 4 cm) on a 0.1 m beam: every step on 1 cm
ROOT = (Segment(0.04, 3 * EI, 1.5 * RHOA), Segment(0.06, EI, RHOA))
STOP = Params(counterpart="stop", contact_stiffness=1e4, segments1=ROOT)
# beam 2 stepped too, softer and lighter towards its tip
PAIR = Params(contact_stiffness=1e4, segments1=ROOT,
              segments2=(Segment(0.06, EI, RHOA), Segment(0.06, 0.5 * EI, 0.8 * RHOA)))


@pytest.mark.parametrize("counterpart", ["beam", "stop"])
def test_equal_segments_give_the_uniform_beams_run(counterpart):
    """Each beam as two equal halves: the structure's modes (Wittrick-Williams, roots refined
    on the wave-coefficient determinant to a few ulps, static data from the Green's function)
    in place of the closed forms give today's contacts to round-off, not bit for bit: onsets
    to 1e-13 relative (measured 2.2e-14 over the first 10), durations to 1e-13 of the release
    time (5e-16 s measured), peak forces to 1e-10 (measured 9e-12). One segment is the flat
    keys themselves: bit for bit."""
    today = Params(counterpart=counterpart, contact_stiffness=1e4, EI1=EI, rhoA1=RHOA)
    halves = {"segments1": (Segment(0.05, EI, RHOA),) * 2}
    if counterpart == "beam":
        halves["segments2"] = (Segment(0.06, today.EI2, today.rhoA2),) * 2
    stepped = today.replace(**halves)
    assert not beam(stepped, 1).closed_form and beam(today, 1).closed_form
    # the derived l1, EI1, rhoA1 (tip compliance, mean mass per length): the uniform beam's
    assert (stepped.l1, stepped.EI1, stepped.rhoA1) == (today.l1, today.EI1, today.rhoA1)
    assert today.replace(segments1=(Segment(0.1, EI, RHOA),)) == today
    expected, got = (simulate(p, 0.05, n_modes=20) for p in (today, stepped))
    assert_todays_contacts(got, expected)
    assert got.attrs["segments1"] == "; ".join(map(repr, halves["segments1"]))
    assert "l1" not in got.attrs and "segments1" not in expected.attrs


def test_orbits_and_their_continuation_take_stepped_beams():
    """A damped stop's periodic orbit (4 modes, Omega = 300 rad/s): equal halves give the
    uniform beam's to 1e-12 of the state (measured 1.3e-14) and its Floquet multipliers to
    1e-10 (1e-13); each point of a continuation in Omega on the stiff-rooted beam is a fixed
    point of the period map built at its Omega, to 1e-12 of the state (7e-15)."""
    uniform = Params(counterpart="stop", contact_stiffness=1e4, damping_ratio=0.05,
                     omega=300.0, EI1=EI, rhoA1=RHOA)
    orbits = [periodic_orbit(p, n_modes=4, method="newton", tolerance=1e-13) for p in (
        uniform, uniform.replace(segments1=(Segment(0.05, EI, RHOA),) * 2))]
    assert (np.linalg.norm(orbits[1].state - orbits[0].state)
            <= 1e-12 * np.linalg.norm(orbits[0].state))
    assert np.abs(orbits[1].multipliers - orbits[0].multipliers).max() <= 1e-10
    stepped = uniform.replace(segments1=ROOT)
    branch = continue_orbits(Continuation(stepped, "omega", 300.0, 320.0, n_modes=4,
                                          max_points=4))
    assert branch.attrs["segments1"] == "; ".join(map(repr, ROOT))
    for omega, state in zip(branch.omega.values, branch.section_state.values, strict=True):
        mapped = PeriodMap(stepped.replace(omega=float(omega)), 4)(state).state
        assert np.linalg.norm(mapped - state) <= 1e-12 * np.linalg.norm(state), omega


ROOT_EI = "segments1.0.EI"
# the root's EI left out of its table: the axis gives it
ROOT_TABLES = {"counterpart": "stop", "contact_stiffness": 1e4, "segments1": [
    {"length": 0.04, "rhoA": 1.5 * RHOA}, {"length": 0.06, "EI": EI, "rhoA": RHOA}]}


def test_each_cell_of_a_segment_axis_is_simulate_with_that_segment():
    """A first-impact map over the root's EI (its table without EI): each cell is simulate's
    first impact of the beam with that root, to 1e-12 s (both certified to round-off;
    measured 7e-18 s); the coordinate has the field's unit and name, the Dataset the tables
    as given. The root at the tip's EI is no uniform beam (1.5 rhoA): the axis moves the
    first impact (by 1.6 ms from EI to 3 EI)."""
    ds = run_sweep(sweep_from_mapping({
        "t_max": 0.05, "n_modes": 12, "observables": ["first_impact_time"],
        "params": ROOT_TABLES, "axes": {ROOT_EI: {"min": EI, "max": 3 * EI, "num": 3},
                                        "omega": {"min": 40.0, "max": 60.0, "num": 2}}}),
        parallel=False)
    assert ds[ROOT_EI].attrs["units"] == "N m^2"
    assert ds[ROOT_EI].attrs["long_name"] == "bending stiffness of segments1[0]"
    assert ds.attrs["segments1"] == "; ".join(map(repr, ROOT_TABLES["segments1"]))
    for i, root_EI in enumerate(ds[ROOT_EI].values):
        for j, omega in enumerate(ds.omega.values):
            params = STOP.replace(omega=float(omega), segments1=(
                Segment(0.04, float(root_EI), 1.5 * RHOA), ROOT[1]))
            run = simulate(params, 0.05, n_modes=12, dt_output=0.05)
            assert float(ds.first_impact_time[i, j]) == pytest.approx(
                float(run.impact_onset_time[0]), abs=1e-12)
    assert np.ptp(ds.first_impact_time.values[:, 0]) > 1e-3


def test_a_continuation_in_a_segments_EI_follows_fixed_points_of_each_map():
    """Every branch point is a fixed point of the period map built at its root EI, to 1e-12
    of the state (measured 4e-13 over 4 points)."""
    params = STOP.replace(damping_ratio=0.05, omega=300.0)
    branch = continue_orbits(Continuation(params, ROOT_EI, 3 * EI, 4 * EI, n_modes=4,
                                          max_points=4))
    assert branch[ROOT_EI].attrs == named_attributes(ROOT_EI)
    assert branch[ROOT_EI].values[-1] > 3 * EI
    for root_EI, state in zip(branch[ROOT_EI].values, branch.section_state.values,
                              strict=True):
        at = with_parameter(params, ROOT_EI, float(root_EI))
        assert parameter_value(at, ROOT_EI) == root_EI
        mapped = PeriodMap(at, 4)(state).state
        assert np.linalg.norm(mapped - state) <= 1e-12 * np.linalg.norm(state), root_EI


def _segment_sweep(fixed, axis):
    return sweep_from_mapping({"t_max": 0.05, "n_modes": 12, "observables": [
        "first_impact_time"], "params": fixed, "axes": {axis: {"min": EI, "max": 2 * EI,
                                                               "num": 2}}})


@pytest.mark.parametrize(("build", "message"), [
    (lambda: _segment_sweep(ROOT_TABLES, "segments1.0.mass"),
     "unknown segment field 'mass'"),
    (lambda: _segment_sweep(ROOT_TABLES, "segments1.2.EI"),
     r"there are 2 parts in segments1 of \[params\] \(indices 0 to 1\)"),
    (lambda: _segment_sweep(ROOT_TABLES, "segments1.1.EI"),
     r"is given both in \[params\] \(segments1\[1\].EI = 0.0090167\) and as an axis"),
    (lambda: _segment_sweep({**ROOT_TABLES, "segments1": ROOT}, ROOT_EI),
     r"segments1\[0\] = Segment\(.*\) gives its EI: give the part as a table without it"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "params": ROOT_TABLES, "axes": {ROOT_EI: {
                                     "min": 1e-30, "max": EI, "num": 2}}}),
     r"axis 'segments1.0.EI' of sweep reaches a non-physical point: EI1 = 1e-30"),
    (lambda: Continuation(STOP, "l1", 0.1, 0.2),
     "parameter = 'l1' is not allowed: it is derived here from the beam's segments"),
])
def test_bad_segment_axes_are_refused_in_one_line(build, message):
    with pytest.raises(ParameterError, match=message):
        build()


@pytest.mark.slow
@pytest.mark.parametrize(("params", "meshes"), [(STOP, (80, 160, 320)),
                                                (PAIR, (160, 320, 640))],
                         ids=["stop", "two beams"])
def test_first_contacts_of_stepped_beams_agree_with_the_fe_model(params, meshes):
    """The first two contacts of 160 modes per beam against the FE model with EI and rhoA per
    element, every step on a node.

    The FE's first onset converges as h^4 (16x per halving, reached from above: 7.7x from 40
    to 80 elements, 11x from 80 to 160, 12.5x from 320 to 640 on two beams; at least 8x
    asserted), so the finest mesh's distance from the one before bounds its error; ours must
    lie within it. Two stepped beams need 640 elements: their second contact's duration
    crosses over between 160 and 320 (f160 - f320 = +2.9e-11 s, f320 - f640 = -3.1e-11 s),
    where the distance to 320 is no bound. 160 modes: at 40 the modes' own truncation (the
    residual falls like N^-3 at a free tip) is 3e-11 s on the second onset and 1.4e-10 N on
    the first peak, as large as the FE's error; 160 and 200 modes agree to 5e-13 s. Measured
    from the finest mesh (stop, 320): onsets 1.5e-13 s and 3.4e-12 s (the bound 1.7e-12 s,
    1.5e-11 s); two beams (640): onsets 1e-14 s and 1.5e-12 s (1.4e-13 s, 2.3e-11 s),
    durations 4e-12 s and 3e-12 s (4.6e-11 s, 3.1e-11 s).
    """
    fe = {n: fe_spring_contacts(params, 1e4, t_max=0.05, n_elements=(n, n), n_contacts=2,
                                mode_rtol=1e-9) for n in meshes}
    ds = simulate(params, 0.05, n_modes=160)
    ours = {"onset": ds.impact_onset_time.values[:2], "duration": ds.impact_duration.values[:2],
            "peak": ds.impact_peak_force.values[:2]}
    coarse, middle, fine = (fe[n]["onset"][0] for n in meshes)
    assert abs(coarse - middle) >= 8 * abs(middle - fine), (coarse, middle, fine)
    for key, values in ours.items():
        middle, fine = fe[meshes[1]][key], fe[meshes[2]][key]
        scale = 1.0 if key == "onset" else np.abs(fine)
        bound = np.abs(middle - fine) / scale + 4e-16 * np.abs(fine) / scale + 1e-12 * (
            key != "onset")
        assert np.all(np.abs(values - fine) / scale <= bound), (key, values - fine, bound)


def test_files_and_the_command_line_take_segments(capsys, tmp_path):
    """[[params.segments1]] tables: `impactbeams modes` lists the stepped beam's exact modes,
    a first-impact map equals single runs (both certified to round-off: 1e-12 s); the tied
    law and a beam key beside the segments are refused in one line, exit code 2."""
    tables = "".join(f"[[params.segments1]]\nlength = {s.length!r}\nEI = {s.EI!r}\n"
                     f"rhoA = {s.rhoA!r}\n" for s in ROOT)
    params = tmp_path / "rig.toml"
    params.write_text('[params]\ncounterpart = "stop"\ncontact_stiffness = 1e4\n' + tables)
    assert main(["modes", "--n", "6", "--json", "--params", str(params)]) == 0
    listed = json.loads(capsys.readouterr().out)["free"]["beam1"]
    assert listed == Cantilever(ROOT).modes(6).frequencies.tolist()
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('t_max = 0.05\nn_modes = 10\nobservables = ["first_impact_time"]\n'
                     '[params]\ncounterpart = "stop"\ncontact_stiffness = 1e4\n' + tables
                     + "[axes.omega]\nmin = 40.0\nmax = 60.0\nnum = 3\n")
    assert main(["run", str(sweep), "-o", str(tmp_path / "out.nc"), "--quiet"]) == 0
    with xr.open_dataset(tmp_path / "out.nc") as ds:
        assert ds.attrs["segments1"] == "; ".join(map(repr, ROOT))
        for omega, mapped in zip(ds.omega.values, ds.first_impact_time.values, strict=True):
            run = simulate(STOP.replace(omega=float(omega)), 0.05, n_modes=10, dt_output=0.05)
            assert float(mapped) == pytest.approx(float(run.impact_onset_time[0]), abs=1e-12)
    for extra, message in ((["--contact-law", "tied"], "supports the paper's uniform beams"),
                           (["--l1", "0.2"], "l1 = 0.2 is not allowed: must equal the total "
                                             "length of segments1, 0.1 m")):
        assert main(["modes", "--params", str(params), *extra]) == 2
        assert message in capsys.readouterr().err


@pytest.mark.parametrize(("build", "message"), [
    (lambda: Params(segments1=ROOT, l1=0.2),
     r"l1 = 0.2 is not allowed: must equal the total length of segments1, 0.1 m"),
    (lambda: Params(segments1=ROOT, EI1=EI), "EI1 in Params.. is not allowed with segments1"),
    (lambda: Params.from_mapping({"segments1": ROOT, "width1": 0.01}),
     "width1 in parameters is not allowed with segments1: each segment gives its own EI and "
     "rhoA"),
    (lambda: Params(segments1=ROOT, contact_law="tied"),
     "contact_law = 'tied' supports the paper's uniform beams only: use contact_law = 'spring' "
     "for a stepped beam"),
    (lambda: Segment(0.05, -EI, RHOA), "Segment.EI = -0.0090167 is not allowed: must be a "
                                       "finite real number > 0"),
    (lambda: Params(segments1=(Segment(0.05, 1e-30, RHOA), ROOT[1])),
     r"segments1\[0\].EI: EI1 = 1e-30 is not allowed: must be from 1e-24 to 1e\+17"),
    (lambda: Params.from_mapping({"segments1": [{"length": 0.05, "EI": EI}]}),
     r"segments1\[0\] = \{'length': 0.05, 'EI': 0.0090167\} is not allowed: a segment is a "
     "table of length"),
    (lambda: Params(segments1=(ROOT[0], PointMass(0.1, 1e-3))),
     r"segments1\[1\] = PointMass.* is not allowed: must be an impactbeams.Segment"),
    (lambda: Params(segments1=0.1), "segments1 = 0.1 is not allowed: must be a tuple"),
    (lambda: Params(counterpart="stop", segments2=ROOT), "counterpart = 'stop' has no beam 2"),
    (lambda: STOP.replace(l1=0.2), "l1 = 0.2 is not allowed: must equal the total length"),
    (lambda: Params(counterpart="stop", segments1=ROOT, structure1=ModalStructure(
        [100.0, 700.0], [1.0, 1.0], 1e-3, 1e-3, 0.1)),
     r"segments1 = \(Segment.*\) is not allowed: structure1 is beam 1 \(a user structure\)"),
    (lambda: Params(segments1=ROOT, attachments1=(PointMass(0.12, 1e-3),)),
     r"attachments1\[0\].position = 0.12 is not allowed: must lie on the beam, 0 < x <= 0.1"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "axes": {"segments1": {"min": 0.0, "max": 1.0, "num": 2}}}),
     "segments1 is not sweepable: give a beam's segments in .params., and sweep one "
     "segment's field as .axes.\"segments1.0.EI\".$"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "params": {"segments1": ROOT},
                                 "axes": {"EI1": {"min": 1e-3, "max": 1e-2, "num": 2}}}),
     r"\[axes.EI1\] of sweep is not allowed with segments1 in \[params\]"),
    # one segment is its beam's l1, EI1, rhoA1 at the grid's corners too (not the defaults)
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "params": {"counterpart": "stop", "segments1": [
                                     {"length": 0.05, "EI": EI, "rhoA": RHOA}]},
                                 "axes": {"clearance": {"min": 1e-5, "max": 0.02, "num": 2}}}),
     r"clearance = 0.02 is not allowed: the clearance must be <= 0.2 l1 = 0.01 m"),
])
def test_bad_segments_are_refused_in_one_line(build, message):
    with pytest.raises(ParameterError, match=message):
        build()


@pytest.mark.parametrize("segments", [
    ROOT, (Segment(0.02, 300 * EI, 0.5 * RHOA), Segment(0.08, EI, RHOA)),
    (Segment(0.05, EI, 10 * RHOA), Segment(0.05, 100 * EI, RHOA))],
    ids=["root", "stiff root", "heavy root"])
def test_the_preflight_bounds_the_highest_frequency_of_a_stepped_beam(segments):
    """The equivalent uniform beam (l1, EI1, rhoA1: the tip compliance and the mass) alone
    falls short of the exact 20th frequency (0.75 of it on the heavy root: the check would pass
    runs it should refuse); the min-max bound, sqrt(max EI / min rhoA), holds (1.1 to 17 times
    the exact value measured)."""
    from impactbeams.preflight import highest_frequency

    params = Params(counterpart="stop", segments1=segments)
    exact = beam(params, 1).free_modes(20).frequencies
    for n in (1, 10, 20):
        assert highest_frequency(params.numeric(), n, steps=params.step_factors) >= exact[n - 1]
    if segments[0].rhoA > segments[1].rhoA and segments[0].EI < segments[1].EI:
        assert highest_frequency(params.numeric(), 20) < 0.8 * exact[-1]


def test_a_grazing_curve_in_a_segments_field_finds_the_segment_whose_orbit_grazes():
    """A shaken stepped beam's clearance set to its orbit's closed-form gap amplitude |G| at
    200 rad/s: the grazing in the root's EI at 200 rad/s, a root searched on the segment's own
    modes (no closed form), is the root's EI, to Brent's tolerance (4 eps; measured equal)."""
    shaken = STOP.replace(shaker="beam1", base_amplitude=1e-4, force_amplitude=0.0,
                          damping_ratio=0.01)
    amplitude = grazing_curve(shaken, 5, "clearance", [200.0])["clearance"].values[0]
    found = grazing_curve(shaken.replace(clearance=float(amplitude)), 5, ROOT_EI, [200.0],
                          within=(1.5 * EI, 4.5 * EI))
    assert found[ROOT_EI].values[0] == pytest.approx(3 * EI, rel=1e-14)


def test_a_fold_curve_in_a_segments_EI_is_a_fold_of_each_EIs_map():
    """The soft stop's lower fold (301.0 rad/s, 3 modes) on a beam whose root segment is 1.2
    times stiffer, followed down in that segment's EI: every point is a fixed point of the
    period map built at its EI and Omega to 1e-10 of the state (measured 2.2e-15) with a
    multiplier at +1 to 1e-10 (as tests/test_attachment_curves.py's curve in a tip mass), and
    the fold moves."""
    soft = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                  force_amplitude=1e-4)
    stiff_root = soft.replace(segments1=(Segment(0.04, 1.2 * soft.EI1, soft.rhoA1),
                                         Segment(0.06, soft.EI1, soft.rhoA1)))
    continuation = Continuation(stiff_root, "omega", 240.0, 340.0, n_modes=3, subspace=4,
                                max_branches=1)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "fold", ROOT_EI, soft.EI1,
        1.2 * soft.EI1, direction="down", which=1, max_points=4))
    assert curve.branch_point.size == 4 and curve.omega.values[-1] < curve.omega.values[0] - 1
    for root_EI, omega, z in zip(curve[ROOT_EI].values, curve.omega.values,
                                 curve.section_state.values, strict=True):
        at = with_parameter(stiff_root.replace(omega=float(omega)), ROOT_EI, float(root_EI))
        result = PeriodMap(at, 3)(z, directions="all", measures=False)
        assert np.linalg.norm(result.state - z) <= 1e-10 * np.linalg.norm(z)
        assert np.abs(np.linalg.eigvals(result.jacobian) - 1.0).min() < 1e-10


def test_basins_on_a_stepped_beam_labelled_by_a_continuation_in_a_segments_EI(tmp_path):
    """tests/test_attachment_curves.py's basins at a tip mass, with the root segment's EI in
    place of the mass: the soft stop (3 modes) on a beam whose root is 1.2 times stiffer, at
    325 rad/s inside its hysteresis band (the lower fold is at 301 rad/s). A continuation in
    the root's EI (6 points from 1.2 EI up) labels the map with its orbit at 1.2 EI (a fixed
    point of that EI's period map to 1e-10 of the state); the other orbit is found by
    running. A cell of each basin ends where a direct `simulate` of 300 periods from its
    state ends: on the cell's attractor to 1e-6 of the section points' scale (the transient
    decays by the attractors' |mu| < 0.91 a period: 0.91^300 = 5e-13; measured on all 49
    cells 6.5e-14 on the continued orbit, 2.4e-10 on the one found by running, whose point is
    the settled map's) and more than 10 % from the other (98 %)."""
    soft = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                  force_amplitude=1e-4, omega=325.0)
    model = soft.replace(segments1=(Segment(0.04, 1.2 * soft.EI1, soft.rhoA1),
                                    Segment(0.06, soft.EI1, soft.rhoA1)))
    continued = tmp_path / "root.nc"
    continue_orbits(Continuation(model, ROOT_EI, 1.19 * soft.EI1, 1.21 * soft.EI1, n_modes=3,
                                 start=1.2 * soft.EI1, max_points=6,
                                 max_branches=1)).to_netcdf(continued)
    assert_basins_labelled_by(model, continued)
