"""An attachment's field as a sweep axis and as a continued parameter (issue 33, item 5).

References: `simulate` at each cell's parameters (its own event search, the modes built for
that mass), the bare beam's closed-form modes where a massless point mass is the same model,
and the period map built anew at each continued mass.
"""

import re

import numpy as np
import pytest

from impactbeams import Contact, ParameterError, Params, simulate
from impactbeams.cli import main
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.orbits import PeriodMap
from impactbeams.params import named_attributes, parameter_value, with_parameter
from impactbeams.structure import PointMass, Spring
from impactbeams.sweep import run_sweep, sweep_from_mapping

MASS = "attachments1.0.mass"
STOP = {"counterpart": "stop", "contact_stiffness": 1e4}
# a point mass at beam 1's tip, its mass swept (left out of its table)
TIP = {**STOP, "attachments1": [{"position": 0.1}]}


def _sweep(fixed, axes, observables=("first_impact_time", "impact_count")):
    return sweep_from_mapping({"t_max": 0.05, "n_modes": 12, "observables": list(observables),
                               "params": fixed, "axes": axes}, source="mass sweep")


def test_each_cell_of_a_mass_axis_is_simulate_at_that_mass():
    """First impacts to 1e-12 s (both certified to round-off; measured equal) and impact
    counts bit for bit; the mass 0 cell is the bare beam's run (the same model: a massless
    point mass, the Wittrick-Williams modes instead of the closed forms) to 1e-13 of its
    first impact time (the bound of test_attachments' massless tip; measured 4.4e-16 here),
    and the same count."""
    axes = {MASS: {"min": 0.0, "max": 2e-3, "num": 3}, "omega": {"min": 40.0, "max": 60.0,
                                                                 "num": 2}}
    ds = run_sweep(_sweep(TIP, axes), parallel=False)
    assert ds[MASS].attrs["units"] == "kg" and ds[MASS].attrs["long_name"] == (
        "point mass of attachments1[0]")
    assert ds.attrs["attachments1"] == "{'position': 0.1}"  # as given: the mass is the axis
    assert list(ds[MASS].values) == [0.0, 1e-3, 2e-3]
    base = Params(**STOP)
    for i, mass in enumerate(ds[MASS].values):
        for j, omega in enumerate(ds.omega.values):
            params = base.replace(omega=float(omega), attachments1=(PointMass(0.1, mass),))
            run = simulate(params, 0.05, n_modes=12, dt_output=0.05)
            first = float(ds.first_impact_time[i, j])
            assert first == pytest.approx(float(run.impact_onset_time[0]), abs=1e-12)
            assert int(ds.impact_count[i, j]) == run.impact.size
            if mass == 0.0:
                bare = simulate(base.replace(omega=float(omega)), 0.05, n_modes=12,
                                dt_output=0.05)
                assert first == pytest.approx(float(bare.impact_onset_time[0]), rel=1e-13)
                assert int(ds.impact_count[i, j]) == bare.impact.size


def test_a_springs_stiffness_and_place_are_geometry_axes():
    """A spring to ground swept in stiffness from 0 and in place: each cell's first impact is
    simulate's at those values (1e-12 s); the preflight counts the spring at its stiffest."""
    fixed = {**STOP, "attachments1": [{"position": 0.1, "mass": 1e-3}, {}]}
    axes = {"attachments1.1.stiffness": {"min": 0.0, "max": 100.0, "num": 2},
            "attachments1.1.position": {"min": 0.04, "max": 0.08, "num": 2}}
    sweep = _sweep(fixed, axes, ("first_impact_time",))
    ds = run_sweep(sweep, parallel=False)
    assert ds["attachments1.1.stiffness"].attrs["units"] == "N/m"
    assert ds["attachments1.1.position"].attrs["long_name"] == (
        "distance from the clamp of attachments1[1]")
    for i, k in enumerate(ds["attachments1.1.stiffness"].values):
        for j, x in enumerate(ds["attachments1.1.position"].values):
            params = Params(**STOP, attachments1=(PointMass(0.1, 1e-3), Spring(x, k)))
            run = simulate(params, 0.05, n_modes=12, dt_output=0.05)
            assert float(ds.first_impact_time[i, j]) == pytest.approx(
                float(run.impact_onset_time[0]), abs=1e-12)


def test_a_mass_axis_beside_several_contacts_is_simulate_at_each_mass():
    """Each contact's own sweep keeps the part's axis: the earliest first impact of a stop
    under mid-span and one under the tip is simulate's at each mass (1e-12 s; measured
    3.5e-18 s)."""
    contacts = (Contact(position1=0.05, clearance=2e-6), Contact(clearance=1e-5))
    ds = run_sweep(_sweep({**TIP, "contacts": contacts}, {MASS: {"min": 0.0, "max": 2e-3,
                                                                 "num": 3}},
                          ("first_impact_time",)), parallel=False)
    for mass, first, which in zip(ds[MASS].values, ds.first_impact_time.values,
                                  ds.first_contact.values, strict=True):
        params = Params(**STOP, contacts=contacts, attachments1=(PointMass(0.1, mass),))
        run = simulate(params, 0.05, n_modes=12, dt_output=0.05)
        assert first == pytest.approx(float(run.impact_onset_time[0]), abs=1e-12)
        assert which == int(run.impact_contact[0])


def test_a_continuation_in_a_tip_mass_follows_fixed_points_of_each_masss_map():
    """Every branch point is a fixed point of the period map built at its mass (the maps are
    built anew per value), to 1e-12 of the state (measured 8e-14 over 12 points); the last
    one is not the start mass's (the mass moves the orbit)."""
    params = Params(**STOP, damping_ratio=0.05, force_amplitude=1e-3, omega=300.0,
                    attachments1=(PointMass(0.1, 5e-4),))
    dataset = continue_orbits(Continuation(params, MASS, 5e-4, 1e-3, n_modes=4, max_points=4))
    assert dataset[MASS].attrs == named_attributes(MASS)
    assert dataset.attrs["continued_parameter"] == MASS
    assert dataset[MASS].values[-1] > 5e-4
    for mass, state in zip(dataset[MASS].values, dataset.section_state.values, strict=True):
        at_mass = with_parameter(params, MASS, float(mass))
        assert parameter_value(at_mass, MASS) == mass
        mapped = PeriodMap(at_mass, 4)(state).state
        assert np.linalg.norm(mapped - state) <= 1e-12 * np.linalg.norm(state), mass
    moved = PeriodMap(params, 4)(state).state - state
    assert np.linalg.norm(moved) > 1e-6 * np.linalg.norm(state)


@pytest.mark.parametrize(("fixed", "axis", "message"), [
    (TIP, "attachments1.1.mass", r"\[axes.\"attachments1.1.mass\"\] of mass sweep = "
     r"'attachments1.1.mass' is not allowed: there are 1 parts in attachments1 of \[params\] "
     r"\(indices 0 to 0\)"),
    (TIP, "attachments1.0.weight", "unknown attachment field 'weight'"),
    ({**STOP, "attachments1": [{"position": 0.1, "mass": 1e-3}]}, MASS,
     r"is given both in \[params\] \(attachments1\[0\].mass = 0.001\) and as an axis"),
    ({**STOP, "attachments1": (PointMass(0.1, 1e-3),)}, MASS,
     r"gives its mass: give the part as a table without it to sweep it, e.g. "
     r"\{'position': 0.1, 'rotary_inertia': 0.0\}"),
    ({**STOP, "attachments1": (Spring(0.05, 10.0),)}, MASS, "has no field 'mass'"),
    (STOP, MASS, r"there are 0 parts in attachments1 of \[params\]$"),
])
def test_bad_attachment_axes_are_refused_in_one_line(fixed, axis, message):
    with pytest.raises(ParameterError, match=message) as error:
        _sweep(fixed, {axis: {"min": 1e-3, "max": 2e-3, "num": 2}})
    assert "\n" not in str(error.value)


def test_a_misnamed_part_axis_or_too_many_part_geometries_are_refused():
    with pytest.raises(ParameterError, match=re.escape(
            "an axis on an attachment's field is named attachments1.INDEX.FIELD, e.g. "
            "'attachments1.0.mass'")):
        _sweep(TIP, {"attachments1.x.mass": {"min": 0.0, "max": 1e-3, "num": 2}})
    # each point of the parts' axes is checked as parameters before any modes are built
    with pytest.raises(ParameterError, match="the parts' axes give 40000 geometries"):
        _sweep({**STOP, "attachments1": [{}]},
               {MASS: {"min": 0.0, "max": 1e-3, "num": 200},
                "attachments1.0.position": {"min": 0.05, "max": 0.1, "num": 200}})


def test_a_negative_mass_or_a_part_off_the_beam_is_refused_naming_the_grid_point(
        tmp_path, capsys):
    negative = f"{MASS} = -0.001 is not allowed: must be a finite real number >= 0 (kg)"
    with pytest.raises(ParameterError, match=re.escape(
            f"axis {MASS!r} of mass sweep reaches a non-physical point: {negative}")):
        _sweep(TIP, {MASS: {"min": -1e-3, "max": 1e-3, "num": 3}})
    # from the command line: that one line, exit 2, no file
    (tmp_path / "sweep.toml").write_text(
        't_max = 0.05\n[params]\ncounterpart = "stop"\nattachments1 = [{position = 0.1}]\n'
        f'[axes."{MASS}"]\nmin = -1e-3\nmax = 1e-3\nnum = 3\n')
    output = tmp_path / "out.nc"
    assert main(["run", str(tmp_path / "sweep.toml"), "-o", str(output), "--quiet"]) == 2
    said = capsys.readouterr().err.strip()
    assert negative in said and "\n" not in said and not output.exists()
    # the mass's place passes the shortest beam's tip at one corner of the grid
    with pytest.raises(ParameterError, match=re.escape(
            "at the grid point attachments1.0.position = 0.09, l1 = 0.08 of mass sweep: "
            "attachments1[0].position = 0.09 is not allowed: must lie on the beam, 0 < x <= "
            "0.08")):
        _sweep({**STOP, "attachments1": [{"mass": 1e-3}]},
               {"attachments1.0.position": {"min": 0.05, "max": 0.09, "num": 2},
                "l1": {"min": 0.08, "max": 0.1, "num": 2}})


@pytest.mark.parametrize(("parameter", "message"), [
    ("attachments1.1.mass", "there are 1 parts in params.attachments1 (indices 0 to 0)"),
    ("attachments1.0.stiffness", "attachments1[0] is a PointMass: its fields are position, "
     "mass, rotary_inertia"),
])
def test_a_continuation_refuses_a_part_or_field_that_is_not_there(parameter, message):
    params = Params(**STOP, attachments1=(PointMass(0.1, 5e-4),))
    with pytest.raises(ParameterError, match=re.escape(
            f"parameter = {parameter!r} is not allowed: {message}")):
        Continuation(params, parameter, 1e-4, 1e-3)
    with pytest.raises(ParameterError, match=re.escape(
            f"{MASS} = -0.0001 is not allowed: must be a finite real number >= 0 (kg)")):
        Continuation(params, MASS, -1e-4, 1e-3)


def test_a_continuation_file_continues_a_parts_field(tmp_path):
    """``[continuation] parameter = "attachments1.0.mass"``, the part in full in [params]:
    the continuation Python builds (its value there replaced along the branch)."""
    from impactbeams.continuation.definition import load_continuation

    path = tmp_path / "mass.toml"
    path.write_text('n_modes = 4\n[params]\ncounterpart = "stop"\ncontact_stiffness = 1e4\n'
                    "attachments1 = [{position = 0.1, mass = 5e-4}]\n[continuation]\n"
                    f'parameter = "{MASS}"\nmin = 5e-4\nmax = 1e-3\n')
    params = Params(**STOP, attachments1=(PointMass(0.1, 5e-4),))
    assert load_continuation(path) == Continuation(params, MASS, 5e-4, 1e-3, n_modes=4)
