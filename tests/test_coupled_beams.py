"""Self-checks of tests/coupled_beams.py (exact frequencies of tip-spring-coupled cantilevers).

Nothing here imports impactbeams' kernels; Params only supplies the default beam values.
"""

import numpy as np
import pytest

from coupled_beams import (
    cantilever_frequencies,
    characteristic,
    coupled_frequencies,
    tip_receptance,
)
from fe_spring import spring_frequencies
from impactbeams.params import Params

P = Params()
TIP_STIFFNESS1 = 3 * P.EI1 / P.l1**3  # beam 1's static tip stiffness, ~27 N/m
# MODEL.md reference numbers (quoted to 6 significant digits there: rel. tolerance 5e-6).
BEAM1 = (246.121, 1542.41, 4318.81)
BEAM2 = (170.917, 1071.12, 2999.17)
TIED = (208.046, 844.946, 1364.32, 2669.69, 3909.25)


def test_receptance_static_limit_and_series_switch():
    c1 = P.l1**3 / (3 * P.EI1)
    omega1 = cantilever_frequencies(P.EI1, P.rhoA1, P.l1, 1)[0]
    assert tip_receptance(P.EI1, P.rhoA1, P.l1, 0.0) == pytest.approx(c1, rel=1e-15)
    # alpha = sum_n Y_n(l)^2 / (omega_n^2 - omega^2) -> c (1 + omega^2 sum(...)/c): the first
    # correction is omega^2 * (sum Y^4/omega^4) ~ (omega/omega_1)^2 * 0.97 c at the lowest order.
    small = tip_receptance(P.EI1, P.rhoA1, P.l1, 1e-3 * omega1)
    assert small == pytest.approx(c1, rel=2e-6) and small > c1
    # The Taylor branch (kl < 1) and the closed form (kl >= 1) must agree where they meet.
    k_switch = 1.0 / P.l1
    w_switch = k_switch**2 * np.sqrt(P.EI1 / P.rhoA1)
    below, above = tip_receptance(P.EI1, P.rhoA1, P.l1, w_switch * np.array([1 - 1e-12,
                                                                               1 + 1e-12]))
    assert below == pytest.approx(above, rel=1e-13)


def test_receptance_is_a_sum_of_modal_partial_fractions():
    # Independent of the closed form: mass-normalised cantilever modes have Y_n(l)^2 = 4 / (rhoA
    # l); alpha(omega) = sum_n 4 / (rhoA l (omega_n^2 - omega^2)). 2000 modes leave a tail of
    # sum_{n>N} 4 / (rhoA l omega_n^2) ~ 4 c / (pi^4 N^3) = 5e-12 c (absolute, as alpha may be
    # near a zero); omega away from the poles.
    w_n = cantilever_frequencies(P.EI1, P.rhoA1, P.l1, 2000)
    omega = np.array([100.0, 1000.0, 3000.0, 10000.0])
    series = np.sum(4 / (P.rhoA1 * P.l1 * (w_n[None, :] ** 2 - omega[:, None] ** 2)), axis=1)
    c1 = P.l1**3 / (3 * P.EI1)
    np.testing.assert_allclose(tip_receptance(P.EI1, P.rhoA1, P.l1, omega), series, rtol=1e-12,
                               atol=1e-11 * c1)


def test_cantilever_frequencies_match_model_md():
    np.testing.assert_allclose(cantilever_frequencies(P.EI1, P.rhoA1, P.l1, 3), BEAM1, rtol=5e-6)
    np.testing.assert_allclose(cantilever_frequencies(P.EI2, P.rhoA2, P.l2, 3), BEAM2, rtol=5e-6)


def test_weak_spring_gives_the_union_of_cantilever_frequencies():
    # Root shift ~ k / (modal tip stiffness omega_n^2 rhoA l / 4) relative: k = 1e-12 * 27 N/m
    # moves every root by < 1e-12 relative.
    got = coupled_frequencies(P, 1e-12 * TIP_STIFFNESS1, 6)
    np.testing.assert_allclose(got, np.sort(BEAM1 + BEAM2), rtol=5e-6)
    exact = np.sort(np.concatenate([cantilever_frequencies(P.EI1, P.rhoA1, P.l1, 3),
                                    cantilever_frequencies(P.EI2, P.rhoA2, P.l2, 3)]))
    np.testing.assert_allclose(got, exact, rtol=1e-11)
    # Weak spring raises each frequency (a stiffer system): roots lie just above the poles.
    assert np.all(got >= exact)


def test_stiff_spring_approaches_the_tied_frequencies():
    tied = coupled_frequencies(P, np.inf, 5)
    np.testing.assert_allclose(tied, TIED, rtol=5e-6)
    # The tied law (k = inf) is the limit; a finite spring softens the system, by O(1/k).
    previous = None
    for ratio in (1e4, 1e6, 1e8, 1e10):
        got = coupled_frequencies(P, ratio * TIP_STIFFNESS1, 5)
        err = (tied - got) / tied
        assert np.all(err > -1e-14)
        if previous is not None:  # 1/k convergence: 100 x stiffer, ~100 x closer
            assert np.all(err < previous / 50 + 1e-13)
        previous = err
    assert np.max(previous) < 1e-8


def test_characteristic_changes_sign_once_between_poles():
    # Dense scan of P between consecutive poles (union of both spectra) at k = 1e4 N/m.
    poles = np.sort(np.concatenate([cantilever_frequencies(P.EI1, P.rhoA1, P.l1, 4),
                                    cantilever_frequencies(P.EI2, P.rhoA2, P.l2, 4)]))
    roots = coupled_frequencies(P, 1e4, 7)
    for j, (lo, hi) in enumerate(zip(poles[:-1], poles[1:], strict=True)):
        w = np.linspace(lo, hi, 401)[1:-1]
        values = np.array([characteristic(P, 1e4, x) for x in w])
        assert np.count_nonzero(np.diff(np.sign(values))) == 1
        assert lo < roots[j] < hi


@pytest.mark.parametrize("k", [1e3, 1e5, np.inf])
def test_equal_beams_share_poles(k):
    # Equal beams: every cantilever frequency is a coupled frequency (in-phase motion, the spring
    # unstretched); the others are the antisymmetric modes, which for k = inf are the
    # clamped-pinned frequencies a (beta / l)^2, tan beta = tanh beta.
    q = P.replace(l2=P.l1)
    got = coupled_frequencies(q, k, 6)
    cant = cantilever_frequencies(q.EI1, q.rhoA1, q.l1, 3)
    np.testing.assert_array_equal(got[0::2], cant)
    assert np.all(got[1::2] > cant) and np.all(got[1::2][:-1] < cant[1:])
    if np.isinf(k):
        beta = np.array([3.9266023120479, 7.0685827456558, 10.210176122813])
        np.testing.assert_allclose(got[1::2], np.sqrt(q.EI1 / q.rhoA1) * (beta / q.l1) ** 2,
                                   rtol=1e-11)
    else:  # antisymmetric mode of equal beams: 1/(2 k) + alpha = 0, i.e. spring 2k to ground
        for w in got[1::2]:
            assert 1 / (2 * k) + tip_receptance(q.EI1, q.rhoA1, q.l1, w) == pytest.approx(
                0.0, abs=1e-9 * q.l1**3 / (3 * q.EI1))


def test_nearly_equal_beams_resolve_both_roots():
    # Poles 1e-9 apart (relative): the root between them must be found, strictly inside.
    q = P.replace(l2=P.l1 * (1 + 5e-10))
    got = coupled_frequencies(q, 1e4, 6)
    poles = np.sort(np.concatenate([cantilever_frequencies(q.EI1, q.rhoA1, q.l1, 3),
                                    cantilever_frequencies(q.EI2, q.rhoA2, q.l2, 3)]))
    assert np.all(got[0::2] >= poles[0::2]) and np.all(got[0::2] <= poles[1::2])
    assert np.all(np.diff(got) > 0)


@pytest.mark.parametrize("ratio", [1e-2, 1.0, 1e2, 1e4, 1e6])
def test_fe_eigenvalues_agree_within_their_mesh_error(ratio):
    # FE (Hermite cubics, tip spring in the stiffness) converges as h^4 from above (Rayleigh-
    # Ritz with consistent mass): the Richardson estimate (f_20 - f_40) / 15 of the error of
    # f_40 must match the true error (f_40 - exact) to within 5 % (measured: 0.1-1.6 %), for
    # the first 8 frequencies (errors 4e-9 .. 9e-6 relative at 40 elements).
    k = ratio * TIP_STIFFNESS1
    exact = coupled_frequencies(P, k, 8)
    f20 = spring_frequencies(P, k, 8, (20, 20))
    f40 = spring_frequencies(P, k, 8, (40, 40))
    estimate = (f20 - f40) / 15
    err = f40 - exact
    assert np.all(err > 0)
    np.testing.assert_allclose(err, estimate, rtol=0.05, atol=1e-13 * exact[-1])
