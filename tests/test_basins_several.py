"""Basins of attraction with several contacts (issue 33): the cells run on the active sets' phases.

The model is tests/test_basins.py's (a cantilever against a stop of 100 N/m at its tip, 5 modes,
zeta = 0.02, F0 = 0.1 mN, Omega = 300 rad/s: an impacting and a non-impacting stable orbit
coexist), on the same plane of beam 1's first mode. Two sets of contacts:

* ``FAR``: that tip stop and a second one at mid-span 1 mm below, which never closes (the
  largest tip deflection on the plane's attractors is 47 um): it must give the single contact's
  map, cell by cell.
* ``TWO_SIDED``: a two-sided stop at the tip, 10 um below and above: the impacting orbit now
  closes both sides once a period (2 contacts per orbit), the non-impacting one survives.

Checks against independent computations: the single contact's map (one kernel call a chunk,
`kernels.basins.settle_cells`), a direct long `simulate` of several contacts from sampled
cells, `periodic_orbit` on `ContactsPeriodMap` (Newton, the exact monodromy).
"""

import math

import numpy as np
import pytest
import xarray as xr

from impactbeams import Contact, LongTime, Params, simulate, two_sided_stop
from impactbeams.kernels.basins import settled_from
from impactbeams.orbits import Settling, basins, periodic_orbit
from impactbeams.orbits.basin_contacts import ContactCellRunner
from impactbeams.orbits.basin_map import Plane, _Setup
from impactbeams.orbits.contacts_map import ContactsPeriodMap
from impactbeams.structure import PointMass
from test_basins import counting_chunks, ends_apart, interrupted_at_third_chunk

PARAMS = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                force_amplitude=1e-4, omega=300.0)
N_MODES = 5
BOX = ((-4e-5, 4e-5), (-1.2e-2, 1.2e-2))  # m, m/s
FAR = PARAMS.replace(contacts=(Contact(), Contact(0.5 * PARAMS.l1, clearance=1e-3)))
TWO_SIDED = PARAMS.replace(contacts=two_sided_stop(None, 1e-5, 1e-5))
# the two-sided stop on a beam with a 0.5 g tip mass (tests/test_attachment_curves.py's), at
# 220 rad/s: the mass moves the coexistence down from 300 rad/s
TIP_MASS = TWO_SIDED.replace(omega=220.0, attachments1=(PointMass(PARAMS.l1, 5e-4),))


def grid(num):
    return tuple(np.linspace(low, high, num) for low, high in BOX)


@pytest.fixture(scope="module")
def two_sided():
    return basins(TWO_SIDED, grid(9), n_modes=N_MODES, workers=1)


def starts(dataset):
    """Each cell's whole state z = (q, q'), rows in the order of the cells."""
    return np.concatenate([dataset.start_displacement.values, dataset.start_velocity.values],
                          axis=-1).reshape(dataset.basin.size, -1)


def test_a_stop_that_never_closes_gives_the_single_contact_s_map():
    """Beside a far stop the map is the single contact's: every cell's label and settle
    periods equal; the attractors' periods, contacts per orbit, states (round-off: the set
    phases' complex modes against the free table's real ones; measured 2.8e-15 of the largest
    coordinate), tip amplitudes (measured 1.3e-15) and multipliers (9.1e-15; |mu| < 1)."""
    single = basins(PARAMS, grid(11), n_modes=N_MODES)
    far = basins(FAR, grid(11), n_modes=N_MODES)
    assert single.attractor.size == 2 and set(np.unique(single.basin.values)) == {0, 1}
    for name in ("basin", "settle_periods", "attractor_period", "attractor_contacts"):
        np.testing.assert_array_equal(far[name].values, single[name].values)
    for name in ("attractor_displacement", "attractor_velocity"):
        np.testing.assert_allclose(far[name].values, single[name].values, rtol=0,
                                   atol=1e-12 * np.abs(single[name].values).max())
    np.testing.assert_allclose(far.attractor_amplitude, single.attractor_amplitude, rtol=1e-12)
    for part in ("real", "imag"):
        name = f"attractor_multiplier_{part}"
        np.testing.assert_allclose(far[name].values, single[name].values, rtol=0, atol=1e-12)


def _mask_first(start):
    q, v, mask = start
    return mask, q, v


def test_with_a_dashpot_states_inside_its_early_release_run_as_one_contact_s():
    """A dashpot on the tip stop (0.02 N s/m) beside the far one: states of the plane's lower
    right (into the stop, moving up fast), four of them inside the dashpot's early release
    (the stop open, its spring still compressed: no set of closed contacts fits), give the
    single contact's labels and settle periods cell by cell; such a state's run starts
    released: its first switch is that gap's opening (function n + 0), not an onset."""
    single = PARAMS.replace(contact_damping=0.02)
    far = single.replace(contacts=FAR.contacts)
    setup = _Setup.checked(far, N_MODES, None, (), None, 1, None, False)
    a, b = np.meshgrid(np.linspace(-3e-5, 0.0, 7), np.linspace(0.0, 0.05, 6), indexing="ij")
    states = Plane.checked(setup, None).states(a.ravel(), b.ravel())
    released = [i for i, z in enumerate(states)
                if setup.runner.map.early_released(*_mask_first(setup.runner.start(z)))]
    assert len(released) == 4
    run = setup.runner.block(setup.runner.start(states[released[0]]))[0]
    assert (run.mask[0], run.switched[1]) == (0, 2)
    expected = basins(single, initial_states=states, n_modes=N_MODES)
    found = basins(far, initial_states=states, n_modes=N_MODES)
    assert set(expected.basin.values) == {0, 1}
    for name in ("basin", "settle_periods", "attractor_contacts"):
        np.testing.assert_array_equal(found[name].values, expected[name].values)


def test_a_two_sided_stop_closes_both_sides_on_one_attractor(two_sided):
    """Two attractors, both period 1: the non-impacting orbit and an impacting one with two
    contacts per orbit, one on each side (its period map's run closes each alone), each basin
    a sizeable share; every cell settled."""
    assert two_sided.attractor_period.values.tolist() == [1, 1]
    assert sorted(two_sided.attractor_contacts.values.tolist()) == [0, 2]
    assert set(np.unique(two_sided.basin.values)) == {0, 1}
    assert np.all(two_sided.basin_fraction.values > 0.05)
    impacting = int(np.argmax(two_sided.attractor_contacts.values))
    z = np.concatenate([two_sided.attractor_displacement[impacting].values,
                        two_sided.attractor_velocity[impacting].values])
    run = ContactsPeriodMap(TWO_SIDED, N_MODES)(z, measures=False).trajectory
    assert set(run.mask.tolist()) == {0, 1, 2}  # below alone, above alone, neither


def test_sampled_cells_agree_with_a_direct_simulate(two_sided):
    """A direct `simulate` of several contacts over 600 periods from every cell next to a
    basin boundary and 6 others ends on the cell's attractor: its last section point within
    1e-6 of the scale of that attractor's (the transient decays by |mu| = 0.90 per period:
    0.9^600 = 3e-28) and more than 10 % of it from the other. Its own samples repeat from the
    period the map says the cell needed."""
    rng = np.random.default_rng(3)
    labels, needed = two_sided.basin.values, two_sided.settle_periods.values.ravel()
    padded = np.pad(labels, 1, mode="edge")
    boundary = np.zeros(labels.shape, bool)
    for shift in ((0, 1), (2, 1), (1, 0), (1, 2)):
        boundary |= padded[shift[0]:shift[0] + 9, shift[1]:shift[1] + 9] != labels
    labels, boundary = labels.ravel(), boundary.ravel()
    chosen = [*np.flatnonzero(boundary), *rng.choice(np.flatnonzero(~boundary), 6,
                                                     replace=False)]
    assert set(labels[chosen]) == {0, 1}
    omega, period = PARAMS.omega, 2 * math.pi / PARAMS.omega
    points = np.stack([two_sided.attractor_section_deflection1[:, 0],
                       two_sided.attractor_section_velocity1[:, 0] / omega], axis=-1)
    scale = np.abs(points).max()
    for cell in chosen:
        run = simulate(TWO_SIDED, 600 * period, N_MODES, dt_output=period,
                       initial_state=starts(two_sided)[cell],
                       long_time=LongTime(sampled_periods=600, max_period=8))
        end = np.array([run.poincare_deflection1[-1], run.poincare_velocity1[-1] / omega])
        apart = np.abs(points - end).max(axis=-1) / scale
        assert apart[labels[cell]] < 1e-6, (cell, apart)
        assert apart[1 - labels[cell]] > 0.1, (cell, apart)
        x = np.stack([run.poincare_deflection1, run.poincare_deflection2,
                      run.poincare_velocity1 / omega, run.poincare_velocity2 / omega], -1)[1:]
        assert settled_from(x, x.shape[0], 1, Settling().tolerance) == needed[cell]


def test_attractors_are_periodic_orbit_s_and_label_the_same_basins(two_sided):
    """Each attractor's state is the orbit Newton converges to from it on the period map of
    several contacts, to 1e-9 of its largest coordinate (measured 1.6e-11 and 0: a leftover
    transient changing by 1e-10 per period lies 1e-10 / (1 - 0.90) away); its leading
    multipliers are the exact monodromy's (1e-8), its tip amplitude the orbit's largest (256
    samples a period: within 1 - cos(pi / 256) = 7.5e-5 below). Given as attractors, those
    orbits label every cell as found."""
    orbits = []
    for k in two_sided.attractor.values:
        z = np.concatenate([two_sided.attractor_displacement[k].values,
                            two_sided.attractor_velocity[k].values])
        orbit = periodic_orbit(TWO_SIDED, N_MODES, int(two_sided.attractor_period[k]), guess=z)
        assert np.abs(orbit.state - z).max() < 1e-9 * np.abs(z).max()
        assert orbit.stable and orbit.contacts == int(two_sided.attractor_contacts[k])
        amplitude = float(two_sided.attractor_amplitude[k])
        assert orbit.max_tip1 * (1 - 1e-4) < amplitude <= orbit.max_tip1 * (1 + 1e-9)
        mu = (two_sided.attractor_multiplier_real[k]
              + 1j * two_sided.attractor_multiplier_imag[k]).values
        np.testing.assert_allclose(np.abs(mu[:4]), np.abs(orbit.multipliers[:4]), rtol=1e-8)
        orbits.append(orbit)
    given = basins(TWO_SIDED, grid(9), n_modes=N_MODES, attractors=orbits[::-1])
    assert given.attractor_given.values.tolist() == [1, 1]
    np.testing.assert_array_equal(given.basin.values, 1 - two_sided.basin.values)


def test_an_interrupted_run_resumes_on_threads(tmp_path, monkeypatch, two_sided):
    """Chunks of 9 cells on two threads: Ctrl-C in the third chunk keeps the finished ones,
    and the same call then runs only the others and gives the one-thread map bit for bit."""
    output = tmp_path / "basins.nc"
    original = ContactCellRunner.run_cells
    calls = interrupted_at_third_chunk(monkeypatch, ContactCellRunner)
    with pytest.raises(KeyboardInterrupt):
        basins(TWO_SIDED, grid(9), n_modes=N_MODES, output=output, workers=1, chunk_cells=9)
    assert len(list((tmp_path / "basins.nc.partial").glob("chunk_*.npz"))) == 2
    calls.clear()
    counting_chunks(monkeypatch, original, calls, ContactCellRunner)
    resumed = basins(TWO_SIDED, grid(9), n_modes=N_MODES, output=output, workers=2,
                     chunk_cells=9)
    assert calls == [9] * 7 and not (tmp_path / "basins.nc.partial").exists()
    for name in ("basin", "settle_periods", "attractor_displacement", "basin_fraction"):
        np.testing.assert_array_equal(resumed[name].values, two_sided[name].values)


BOX_OPTIONS = ["--axis1", "-4e-5,4e-5", "--axis2", "-1.2e-2,1.2e-2"]


def params_file(folder, above=1e-5):
    """TWO_SIDED's parameters file (the stop above ``above`` m away), as TWO_SIDED gives them:
    the contacts' stiffness the run's."""
    path = folder / f"two_sided_{above}.toml"
    path.write_text(
        '[params]\ncounterpart = "stop"\ncontact_stiffness = 100.0\ndamping_ratio = 0.02\n'
        "force_amplitude = 1e-4\nomega = 300.0\n"
        '[[params.contacts]]\nside = "below"\nclearance = 1e-5\n'
        f'[[params.contacts]]\nside = "above"\nclearance = {above}\n')
    return path


def test_cli_basins_of_several_contacts(tmp_path, capsys, two_sided):
    """``impactbeams basins --params`` of a file with ``[[params.contacts]]``: the map's file
    (the same labels as the library's); bad input: one line, exit 2, nothing written."""
    from impactbeams.cli import main

    params = params_file(tmp_path)
    output = tmp_path / "basins.nc"
    assert main(["basins", "--params", str(params), "--n-modes", "5", *BOX_OPTIONS, "--points", "9",
                 "-o", str(output)]) == 0
    assert "81 initial states, 2 attractors" in capsys.readouterr().err
    with xr.open_dataset(output) as written:
        np.testing.assert_array_equal(written.basin.values, two_sided.basin.values)
    for bad, word in ((["--contact-position1", "0.05"], "contact_position1"),
                      (["--coordinates", "0,20"], "coordinates"),
                      (["--omega", "0"], "omega")):
        assert main(["basins", "--params", str(params), "--n-modes", "5", *BOX_OPTIONS, *bad,
                     "-o", str(tmp_path / "x.nc")]) == 2
        err = capsys.readouterr().err
        assert word in err and "Traceback" not in err, err
        assert len(err.strip().splitlines()) == 1 and err.startswith("impactbeams: error:")
    assert not (tmp_path / "x.nc").exists()


def test_chunks_on_a_dask_cluster_give_the_same_map(two_sided):
    """Each chunk one task on a local cluster (the contacts packed on the worker): the same
    map, bit for bit, as one thread here."""
    from test_distributed import local_cluster

    with local_cluster(1) as client:
        remote = basins(TWO_SIDED, grid(9), n_modes=N_MODES, client=client, chunk_cells=27)
    for name in ("basin", "settle_periods", "attractor_displacement", "attractor_velocity"):
        np.testing.assert_array_equal(remote[name].values, two_sided[name].values)


def test_a_continuation_of_several_contacts_labels_the_map(tmp_path, capsys, two_sided):
    """``--attractors`` a continuation of the two-sided stop in Omega: its orbit at 300 rad/s
    (the impacting one, converged on the map's contacts) labels first, every cell as found;
    one in the stop above's clearance gives that orbit at the map's clearance; a continuation
    of other contacts (the stop above 20 um away) is refused in one line."""
    from impactbeams.cli import main
    from impactbeams.continuation import Continuation, continue_orbits
    from impactbeams.orbits.basin_inputs import continued_orbits

    curve = tmp_path / "curve.nc"
    continue_orbits(Continuation(TWO_SIDED, "omega", 250.0, 330.0, n_modes=N_MODES,
                                 max_branches=1)).to_netcdf(curve)
    output = tmp_path / "given.nc"
    assert main(["basins", "--params", str(params_file(tmp_path)), "--n-modes", "5", *BOX_OPTIONS,
                 "--points", "9", "--attractors", str(curve), "-o", str(output)]) == 0
    with xr.open_dataset(output) as given:
        assert given.attractor_given.values.tolist() == [1, 0]
        assert given.attractor_contacts.values.tolist() == [2, 0]
        impacting = int(np.argmax(two_sided.attractor_contacts.values))
        np.testing.assert_array_equal(given.basin.values == 0,
                                      two_sided.basin.values == impacting)
    # continued in the stop above's clearance: its point at the map's 10 um is the same orbit
    # (each converged by Newton on the map's contacts to a relative residual of 1e-11, which
    # leaves 1e-11 / (1 - |mu|) = 1e-10 of the state; measured 4.3e-12)
    along = tmp_path / "clearance.nc"
    continue_orbits(Continuation(TWO_SIDED, "contacts.1.clearance", 0.8e-5, 1.2e-5,
                                 n_modes=N_MODES, max_branches=1)).to_netcdf(along)
    (orbit,) = continued_orbits(along, TWO_SIDED, N_MODES, "attractors")
    (same,) = continued_orbits(curve, TWO_SIDED, N_MODES, "attractors")
    assert np.abs(orbit.state - same.state).max() < 1e-9 * np.abs(same.state).max()
    capsys.readouterr()
    assert main(["basins", "--params", str(params_file(tmp_path, 2e-5)), "--n-modes", "5",
                 *BOX_OPTIONS, "--attractors", str(curve), "-o", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("impactbeams: error:") and len(err.strip().splitlines()) == 1
    assert "its orbits are of contacts = " in err and "clearance=2e-05" in err


def test_basins_of_a_two_sided_stop_on_a_beam_with_a_tip_mass():
    """Several contacts and an attachment together: the two-sided stop at a tip carrying a
    0.5 g mass has an impacting orbit closing both sides (2 contacts a period) beside the
    non-impacting one. Cells of each basin (the first three) end where a direct `simulate` of
    300 periods from the cell's state ends: on the cell's attractor to 1e-6 of the section
    points' scale (the transient decays by |mu| < 0.91 a period: 0.91^300 = 5e-13; measured
    2.7e-11) and more than 10 % from the other (138 %)."""
    dataset = basins(TIP_MASS, grid(7), n_modes=N_MODES, workers=1)
    assert dataset.attractor_period.values.tolist() == [1, 1]
    assert sorted(dataset.attractor_contacts.values.tolist()) == [0, 2]
    labels = dataset.basin.values.ravel()
    assert set(labels) == {0, 1}
    for label in (0, 1):
        for cell in np.flatnonzero(labels == label)[:3]:
            apart = ends_apart(TIP_MASS, dataset, N_MODES, cell)
            assert apart[label] < 1e-6 and apart[1 - label] > 0.1, (cell, apart)
