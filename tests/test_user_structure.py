"""Beam 1 as the user's own structure (issue 33, item 4): matrices or modal data.

References: the FE model of tests/fe_reference.py and tests/fe_spring.py, whose contacts are
exact for its discrete model (the closed-form flexibility, every FE mode): passed as M and K it
is the same model, so the engine with all its modes must give the same contacts to the
eigensolver's round-off; and the textbook cantilever's closed forms, which given as modal data
must give today's results.
"""

import json
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
import xarray as xr

from fe_reference import _eig, beam_flexibility, beam_matrices, tip_dof
from fe_spring import fe_spring_contacts
from impactbeams import MatrixStructure, ModalStructure, simulate
from impactbeams.cli import main
from impactbeams.modes import beam
from impactbeams.params import ParameterError, Params
from impactbeams.structure.user import read_structure
from impactbeams.sweep import run_sweep, sweep_from_mapping

ELEMENTS = 40
STOP = Params(counterpart="stop", contact_stiffness=1e4)
K40, M40 = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, ELEMENTS)
TIP = tip_dof(ELEMENTS)


def fe_structure(sparse: bool = False, **keys) -> MatrixStructure:
    """The FE cantilever of 40 elements as a user structure (dense or CSR)."""
    M, K = (scipy.sparse.csr_matrix(a) for a in (M40, K40)) if sparse else (M40, K40)
    return MatrixStructure(M, K, contact_dof=TIP, length=STOP.l1, **keys)


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_the_fe_models_matrices_give_its_contacts(sparse):
    """All 80 modes of M, K: the FE reference's first three contacts. Measured: onsets within
    1e-13 s (dense) and 1.5e-11 s (sparse), durations, impulses and peaks within 5e-11
    (dense) and 1.4e-8 (sparse) relative; the low frequencies within 6e-11 of the reference's
    (from its closed-form flexibility). What is left is K's own round-off, cond(K) eps: the
    sparse LU's compliance and the modes' sum differ by 1e-10 of it, a residual flexibility
    in series with the contact spring that the dense Cholesky does not leave."""
    structure = fe_structure(sparse)
    reference = _eig(beam_flexibility(STOP.EI1, STOP.l1, ELEMENTS), M40)[0]
    # both lose a relative eps (omega_n / omega_1)^2 on the high modes (eigenvalues to
    # eps / omega_1^2 absolute): measured 2e-9 on the highest
    error = np.abs(structure.modes(2 * ELEMENTS).frequencies / reference - 1)
    assert np.all(error <= 1e-10 + 8 * np.finfo(float).eps * (reference / reference[0]) ** 2)
    np.testing.assert_allclose(structure.tip_compliance, STOP.tip_compliance[0], rtol=1e-9)
    fe = fe_spring_contacts(STOP, 1e4, t_max=0.05, n_elements=(ELEMENTS, ELEMENTS),
                            n_contacts=3, mode_rtol=1e-9)
    ds = simulate(STOP.replace(structure1=structure), 0.05, n_modes=2 * ELEMENTS)
    assert ds.impact.size >= 3
    np.testing.assert_allclose(ds.impact_onset_time.values[:3], fe["onset"], rtol=0, atol=1e-10)
    for ours, theirs in (("impact_duration", "duration"), ("impact_impulse", "impulse"),
                         ("impact_peak_force", "peak")):
        np.testing.assert_allclose(ds[ours].values[:3], fe[theirs], rtol=1e-7, atol=0)
    assert "MatrixStructure(80 DOFs" in ds.attrs["structure1"]


def test_the_low_modes_keep_their_digits_where_plain_eigh_loses_them():
    """200 elements (400 DOFs), the 12 lowest frequencies against the FE's own from its
    closed-form flexibility: shift-invert (sparse) and the flexibility's eigenproblem (dense)
    within 1e-8 (measured 3.9e-9 and 2.3e-9: K's own round-off, cond(K) eps ~ h^-4), plain
    eigh(K, M) off by 2e-5, more than 100 times as much."""
    n = 200
    K, M = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, n)
    reference = _eig(beam_flexibility(STOP.EI1, STOP.l1, n), M)[0][:12]
    errors = []
    for matrices in ((M, K), (scipy.sparse.csr_matrix(M), scipy.sparse.csr_matrix(K))):
        structure = MatrixStructure(*matrices, contact_dof=tip_dof(n), length=STOP.l1)
        errors.append(np.abs(structure.modes(12).frequencies / reference - 1).max())
    assert max(errors) <= 1e-8
    assert "shift-invert" in structure.describe(12)
    plain = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, 11]))
    assert np.abs(plain / reference - 1).max() > 100 * max(errors)


def analytic_modal_data(n: int, **keys) -> ModalStructure:
    """Today's beam 1 (closed forms) as modal data: its first ``n`` modes."""
    uniform = beam(STOP, 1)
    modes = uniform.free_modes(n)
    return ModalStructure(modes.frequencies, modes.shapes.tip(), uniform.tip_compliance,
                          33.0 / 140.0 * STOP.rhoA1 * STOP.l1, STOP.l1,
                          participation=uniform.participation(modes.shapes), **keys)


@pytest.mark.parametrize("drive", [{}, {"shaker": "beam1", "base_amplitude": 2e-6,
                                        "force_amplitude": 0.0, "omega": 300.0}],
                         ids=["tip force", "shaker"])
def test_modal_data_of_the_textbook_beam_give_todays_results(drive):
    """The closed forms' own numbers as modal data: today's contacts and tips bit for bit, the
    energies to 1e-13 of the largest energy (the kinetic norm's round-off: measured 8e-25 J
    of 1e-11 J)."""
    today = STOP.replace(**drive)
    given = today.replace(structure1=analytic_modal_data(20))
    expected, got = (simulate(p, 0.05, n_modes=20, energy_balance=True) for p in (today, given))
    assert expected.impact.size >= 2
    for name in ("impact_onset_time", "impact_duration", "impact_peak_force", "impact_impulse",
                 "tip_deflection_1", "work_of_force"):
        np.testing.assert_array_equal(got[name].values, expected[name].values, err_msg=name)
    # the static shape's kinetic norm: 33/140 rhoA l given, times 140 / (33 l) and l again
    scale = np.abs(expected.energy.values).max()
    for name in ("energy", "unresolved_kinetic_energy"):
        np.testing.assert_allclose(got[name].values, expected[name].values, rtol=0,
                                   atol=1e-13 * scale, err_msg=name)


def test_a_modes_sign_is_its_own_choice():
    """Modes 2 and 5 given with the other sign (contact value and participation factor both
    flipped) are the same modes: the same shaker run, bit for bit."""
    params = STOP.replace(shaker="beam1", base_amplitude=2e-6, force_amplitude=0.0, omega=300.0)
    given = analytic_modal_data(12)
    sign = np.ones(12)
    sign[[1, 4]] = -1.0
    flipped = ModalStructure(given.frequencies, sign * given.contact_values,
                             given.tip_compliance, given.static_mass, given.length,
                             participation=sign * given.participation)
    runs = [simulate(params.replace(structure1=s), 0.05, n_modes=12) for s in (given, flipped)]
    assert runs[0].impact.size >= 1
    np.testing.assert_array_equal(runs[1].impact_onset_time.values,
                                  runs[0].impact_onset_time.values)


def _map(params: dict, observable: str, n_modes: int = 12) -> xr.Dataset:
    return run_sweep(sweep_from_mapping({
        "t_max": 0.05, "n_modes": n_modes, "observables": [observable], "params": params,
        "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3},
                 "clearance": {"min": 1e-5, "max": 2e-5, "num": 2}}}, source="user"),
        parallel=False)


def test_maps_of_a_matrix_structure_equal_single_runs():
    """A first-impact map (the column kernel) and a long-time map (impact counts) against
    simulate()'s event search, cell by cell: onsets to 1e-12 s, counts exactly."""
    structure = fe_structure()
    fixed = {"counterpart": "stop", "contact_stiffness": 1e4, "structure1": structure}
    first = _map(fixed, "first_impact_time")
    counts = _map(fixed, "impact_count")
    params = Params(**fixed)
    for i, omega in enumerate(first.omega.values):
        for j, clearance in enumerate(first.clearance.values):
            run = simulate(params.replace(omega=float(omega), clearance=float(clearance)), 0.05,
                           n_modes=12, dt_output=0.05)
            assert float(first.first_impact_time[i, j]) == pytest.approx(
                float(run.impact_onset_time[0]), abs=1e-12)
            assert int(counts.impact_count[i, j]) == run.impact.size


def test_a_first_impact_map_of_modal_data_is_todays():
    today = _map({"counterpart": "stop", "contact_stiffness": 1e4}, "first_impact_time")
    given = _map({"counterpart": "stop", "contact_stiffness": 1e4,
                  "structure1": analytic_modal_data(12)}, "first_impact_time")
    np.testing.assert_array_equal(given.first_impact_time.values, today.first_impact_time.values)


def test_an_npz_file_from_the_command_line_and_a_sweep_file(capsys, tmp_path):
    """``modes --structure1 rig.npz`` states the eigenproblem and its frequencies are the
    structure's; a sweep file naming the .npz maps as the object does from Python."""
    path = tmp_path / "rig.npz"
    np.savez(path, mass=M40, stiffness=K40, contact_dof=TIP, length=STOP.l1)
    assert main(["modes", "--structure1", str(path), "--counterpart", "stop", "--n", "3",
                 "--contact-stiffness", "1e4", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["structure1"].startswith("structure1: 80 DOFs (dense), contact at DOF 78")
    assert "MiB" in result["structure1"]
    np.testing.assert_array_equal(result["free"]["beam1"], fe_structure().modes(3).frequencies)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        't_max = 0.05\nn_modes = 10\nobservables = ["first_impact_time"]\n[params]\n'
        f'counterpart = "stop"\ncontact_stiffness = 1e4\nstructure1 = "{path}"\n'
        "[axes.omega]\nmin = 40.0\nmax = 60.0\nnum = 3\n")
    assert main(["run", str(sweep), "-o", str(tmp_path / "out.nc"), "--quiet"]) == 0
    python = run_sweep(sweep_from_mapping({
        "t_max": 0.05, "n_modes": 10, "observables": ["first_impact_time"],
        "params": {"counterpart": "stop", "contact_stiffness": 1e4,
                   "structure1": fe_structure()},
        "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3}}}), parallel=False)
    with xr.open_dataset(tmp_path / "out.nc") as ds:
        assert f"from {path}" in ds.attrs["structure1"]
        np.testing.assert_array_equal(ds.first_impact_time.values,
                                      python.first_impact_time.values)
    assert main(["plot", str(tmp_path / "out.nc"), "-o", str(tmp_path / "map.png")]) == 0
    assert (tmp_path / "map.png").stat().st_size > 0
    bad = tmp_path / "bad.npz"
    np.savez(bad, mass=M40, stiffness=K40, contact_dof=TIP)
    assert main(["modes", "--structure1", str(bad), "--counterpart", "stop"]) == 2
    assert "the file has no array 'length'" in capsys.readouterr().err


def test_a_sparse_npz_file_is_the_dense_model():
    rows, cols = np.nonzero(K40)
    m_rows, m_cols = np.nonzero(M40)
    structure = read_npz({"stiffness_rows": rows, "stiffness_cols": cols,
                          "stiffness_values": K40[rows, cols], "mass_rows": m_rows,
                          "mass_cols": m_cols, "mass_values": M40[m_rows, m_cols],
                          "size": K40.shape[0], "contact_dof": TIP, "length": STOP.l1})
    # eigsh on the triplets, the flexibility's eigenproblem on the dense: K's round-off apart
    np.testing.assert_allclose(structure.modes(5).frequencies, fe_structure().modes(5).frequencies,
                               rtol=1e-9)


def test_a_modal_npz_file_is_the_modal_data():
    given = analytic_modal_data(6)
    read = read_npz({"frequencies": given.frequencies, "contact_values": given.contact_values,
                     "tip_compliance": given.tip_compliance, "static_mass": given.static_mass,
                     "length": given.length, "participation": given.participation})
    assert isinstance(read, ModalStructure) and read.digest == given.digest
    np.testing.assert_array_equal(read.modes(6).participation(), given.modes(6).participation())


def read_npz(arrays):
    """``arrays`` written to a .npz file and read back as a structure."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "s.npz"
        np.savez(path, **arrays)
        return read_structure(path)


def _asymmetric():
    K = K40.copy()
    K[0, 2] *= 1 + 1e-9
    return MatrixStructure(M40, K, contact_dof=TIP, length=0.1)


def _indefinite():
    K = K40.copy()
    K[0, 0] = -1.0
    return MatrixStructure(M40, K, contact_dof=TIP, length=0.1)


def _singular():
    K = K40.copy()
    K[-2:, :] = 0.0
    K[:, -2:] = 0.0  # the tip node held by nothing
    return MatrixStructure(M40, K, contact_dof=TIP, length=0.1)


def _nan():
    M = M40.copy()
    M[3, 3] = np.nan
    return MatrixStructure(M, K40, contact_dof=TIP, length=0.1)


def _sparse_indefinite():
    K = K40.copy()
    K[0, 0] = -1.0
    return MatrixStructure(scipy.sparse.csr_matrix(M40), scipy.sparse.csr_matrix(K),
                           contact_dof=TIP, length=0.1)


@pytest.mark.parametrize(("build", "message"), [
    (_asymmetric, r"structure1.stiffness = 'a matrix with max \|A - A\^T\| = .*' is not "
                  r"allowed: must be symmetric"),
    (_indefinite, "structure1.stiffness = 'a matrix' is not allowed: must be positive definite"),
    (_singular, "structure1.stiffness = 'a matrix' is not allowed: must be positive definite"),
    (_sparse_indefinite, "structure1.stiffness = 'a matrix' is not allowed: must be positive "
                         "definite"),
    (_nan, "structure1.mass = 'a matrix with NaN or inf' is not allowed: every entry must be "
           "finite"),
    (lambda: MatrixStructure(M40[:, :-1], K40, contact_dof=TIP, length=0.1),
     r"structure1.mass = 'shape \(80, 79\)' is not allowed: must be a square matrix"),
    (lambda: MatrixStructure(M40[:-2, :-2], K40, contact_dof=TIP, length=0.1),
     "structure1.stiffness = '80 x 80' is not allowed: must have the mass matrix's shape, "
     "78 x 78"),
    (lambda: MatrixStructure(M40, K40, contact_dof=80, length=0.1),
     "structure1.contact_dof = 80 is not allowed: must be a DOF index from 0 to 79"),
    (lambda: MatrixStructure(M40, K40, contact_dof=TIP, length=0.0),
     r"structure1.length = 0.0 is not allowed: must be > 0 \(m\)"),
    (lambda: MatrixStructure(M40, K40, contact_dof=TIP, length=0.1, influence=np.ones(80) * 2),
     r"structure1.influence\[78\] = 2.0 is not allowed: must be 1"),
    (lambda: MatrixStructure(M40, K40, contact_dof=TIP, length=0.1, influence=np.ones(3)),
     "structure1.influence = 'a real vector' is not allowed|structure1.influence = "),
    (lambda: MatrixStructure("M", K40, contact_dof=TIP, length=0.1),
     "structure1.mass = 'str' is not allowed: must be a real matrix"),
    (lambda: ModalStructure([2.0, 1.0], [1.0, 1.0], 1.0, 1.0, 0.1),
     "structure1.frequencies = .* is not allowed: must be positive and ascending"),
    (lambda: ModalStructure([1.0, 2.0], [1.0, 1.0], 1.0, 1.0, 0.1),
     r"structure1.tip_compliance = 1.0 is not allowed: must be at least the modes' flexibility"),
    (lambda: ModalStructure([1.0, 2.0], [1.0], 10.0, 1.0, 0.1),
     "structure1.contact_values = .* is not allowed: must be a real vector of 2 values"),
    (lambda: STOP.replace(structure1=fe_structure(), l1=0.2),
     "l1 = 0.2 is not allowed: structure1 is beam 1 .*: leave beam 1's keys out"),
    (lambda: Params(structure1=fe_structure(), counterpart="stop", contact_law="tied"),
     "contact_law = 'tied' supports the paper's uniform beams only"),
    (lambda: STOP.replace(structure1=fe_structure(), base_amplitude=1e-6),
     "base_amplitude = 1e-06 is not allowed: structure1 has no influence vector"),
    (lambda: STOP.replace(structure1="missing.npz"),
     "structure1 = 'missing.npz' is not allowed: must name an existing .npz file"),
    (lambda: STOP.replace(structure1=3.0),
     "structure1 = 3.0 is not allowed: must be an impactbeams.MatrixStructure"),
    (lambda: simulate(STOP.replace(structure1=fe_structure()), 0.01, n_modes=81),
     "n_modes = 81 is not allowed: structure1 has 80 modes"),
    (lambda: simulate(STOP.replace(structure1=fe_structure()), 0.01, n_modes=5, fields=True),
     "fields = True is not allowed: beam 1 is a user structure"),
    (lambda: ModalStructure([1.0, 2.0], [1.0, 1.0], 10.0, 0.0, 0.1),
     r"structure1.static_mass = 0.0 is not allowed: must be > 0 \(kg\)"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "axes": {"structure1": {"min": 0.0, "max": 1.0, "num": 2}}}),
     "structure1 is not sweepable"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "params": {"counterpart": "stop", "structure1": fe_structure()},
                                 "axes": {"l1": {"min": 0.05, "max": 0.1, "num": 2}}}),
     "structure1 is beam 1"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "params": {"counterpart": "stop", "structure1": fe_structure(),
                                            "shaker": "beam1"},
                                 "axes": {"base_amplitude": {"min": 0.0, "max": 1e-6,
                                                             "num": 2}}}),
     "structure1 has no influence vector"),
    (lambda: read_npz({"stiffness": K40, "mass": M40, "contact_dof": TIP, "length": 0.1,
                       "gyroscopic": K40}),
     "structure1 array 'gyroscopic' = .* is not allowed: MatrixStructure files hold"),
])
def test_bad_structures_are_refused_in_one_line(build, message):
    with pytest.raises(ParameterError, match=message) as error:
        build()
    assert "\n" not in str(error.value)


def test_a_shaken_fe_model_converges_to_the_shaken_beam():
    """Gamma_n = phi_n^T M r (r: the clamp's rigid motion, w = 1, slopes 0) against the closed
    forms, and the first two contacts of a shaker run (12 modes) against the closed-form
    beam's: the FE's errors fall 7.7 times or more per halving of the elements. Measured: Gamma_1
    4.6e-6 at 40 elements, 5.8e-7 at 80; onsets 1.6e-7 and 2.8e-6 s at 40, 5.4e-9 and
    1.8e-7 s at 80."""
    params = STOP.replace(shaker="beam1", base_amplitude=2e-6, force_amplitude=0.0, omega=300.0)
    uniform = beam(STOP, 1)
    expected = uniform.participation(uniform.free_modes(5).shapes)
    onsets = simulate(params, 0.05, n_modes=12).impact_onset_time.values
    assert onsets.size == 2
    gamma_errors, onset_errors = [], []
    for n in (40, 80):
        K, M = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, n)
        structure = MatrixStructure(M, K, contact_dof=tip_dof(n), length=STOP.l1,
                                    influence=np.tile([1.0, 0.0], n))
        gamma_errors.append(np.abs(structure.modes(5).participation() / expected - 1))
        run = simulate(params.replace(structure1=structure), 0.05, n_modes=12)
        onset_errors.append(np.abs(run.impact_onset_time.values - onsets))
    for coarse, fine in (gamma_errors, onset_errors):
        assert np.all(fine <= coarse / 7)
    assert gamma_errors[1].max() < 2e-4 and onset_errors[1].max() < 1e-6


@pytest.mark.slow
def test_two_beams_with_an_fe_beam_1_converge_to_the_fe_pair():
    """Beam 1 as the FE model (40 elements, all 80 modes) against the closed-form beam 2 (80
    modes), and the FE pair with beam 1's 40 elements and beam 2 refined: the first onset
    agrees to round-off (it precedes beam 2's say), the later ones converge as the FE beam 2
    does, h^4 (measured 2.0e-9 and 7.8e-9 s at 80 elements, 1.4e-10 and 4.4e-10 s at 160)."""
    pair = Params(contact_stiffness=1e4)
    ds = simulate(pair.replace(structure1=fe_structure()), 0.05, n_modes=2 * ELEMENTS)
    errors = [np.abs(ds.impact_onset_time.values[:3] - fe_spring_contacts(
        pair, 1e4, t_max=0.05, n_elements=(ELEMENTS, n), n_contacts=3, mode_rtol=1e-9)["onset"])
        for n in (80, 160)]
    assert errors[1][0] < 1e-12 and np.all(errors[1][1:] <= errors[0][1:] / 8)
    assert errors[1].max() < 1e-9


def test_what_needs_a_continuous_beam_refuses_a_user_structure():
    """Initial fields and the tied law's contact modes need a beam along x: one line each."""
    from impactbeams.contact import build_tied_model
    from impactbeams.trajectory.start import InitialFields

    params = STOP.replace(structure1=fe_structure())
    with pytest.raises(ParameterError, match=r"initial fields are projected on beams along x "
                                             r"\(uniform, stepped or with attachments\), not "
                                             "on a user structure"):
        simulate(params, 0.01, n_modes=12, initial_state=InitialFields(deflection1=lambda x: x))
    with pytest.raises(ParameterError, match="the tied law supports the paper's uniform beams "
                                             "only, not a beam with attachments or a user"):
        build_tied_model(params, 5)


def test_lyapunov_exponents_and_a_steady_start_take_a_matrix_structure():
    """The tangent flow and the steady start use only the free modes: with modal data of the
    textbook beam they give today's exponents and contacts, bit for bit."""
    today = STOP.replace(damping_ratio=0.01, start="steady", omega=200.0)
    given = today.replace(structure1=analytic_modal_data(12))
    runs = [simulate(p, 0.2, n_modes=12, lyapunov=True) for p in (today, given)]
    assert runs[0].impact.size > 0
    for name in ("impact_onset_time", "lyapunov_exponent"):
        np.testing.assert_array_equal(runs[1][name].values, runs[0][name].values)


def test_a_periodic_orbit_of_modal_data_is_todays_and_params_travel_pickled():
    """The period map uses only the free modes: today's orbit, bit for bit. A Params with a
    structure pickles (Dask's workers get it so) and keeps its data."""
    import pickle

    from impactbeams import periodic_orbit

    today = STOP.replace(damping_ratio=0.01, omega=200.0, force_amplitude=3e-3)
    given = today.replace(structure1=analytic_modal_data(12))
    orbits = [periodic_orbit(p, n_modes=12) for p in (today, given)]
    assert orbits[0].contacts >= 1
    np.testing.assert_array_equal(orbits[1].state, orbits[0].state)
    np.testing.assert_array_equal(orbits[1].multipliers, orbits[0].multipliers)
    copy = pickle.loads(pickle.dumps(STOP.replace(structure1=fe_structure())))
    assert repr(copy.structure1) == repr(fe_structure())
    np.testing.assert_array_equal(copy.structure1.modes(5).frequencies,
                                  fe_structure().modes(5).frequencies)


def test_the_modes_a_contact_needs_are_counted_on_the_structures_own_modes():
    """required_modes counts the modes softer at the contact than k on the structure's own
    modes: the FE model's count is the closed-form beam's; a default run takes it, within the
    modes the structure has."""
    from impactbeams.contact import recommended_modes, required_modes

    for k in (1e4, 1e6):
        today = STOP.replace(contact_stiffness=k)
        given = today.replace(structure1=fe_structure())
        assert required_modes(given) == required_modes(today)
    few = STOP.replace(contact_stiffness=1e6, structure1=analytic_modal_data(12))
    assert required_modes(few) > 12 and recommended_modes(few) == 12


def test_a_continuation_of_modal_data_is_todays():
    """Two beams, beam 1 as the textbook beam's modal data: today's branch, bit for bit."""
    from impactbeams import Continuation, continue_orbits

    today = Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5)
    uniform = beam(today, 1)
    modes = uniform.free_modes(3)
    given = today.replace(structure1=ModalStructure(
        modes.frequencies, modes.shapes.tip(), uniform.tip_compliance,
        33.0 / 140.0 * today.rhoA1 * today.l1, today.l1,
        participation=uniform.participation(modes.shapes)))
    branches = [continue_orbits(Continuation(p, "omega", 248.8, 250.5, start=248.9, n_modes=3,
                                             max_branches=2)) for p in (today, given)]
    assert branches[0].state.size > 0
    for name in ("state", "multiplier", "orbit_period", "omega"):
        np.testing.assert_array_equal(branches[1][name].values, branches[0][name].values)
