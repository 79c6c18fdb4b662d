"""Closed-form grazing curves with several contacts (issue 33, "several contacts").

Each contact has its own gap on the one linear orbit: the curve is the first contact's to
touch. Checked against the single contact's curve beside a stop that never closes (bit for
bit), against the continued grazing curve of the several contacts' period map (a different
method: shooting on the active sets' phases and the contact's physical gap), and each root of
`grazing_frequencies` against every contact's steady gap there.
"""

import numpy as np
import pytest
import xarray as xr

import impactbeams as ib
from impactbeams import ParameterError
from impactbeams.cli import main
from impactbeams.continuation import BifurcationCurve, Continuation, continue_orbits
from impactbeams.continuation.twoparameter import continue_curve
from impactbeams.variables import validate
from several_stops import FAR, N_MODES, STOP, TWO, TWO_TOML

OMEGA = np.linspace(50.0, 900.0, 171)


@pytest.mark.parametrize("parameter", ["force_amplitude", "base_amplitude"])
def test_beside_a_stop_that_never_closes_the_curve_is_the_single_stops(parameter):
    """The far stop's gap never closes first: the tip stop's own curve, bit for bit (its
    run's linear gap is the single stop's), the tip stop touching at every point."""
    params = {"force_amplitude": FAR, "base_amplitude": FAR.replace(base_amplitude=1e-6)}[
        parameter]
    several = ib.grazing_curve(params, N_MODES, parameter, OMEGA)
    single = ib.grazing_curve(params.each_contact()[0], N_MODES, parameter, OMEGA)
    validate(several)
    for name in (parameter, "grazing_phase"):
        np.testing.assert_array_equal(several[name].values, single[name].values)
    assert "grazing_contact" not in single
    np.testing.assert_array_equal(several.grazing_contact.values,
                                  np.where(np.isnan(single[parameter].values), -1, 0))


def test_two_stops_curve_is_the_continued_grazing_curve():
    """The non-impacting orbit's first grazing (the tip stop, 201.78 rad/s at 0.1 mN)
    continued in F0 on the several contacts' period map: every point is the closed form's
    first touch (the tip stop's, ``grazing_contact`` 0 there) to 1e-12 relative (measured
    1.1e-15: Newton on the grazing converges quadratically, so a point's last correction,
    below 1e-10 of the scaled unknowns, leaves it at round-off)."""
    continuation = Continuation(TWO, "omega", 195.0, 205.0, n_modes=N_MODES, max_branches=1)
    branch = continue_orbits(continuation)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, branch, "grazing", "force_amplitude", 5e-5, 2e-4, box=(150.0, 330.0),
        max_points=12))
    assert curve.attrs["curve_contact"] == 0
    closed = ib.grazing_curve(TWO, N_MODES, "force_amplitude", curve.omega.values)
    np.testing.assert_array_equal(closed.grazing_contact.values, 0)
    np.testing.assert_allclose(curve.force_amplitude.values, closed.force_amplitude.values,
                               rtol=1e-12, atol=0.0)


def test_the_first_contact_to_touch_changes_along_omega():
    """Over 50 to 900 rad/s each stop touches first somewhere; at each frequency the curve is
    the smaller of the two stops' own curves (each contact's run alone), and one contact's
    clearance curve is that stop's own where the other's gap stays open, NaN where it is
    closed at 0.1 mN (`steady_gap` of its run)."""
    curve = ib.grazing_curve(TWO, N_MODES, "force_amplitude", OMEGA)
    own = [ib.grazing_curve(run, N_MODES, "force_amplitude", OMEGA).force_amplitude.values
           for run in TWO.each_contact()]
    assert set(curve.grazing_contact.values.tolist()) == {0, 1}
    np.testing.assert_array_equal(curve.force_amplitude.values, np.minimum(*own))
    np.testing.assert_array_equal(curve.grazing_contact.values, np.argmin(own, axis=0))
    name = "contacts.1.clearance"
    clearance = ib.grazing_curve(TWO, N_MODES, name, OMEGA)
    validate(clearance)
    assert clearance[name].attrs["long_name"].endswith(" of contacts[1]")
    tip = TWO.each_contact()[0]
    open_tip = np.array([ib.steady_gap(tip.replace(omega=w), N_MODES).minimum > 0.0
                         for w in OMEGA])
    assert 0 < np.count_nonzero(open_tip) < OMEGA.size
    mid = ib.grazing_curve(TWO.each_contact()[1], N_MODES, "clearance", OMEGA)
    np.testing.assert_array_equal(clearance[name].values,
                                  np.where(open_tip, mid.clearance.values, np.nan))
    np.testing.assert_array_equal(clearance.grazing_contact.values, np.where(open_tip, 1, -1))


@pytest.mark.parametrize(("force", "contact"), [(2e-4, 0), (4e-4, 1)])
def test_grazing_frequencies_are_where_the_first_gap_touches(force, contact):
    """At 0.2 mN the tip stop grazes at both roots in 50 to 3000 rad/s, at 0.4 mN the
    mid-span one at all three: at each root the grazing stop's steady gap (its run's
    `steady_gap`) is 0 to 1e-12 of its clearance (Brent's method to 4 epsilons of Omega, the
    gap's slope there ~1e-7 m per rad/s; measured 5.1e-15) and the other stop's is open."""
    params = TWO.replace(force_amplitude=force)
    roots = ib.grazing_frequencies(params, N_MODES, 50.0, 3000.0)
    validate(roots)
    assert roots.omega.size >= 2
    np.testing.assert_array_equal(roots.grazing_contact.values, contact)
    for omega in roots.omega.values:
        runs = params.replace(omega=float(omega)).each_contact()
        minima = [ib.steady_gap(run, N_MODES).minimum for run in runs]
        assert abs(minima[contact]) < 1e-12 * runs[contact].clearance
        assert minima[1 - contact] > 0.0


@pytest.mark.parametrize(("call", "message"), [
    (lambda: ib.grazing_curve(TWO, N_MODES, "clearance", [100.0]),
     "parameter = 'clearance' is not allowed: must be one of 'force_amplitude', "
     "'base_amplitude' or one contact's clearance, 'contacts.INDEX.clearance' with INDEX from "
     "0 to 1 (with 2 contacts each gives its own)"),
    (lambda: ib.grazing_curve(TWO, N_MODES, "contacts.2.clearance", [100.0]),
     "parameter = 'contacts.2.clearance' is not allowed"),
    (lambda: ib.grazing_curve(TWO, N_MODES, "contacts.0.stiffness", [100.0]),
     "parameter = 'contacts.0.stiffness' is not allowed"),
    (lambda: ib.grazing_curve(STOP, N_MODES, "contacts.0.clearance", [100.0]),
     "parameter = 'contacts.0.clearance' is not allowed: must be one of 'force_amplitude', "
     "'base_amplitude', 'clearance'"),
    (lambda: ib.steady_gap(TWO, N_MODES), "contacts: 2 contacts are not allowed in steady_gap, "
     "which gives one gap: the gap of contact INDEX is steady_gap(params.each_contact()[INDEX]"),
])
def test_bad_input_in_one_line(call, message):
    with pytest.raises(ParameterError) as error:
        call()
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("parameter", ["force_amplitude", "contacts.1.clearance", "omega"])
def test_the_command_takes_a_parameters_file_with_contacts(tmp_path, capsys, parameter):
    (tmp_path / "two.toml").write_text(TWO_TOML)
    output = tmp_path / "grazing.nc"
    assert main(["grazing", parameter, "--omega-min", "50", "--omega-max", "900", "--points",
                 "11", "--params", str(tmp_path / "two.toml"), "--n-modes", "3", "-o",
                 str(output)]) == 0
    assert capsys.readouterr().err.startswith(f"wrote {output}: ")
    expected = (ib.grazing_frequencies(TWO, N_MODES, 50.0, 900.0, 11) if parameter == "omega"
                else ib.grazing_curve(TWO, N_MODES, parameter, np.linspace(50.0, 900.0, 11)))
    with xr.open_dataset(output) as written:
        validate(written)
        for name in expected.variables:
            np.testing.assert_array_equal(written[name].values, expected[name].values)


def test_the_command_refuses_the_flat_clearance_of_several_contacts(tmp_path, capsys):
    (tmp_path / "two.toml").write_text(TWO_TOML)
    output = tmp_path / "grazing.nc"
    assert main(["grazing", "clearance", "--omega-min", "50", "--omega-max", "900",
                 "--params", str(tmp_path / "two.toml"), "-o", str(output)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("impactbeams: error: parameter = 'clearance' is not allowed: must "
                           "be one of 'force_amplitude', 'base_amplitude', 'omega' or one "
                           "contact's clearance")
    assert not output.exists()
