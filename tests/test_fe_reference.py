"""Self-checks of the finite-element reference model (tests/fe_reference.py) only.

These check the FE model against textbook beam results and against itself (mesh refinement,
direct time integration, energy), so that it can be trusted as an independent reference for
impactbeams. Nothing here imports impactbeams.
"""

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from fe_reference import (
    _eig,
    _free_phase,
    _Pair,
    _Phases,
    beam_flexibility,
    beam_matrices,
    cantilever_frequencies,
    contact_frequencies,
    first_impact_time,
    simulate_impacts,
    static_tip_shape,
    steel_strip,
    tip_dof,
)

EPS = np.finfo(float).eps
EI, RHOA = steel_strip()  # default steel strip, a = sqrt(EI / rhoA) = 0.7 m^2/s
L1, L2 = 0.1, 0.12
CLEARANCE, F0, OMEGA = 1.1e-5, 1e-3, 50.0
DEFAULT = (EI, RHOA, L1, EI, RHOA, L2, CLEARANCE, F0, OMEGA)

BETA_CANTILEVER = (1.8751040687, 4.6940911330, 7.8547574382)  # cos b cosh b + 1 = 0
BETA_CLAMPED_PINNED = (3.9266023120, 7.0685827500)  # tan b = tanh b


def cantilever_root(n: int) -> float:
    """n-th root (n >= 1) of cos b cosh b + 1 = 0, written as cos b + 1/cosh b = 0."""
    guess = (2 * n - 1) * np.pi / 2
    return brentq(lambda b: np.cos(b) + 1 / np.cosh(b), guess - 0.5, guess + 0.5, xtol=1e-15)


def omega_of(beta: float, length: float) -> float:
    return beta**2 / length**2 * np.sqrt(EI / RHOA)


def test_steel_strip_matches_a():
    assert np.sqrt(EI / RHOA) == pytest.approx(0.7, rel=1e-14)


@pytest.mark.parametrize("n_elements", [1, 2, 5, 20])
def test_static_tip_load_is_exact(n_elements):
    # Hermite cubics hold the exact cubic tip-load shape; what is left is the round-off of a
    # solve with K, whose condition number grows as n^4 (about 1e-13 at 20 elements).
    K, _ = beam_matrices(EI, RHOA, L1, n_elements)
    load = np.zeros(K.shape[0])
    load[tip_dof(n_elements)] = 1.0
    x = scipy.linalg.solve(K, load, assume_a="pos")
    nodes = L1 * np.arange(1, n_elements + 1) / n_elements
    w_exact = (3 * L1 * nodes**2 - nodes**3) / (6 * EI)
    slope_exact = (2 * L1 * nodes - nodes**2) / (2 * EI)
    assert x[tip_dof(n_elements)] == pytest.approx(L1**3 / (3 * EI), rel=1e-12)
    np.testing.assert_allclose(x[0::2], w_exact, rtol=1e-12, atol=1e-12 * w_exact[-1])
    np.testing.assert_allclose(x[1::2], slope_exact, rtol=1e-12, atol=1e-12 * slope_exact[-1])


@pytest.mark.parametrize("n_elements", [1, 3, 20])
def test_flexibility_is_inverse_stiffness(n_elements):
    K, _ = beam_matrices(EI, RHOA, L1, n_elements)
    F = beam_flexibility(EI, L1, n_elements)
    # Residual of a product with an ill-conditioned K: bounded by eps ||K|| ||F||.
    tol = 10 * EPS * np.linalg.norm(K, 2) * np.linalg.norm(F, 2)
    np.testing.assert_allclose(K @ F, np.eye(K.shape[0]), rtol=0, atol=tol)
    np.testing.assert_array_equal(F, F.T)


def test_flexibility_eigen_solution_matches_stiffness_form():
    # Coarse meshes, where eigh(K, M) is still accurate: same FE frequencies either way.
    K, M = beam_matrices(EI, RHOA, L1, 5)
    direct = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True))
    np.testing.assert_allclose(cantilever_frequencies(EI, RHOA, L1, 10, 5), direct, rtol=1e-11)


def test_tied_flexibility_inverts_constrained_stiffness():
    # The rank-one tied flexibility equals (T^T K T)^-1 of the constraint-matrix formulation.
    pair = _Pair.build(EI, RHOA, L1, 2 * EI, 0.5 * RHOA, L2, (4, 6))
    K_c = pair.T.T @ pair.K @ pair.T
    F_c = pair.tied_flexibility()
    tol = 10 * EPS * np.linalg.norm(K_c, 2) * np.linalg.norm(F_c, 2)
    np.testing.assert_allclose(K_c @ F_c, np.eye(K_c.shape[0]), rtol=0, atol=tol)


def test_textbook_constants():
    for n, beta in enumerate(BETA_CANTILEVER, start=1):
        assert cantilever_root(n) == pytest.approx(beta, abs=1e-10)
    for n, beta in enumerate(BETA_CLAMPED_PINNED, start=1):
        guess = (4 * n + 1) * np.pi / 4
        root = brentq(lambda b: np.tan(b) - np.tanh(b), guess - 0.3, guess + 0.3, xtol=1e-15)
        # The second printed constant is off in its last digits (root 7.068582745628...).
        assert root == pytest.approx(beta, abs=1e-8)


def test_cantilever_frequencies_converge_as_h4():
    exact = np.array([omega_of(cantilever_root(n), L1) for n in (1, 2, 3)])
    errors = np.array(
        [cantilever_frequencies(EI, RHOA, L1, 3, n) / exact - 1 for n in (10, 20, 40, 80)]
    )
    assert np.all(errors > 0)  # consistent mass: Rayleigh-Ritz bounds from above
    ratios = errors[:-1] / errors[1:]
    # Hermite cubics: frequency error C h^4, so halving h divides it by 16 (2^4); 10
    # elements are not quite asymptotic for mode 3 (ratio 15.55).
    np.testing.assert_allclose(ratios, 16.0, rtol=0.03)
    assert errors[2, 0] < 5e-9  # mode 1, 40 elements


def test_cantilever_frequencies_round_off_at_fine_meshes():
    # The flexibility-based eigen-solution keeps the h^4 trend down to ~1e-11 relative.
    exact = omega_of(cantilever_root(1), L1)
    e60, e120 = (cantilever_frequencies(EI, RHOA, L1, 1, n)[0] / exact - 1 for n in (60, 120))
    assert e60 / e120 == pytest.approx(16.0, rel=0.05)  # e120 = 4e-11


@pytest.mark.parametrize(
    ("length", "reference"),
    [(L1, (246.121, 1542.41, 4318.81)), (L2, (170.917, 1071.12, 2999.17))],
)
def test_reference_cantilever_frequencies(length, reference):
    # References are printed to 6 digits: FE (40 elements, error < 2e-6) must round to them.
    omega = cantilever_frequencies(EI, RHOA, length, 3, 40)
    assert_rounds_to(omega, reference)


def test_reference_contact_frequencies():
    omega = contact_frequencies(EI, RHOA, L1, EI, RHOA, L2, 5, 40, 40)
    assert_rounds_to(omega, (208.046, 844.946, 1364.32, 2669.69, 3909.25))


def assert_rounds_to(values, reference):
    for value, ref in zip(values, reference, strict=True):
        digits = len(f"{ref}".split(".")[1])
        assert abs(value - ref) <= 0.5 * 10.0**-digits, (value, ref)


def test_contact_frequencies_of_equal_beams():
    # Equal beams: symmetric contact modes are cantilever modes (no tie force), antisymmetric
    # ones have the tip pinned (clamped-pinned modes).
    n = 40
    contact = contact_frequencies(EI, RHOA, L1, EI, RHOA, L1, 5, n, n)
    cantilever = cantilever_frequencies(EI, RHOA, L1, 3, n)
    np.testing.assert_allclose(contact[[0, 2, 4]], cantilever, rtol=1e-10)
    # FE clamped-pinned beam: flexibility of the cantilever with its tip held (x_tip = 0).
    F = beam_flexibility(EI, L1, n)
    tip = tip_dof(n)
    pinned = np.delete(np.delete(F - np.outer(F[:, tip], F[tip]) / F[tip, tip], tip, 0), tip, 1)
    M = beam_matrices(EI, RHOA, L1, n)[1]
    clamped_pinned = _eig(pinned, np.delete(np.delete(M, tip, 0), tip, 1))[0][:2]
    np.testing.assert_allclose(contact[[1, 3]], clamped_pinned, rtol=1e-10)
    textbook = [omega_of(b, L1) for b in (*BETA_CANTILEVER, *BETA_CLAMPED_PINNED)]
    np.testing.assert_allclose(contact, sorted(textbook), rtol=2e-6)  # FE error at 40 elements


def test_tied_static_contact_force():
    # Static tied state: MODEL.md gives R = (F c1 - Delta) / (c1 + c2), c_i = l_i^3 / (3 EI_i),
    # so R = -Delta / (c1 + c2) without force (the tie pulls). Exact for Hermite cubics.
    pair = _Pair.build(EI, RHOA, L1, 2 * EI, RHOA, L2, (7, 9))
    free, gap = _free_phase(pair, CLEARANCE, 0.0, OMEGA)
    phases = _Phases.build(pair, free, gap, 0.0)
    force = phases.force(phases.contact, 0.0, phases.contact.static[None, :])[0]
    c1, c2 = L1**3 / (3 * EI), L2**3 / (3 * 2 * EI)
    assert force == pytest.approx(-CLEARANCE / (c1 + c2), rel=1e-9)


def test_first_impact_time_converges_with_mesh():
    t20, t40, t80 = (first_impact_time(*DEFAULT, n_elements=(n, n)) for n in (20, 40, 80))
    assert 0.009 < t40 < 0.0093
    # O(h^4) convergence: each halving gains at least a factor of ~10 (16 asymptotically).
    assert abs(t40 - t20) < 2e-7 * t40
    assert abs(t80 - t40) < abs(t40 - t20) / 10


@pytest.mark.parametrize(("n_elements", "rtol"), [(40, 2e-6), (160, 3e-7)])
def test_first_impact_time_matches_continuum_release(n_elements, rtol):
    # Beam 1 released from rest in its static tip-load shape (no force, beam 2 at rest): the
    # continuum tip is delta * sum_n 12 / beta_n^4 cos(omega_n t) (the sum of 12 / beta_n^4
    # is 1); impact when it reaches -clearance. The release excites every mode (amplitudes
    # ~ n^-4) and the FE phases of the high ones drift, so here t* converges only about as
    # h^2, with an erratic sign: measured 9e-7 relative at 40 elements, 1.5e-7 at 160.
    uplift = 2e-5
    betas = np.array([cantilever_root(n) for n in range(1, 11)])
    betas = np.concatenate([betas, (2 * np.arange(11, 3001) - 1) * np.pi / 2])  # exact to eps

    def gap(t):
        return CLEARANCE + uplift * np.sum(12 / betas**4 * np.cos(omega_of(betas, L1) * t))

    t_fe = first_impact_time(
        EI, RHOA, L1, EI, RHOA, L2, CLEARANCE, 0.0, OMEGA,
        uplift1=uplift, n_elements=(n_elements, n_elements),
    )  # fmt: skip
    t_exact = brentq(gap, 0.5 * t_fe, 1.01 * t_fe, xtol=1e-16)
    assert gap(0.5 * t_fe) > 0
    assert t_fe == pytest.approx(t_exact, rel=rtol)


def test_first_impact_time_none():
    tiny_force = (*DEFAULT[:7], 1e-5, OMEGA)
    assert np.isnan(first_impact_time(*tiny_force, t_max=0.2, n_elements=(10, 10)))


def test_simulation_first_onset_equals_first_impact_time():
    result = simulate_impacts(*DEFAULT, t_max=0.0095, n_elements=(20, 20))
    t_first = first_impact_time(*DEFAULT, n_elements=(20, 20))
    assert result["onset_times"][0] == pytest.approx(t_first, rel=1e-13)


def test_exact_propagation_against_direct_integration_at_resonance():
    # No impact (huge clearance), forcing exactly at beam 1's first FE frequency, both beams
    # uplifted: the closed-form modal solution must match a tight direct integration of
    # M x'' + K x = f of the same (small) FE model.
    n = 3
    omega = cantilever_frequencies(EI, RHOA, L1, 1, n)[0]
    t_out = np.linspace(0.0, 0.05, 201)
    result = simulate_impacts(
        EI, RHOA, L1, EI, RHOA, L2, 1.0, F0, omega,
        uplift1=1e-5, uplift2=-5e-6, t_max=0.05, t_out=t_out, n_elements=(n, n),
    )  # fmt: skip
    K = scipy.linalg.block_diag(*(beam_matrices(EI, RHOA, length, n)[0] for length in (L1, L2)))
    M = scipy.linalg.block_diag(*(beam_matrices(EI, RHOA, length, n)[1] for length in (L1, L2)))
    tip1, tip2 = tip_dof(n), 2 * n + tip_dof(n)
    x0 = np.concatenate(
        [static_tip_shape(beam_flexibility(EI, L1, n), 1e-5),
         static_tip_shape(beam_flexibility(EI, L2, n), -5e-6)]
    )  # fmt: skip

    def rhs(t, y):
        force = np.zeros(4 * n)
        force[tip1] = -F0 * np.sin(omega * t)
        return np.concatenate([y[4 * n :], np.linalg.solve(M, force - K @ y[: 4 * n])])

    direct = solve_ivp(
        rhs, (0.0, 0.05), np.concatenate([x0, np.zeros(4 * n)]), method="DOP853",
        t_eval=t_out, rtol=1e-12, atol=1e-20,
    )  # fmt: skip
    scale = np.abs(direct.y[tip1]).max()
    assert scale > 5e-5  # resonance has grown the response well past the uplift
    np.testing.assert_allclose(result["tip1"], direct.y[tip1], rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(result["tip2"], direct.y[tip2], rtol=0, atol=1e-8 * scale)
    assert result["onset_times"].size == 0


def test_unforced_impacts_only_lose_energy_at_onsets():
    t_out = np.linspace(0.0, 0.02, 8001)
    result = simulate_impacts(
        *DEFAULT[:7], 0.0, OMEGA, uplift1=2e-5, t_max=0.02, t_out=t_out, n_elements=(20, 20)
    )
    onsets, releases = result["onset_times"], result["release_times"]
    assert onsets.size > 5
    assert np.all(result["impact_gap_rates"] <= 0)
    assert np.all(releases >= onsets[: releases.size])
    assert np.all(onsets[1:] >= releases[: onsets.size - 1])
    energy = result["energy"]
    change = np.diff(energy) / energy[0]
    straddles_onset = np.zeros(change.size, dtype=bool)
    straddles_onset[np.searchsorted(t_out, onsets) - 1] = True
    # Between onsets the FE energy is conserved up to the round-off of the high modes'
    # frequencies (relative error ~ eps (omega_max / omega_1)^2, about 1e-8 here).
    assert np.abs(change[~straddles_onset]).max() < 1e-9
    assert np.all(change[straddles_onset] < 1e-9)
    assert energy[-1] < energy[0]
    assert result["gap"].min() > -1e-15
    assert result["contact_force"].min() >= 0.0
    assert np.all(result["contact_force"][~result["in_contact"]] == 0.0)
