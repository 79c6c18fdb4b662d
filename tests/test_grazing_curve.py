"""Grazing curves of the non-impacting orbit from the linear response (issue 34, item 2).

Checked against three independent computations: the steady tip amplitude of `simulate`'s
steady start and its root by Brent's method (tests/continuation_reference.py), the event
search of `simulate` (no contact just below the curve, contacts just above), and the
grazings located by `continue_orbits` on the nonlinear period map.
"""

import numpy as np
import pytest
import xarray as xr

import continuation_reference as reference
import impactbeams as ib
from impactbeams.cli import main
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.params import ParameterError
from impactbeams.variables import BIFURCATIONS, validate

GRAZING = BIFURCATIONS.index("grazing")
N_MODES = 5
# the shipped continuation example's stop: soft (k = 100 N/m), resolved by 5 modes
STOP = ib.Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                 force_amplitude=1e-4)
# the same stop, beam 1's clamp on a shaker (the stop stays), no tip force
STOP_SHAKEN = STOP.replace(force_amplitude=0.0, base_amplitude=2e-6, shaker="beam1")
# two beams, the spring as soft; beam 2's clamp shaken, with a tip force on beam 1 too
BEAMS = ib.Params(contact_stiffness=100.0, damping_ratio=0.02, force_amplitude=5e-5)
BEAMS_BOTH = BEAMS.replace(base_amplitude=2e-6, shaker="beam2")
# The closed form and the references sum the same modal terms in different orders: they agree
# to rounding (measured 0 to 1.4e-15 relative); a root in Omega moves by that rounding over the
# logarithmic slope of |G|, O(1) or more here, and Brent's method stops within 4 epsilons.
ROUNDING = 1e-12
# the continuation locates a grazing to locate_tolerance = 1e-11 of its range (0.2 of the
# value here: 2e-12 relative), its Newton corrector to 1e-10 of the state: the brief's 1e-9
LOCATED = 1e-9


@pytest.mark.parametrize(("params", "drive"), [(STOP, "force_amplitude"),
                                               (STOP_SHAKEN, "base_amplitude")])
@pytest.mark.parametrize("level", [0.5, 1.0, 2.0])
def test_against_the_steady_amplitudes_root(params, drive, level):
    """At three drive levels: the grazing frequency below resonance is the reference's root
    of |G(Omega)| = Delta (the tip amplitude of `simulate`'s steady start, which is the gap's
    against a fixed stop), and the closed form at that frequency gives the drive back."""
    params = params.replace(**{drive: level * getattr(params, drive)})
    (omega,) = ib.grazing_frequencies(params, N_MODES, 20.0, 245.0).omega.values
    expected = reference.stop_grazing(params, N_MODES, 20.0, 245.0)
    assert omega == pytest.approx(expected, rel=ROUNDING, abs=0.0)
    curve = ib.grazing_curve(params, N_MODES, drive, [expected])
    assert float(curve[drive][0]) == pytest.approx(getattr(params, drive), rel=ROUNDING, abs=0.0)


@pytest.mark.parametrize("params", [BEAMS, BEAMS_BOTH, STOP_SHAKEN.replace(shaker="both"),
                                    BEAMS.replace(damping_ratio=0.0, omega=190.0)])
def test_the_minimum_is_the_simulated_orbits_minimum(params):
    """On `simulate`'s steady start, the gap at `time_of_minimum` is `minimum` and its rate is
    zero (to rounding), and no sample of the period lies below it."""
    gap = ib.steady_gap(params, N_MODES)
    assert 0.0 < gap.minimum < params.clearance
    steady = params.replace(start="steady")
    period = 2 * np.pi / params.omega
    at = ib.simulate(steady, period, N_MODES, times=[gap.time_of_minimum])
    scale = abs(gap.phasor)
    assert float(at.gap[0]) == pytest.approx(gap.minimum, rel=0.0, abs=ROUNDING * scale)
    rate = float(at.tip_velocity_1[0] - at.tip_velocity_2[0])
    assert abs(rate) < ROUNDING * params.omega * scale
    samples = ib.simulate(steady, period, N_MODES, times=np.linspace(0.0, period, 4001))
    assert samples.gap.values.min() >= gap.minimum - ROUNDING * scale
    assert samples.gap.values.min() - gap.minimum < 1e-5 * scale  # sampled near it: (pi/4000)^2
    np.testing.assert_allclose(samples.gap.values, gap(samples.time.values), rtol=0.0,
                               atol=ROUNDING * scale)


@pytest.mark.parametrize(("params", "drive", "omega", "start"), [
    (STOP, "force_amplitude", 200.0, "rest"),
    (BEAMS_BOTH, "base_amplitude", 150.0, "steady")])
def test_no_contact_just_below_the_curve_and_contacts_just_above(params, drive, omega, start):
    """`simulate`'s event search at the grazing drive times 1 -+ 1e-6: no contact once the
    start's transient has decayed (from rest: by e^(-zeta omega_1 t), below 1e-7 of the
    clearance after 4 s), and a contact in every forcing period of the last 2 s above."""
    params = params.replace(omega=omega, start=start)
    grazing = float(ib.grazing_curve(params, N_MODES, drive, [omega])[drive][0])
    below, above = (ib.simulate(params.replace(**{drive: grazing * factor}), 8.0, N_MODES,
                                times=[0.0]).impact_onset_time.values
                    for factor in (1 - 1e-6, 1 + 1e-6))
    assert not np.any(below > 4.0)
    periods = 2.0 * omega / (2 * np.pi)
    assert np.count_nonzero(above > 6.0) >= np.floor(periods)


@pytest.mark.parametrize(("params", "parameter", "omega", "direction"), [
    (STOP, "force_amplitude", 200.0, "up"),
    (STOP_SHAKEN, "base_amplitude", 230.0, "up"),
    (BEAMS, "clearance", 150.0, "down"),
    (BEAMS_BOTH, "omega", None, "up"),
])
def test_against_the_continuations_located_grazing(params, parameter, omega, direction):
    """The first grazing that `continue_orbits` locates on the nonlinear period map, in a
    drive, the clearance or Omega over +-10 % of the closed form's value."""
    if parameter == "omega":
        (expected,) = ib.grazing_frequencies(params, N_MODES, 100.0, 160.0).omega.values
        params = params.replace(omega=0.9 * expected)
    else:
        params = params.replace(omega=omega)
        expected = float(ib.grazing_curve(params, N_MODES, parameter, [omega])[parameter][0])
    branch = continue_orbits(Continuation(params, parameter, 0.9 * expected, 1.1 * expected,
                                          direction=direction, n_modes=N_MODES,
                                          max_branches=1))
    located = branch[parameter].values[branch.bifurcation.values == GRAZING]
    assert located.size >= 1
    assert located[0] == pytest.approx(expected, rel=LOCATED, abs=0.0)


def test_a_drive_with_the_other_one_fixed():
    """Both drives: the grazing base amplitude at a fixed tip force is where the steady gap's
    minimum is zero; NaN where the tip force alone already closes the gap."""
    params = BEAMS_BOTH.replace(force_amplitude=2e-4)
    curve = ib.grazing_curve(params, N_MODES, "base_amplitude", [80.0, 100.0, 120.0, 200.0])
    values = curve.base_amplitude.values
    alone = [ib.steady_gap(params.replace(base_amplitude=0.0, omega=omega), N_MODES).minimum
             for omega in curve.omega.values]
    assert np.array_equal(np.isnan(values), np.array(alone) <= 0.0)
    assert np.isnan(values).any() and np.isfinite(values).sum() >= 2
    for omega, value, phase in zip(curve.omega.values, values, curve.grazing_phase.values,
                                   strict=True):
        if np.isfinite(value):
            gap = ib.steady_gap(params.replace(base_amplitude=value, omega=omega), N_MODES)
            assert abs(gap.minimum) < ROUNDING * params.clearance
            assert phase == pytest.approx(gap.phase_of_minimum, abs=ROUNDING)


def test_the_dataset():
    curve = ib.grazing_curve(STOP, N_MODES, "force_amplitude", np.linspace(100.0, 400.0, 7))
    validate(curve)
    assert curve.force_amplitude.attrs["units"] == "N" and curve.omega.attrs["units"] == "rad/s"
    assert curve.grazing_phase.attrs["units"] == "rad"
    assert curve.attrs["grazing_parameter"] == "force_amplitude"
    assert "force_amplitude" not in curve.attrs and curve.attrs["n_modes"] == N_MODES
    assert np.all((curve.grazing_phase >= 0.0) & (curve.grazing_phase < 2 * np.pi))
    # below the curve the gap opens: half the grazing force leaves half the steady amplitude
    for omega, force in zip(curve.omega.values, curve.force_amplitude.values, strict=True):
        gap = ib.steady_gap(STOP.replace(omega=omega, force_amplitude=force / 2), N_MODES)
        assert gap.minimum == pytest.approx(STOP.clearance / 2, rel=ROUNDING)
    none = ib.grazing_frequencies(STOP.replace(force_amplitude=1e-6), N_MODES, 100.0, 200.0)
    assert none.grazing_point.size == 0


@pytest.mark.parametrize(("call", "message"), [
    (lambda: ib.grazing_curve(STOP, N_MODES, "uplift1", [100.0]),
     "parameter = 'uplift1' is not allowed: must be one of 'force_amplitude', "
     "'base_amplitude', 'clearance'"),
    (lambda: ib.grazing_curve(STOP, N_MODES, "clearance", [100.0, 0.0]),
     "omega = 0.0 is not allowed: must be finite and > 0"),
    (lambda: ib.grazing_curve(STOP, N_MODES, "clearance", [np.nan]),
     "omega = nan is not allowed: must be finite and > 0"),
    (lambda: ib.grazing_curve(STOP, N_MODES, "clearance", []),
     "omega = [] is not allowed: must be a positive frequency or a 1-d sequence"),
    (lambda: ib.grazing_curve(STOP, 0, "clearance", [100.0]), "n_modes = 0 is not allowed"),
    (lambda: ib.grazing_frequencies(STOP, N_MODES, 200.0, 100.0),
     "high = 100.0 is not allowed: the range [200.0, 100.0] is empty"),
    (lambda: ib.grazing_frequencies(STOP, N_MODES, 100.0, 200.0, brackets=1),
     "brackets = 1 is not allowed"),
    (lambda: ib.steady_gap(STOP.replace(damping_ratio=0.0, omega=0.0), N_MODES),
     "omega = 0.0 is not allowed"),
])
def test_bad_input_in_one_line(call, message):
    with pytest.raises(ParameterError) as error:
        call()
    assert message in str(error.value) and "\n" not in str(error.value)


def test_undamped_resonance_refused():
    omega = float(ib.build_free_phase(STOP, N_MODES).frequencies[0])
    with pytest.raises(ParameterError, match=r"omega = .* is a natural frequency and "
                                             r"damping_ratio = 0"):
        ib.steady_gap(STOP.replace(damping_ratio=0.0, omega=omega), N_MODES)


STOP_OPTIONS = ["--counterpart", "stop", "--contact-stiffness", "100", "--damping-ratio",
                "0.02", "--force-amplitude", "1e-4", "--n-modes", "5"]


@pytest.mark.parametrize(("parameter", "extra"), [("force_amplitude", ["--points", "7"]),
                                                  ("omega", [])])
def test_the_command_writes_the_librarys_curve(tmp_path, capsys, parameter, extra):
    output = tmp_path / "grazing.nc"
    assert main(["grazing", parameter, "--omega-min", "100", "--omega-max", "400", *extra,
                 *STOP_OPTIONS, "-o", str(output)]) == 0
    expected = (ib.grazing_frequencies(STOP, N_MODES, 100.0, 400.0) if parameter == "omega"
                else ib.grazing_curve(STOP, N_MODES, parameter, np.linspace(100.0, 400.0, 7)))
    with xr.open_dataset(output) as written:
        validate(written)
        for name in ("omega", "grazing_phase", *([parameter] if parameter != "omega" else [])):
            np.testing.assert_array_equal(written[name].values, expected[name].values)
    assert capsys.readouterr().err.startswith(f"wrote {output}: ")


@pytest.mark.parametrize(("argv", "message"), [
    (["clearance", "--omega-min", "0", "--omega-max", "10"],
     "--omega-min = 0.0 is not allowed: must be finite and > 0 (rad/s)"),
    (["clearance", "--omega-min", "20", "--omega-max", "10"],
     "--omega-max = 10.0 is not allowed: the range [20.0, 10.0] is empty"),
    (["clearance", "--omega-min", "1", "--omega-max", "10", "--omega", "5"],
     "--omega is not allowed with grazing"),
    (["clearance", "--omega-min", "1", "--omega-max", "10", "--start", "steady"],
     "--start is not allowed with grazing"),
    (["clearance", "--omega-min", "1", "--omega-max", "10", "--points", "1"],
     "argument --points: 1 is not allowed: must be an integer >= 2"),
    (["uplift1", "--omega-min", "1", "--omega-max", "10"],
     "parameter = 'uplift1' is not allowed: must be one of 'force_amplitude', "
     "'base_amplitude', 'clearance', 'omega'"),
])
def test_the_commands_bad_input_exits_2_in_one_line(tmp_path, capsys, argv, message):
    output = tmp_path / "grazing.nc"
    assert main(["grazing", *argv, "-o", str(output)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("impactbeams: error: ") and message in err[-1]
    assert len(err) <= 2 and not output.exists()  # a usage line before argparse's errors
