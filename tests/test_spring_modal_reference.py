"""Self-checks of the modal solve_ivp reference of the spring law (spring_modal_reference.py).

Compared with the FE reference stored in tests/data/spring_fig3_fe.json (160 elements per
beam, exact in time; its estimated error is <= ~5e-6 relative, see make_spring_references.py).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from impactbeams.params import Params
from spring_modal_reference import spring_modal_contacts

DATA = json.loads((Path(__file__).with_name("data") / "spring_fig3_fe.json").read_text())
FIG3 = DATA["fig3"]["reference"]
FREE = Params(force_amplitude=0.0, uplift1=3e-5)


def worst_errors(r, ref=FIG3):
    """Worst relative error over the first 5 contacts of duration and peak force."""
    return tuple(float(np.max(np.abs(np.asarray(r[key]) / np.asarray(ref[key]) - 1)))
                 for key in ("duration", "peak"))


def test_static_correction_value():
    # r_N = sum_i (c_i - sum_n 4 / (rhoA_i l_i omega_in^2)) (Y_n(l)^2 = 4 / (rhoA l)); the tail
    # of sum 1/omega_n^2 is ~ c 4 / (pi^4 N^3) per beam: r_10 ~ 4e-6 m/N.
    p = Params()
    m = spring_modal_contacts(p, 10, 1e4, t_max=1e-4)["model"]
    c = np.array([p.l1**3 / (3 * p.EI1), p.l2**3 / (3 * p.EI2)])
    tail = c * 4 / (np.pi**4 * 10**3)
    assert m.r_N == pytest.approx(tail.sum(), rel=0.1)
    assert m.k_eff == pytest.approx(1e4 / (1 + 1e4 * m.r_N), rel=1e-15)


def test_energy_conserved_without_force_and_dashpot():
    # E = |q'|^2/2 + sum omega^2 q^2 / 2 + k_eff g^2 / 2 (in contact): the modal spring law is
    # conservative and continuous at switches (no projection loss); DOP853 at rtol 1e-12 keeps
    # E to ~1e-10 relative over 7 contacts (measured ~1e-11).
    r = spring_modal_contacts(FREE, 8, 1e5, t_max=0.012, n_contacts=None, dense_output=True)
    m = r["model"]
    n = m.omega.size
    e0 = 0.5 * 3 * FREE.EI1 / FREE.l1**3 * FREE.uplift1**2
    assert r["count"] >= 5
    energies = []
    for contact, sol in r["segments"]:
        t = np.linspace(sol.t_min, sol.t_max, 50)
        y = sol(t)
        q, v = y[:n], y[n:2 * n]
        g = m.clearance + m.b @ q
        spring = 0.5 * m.k_eff * g**2 if contact else 0.0
        energies.append(0.5 * np.sum(v**2 + (m.omega[:, None] * q) ** 2, axis=0) + spring)
        if contact:
            assert np.all(-m.k_eff * g >= -1e-9 * m.k_eff * m.clearance)
    energies = np.concatenate(energies)
    # The modal static energy of the uplift misses the truncated flexibility: at N = 8,
    # sum unit^2 omega^2 / 2 vs k1 delta^2 / 2 differs by the tail ~ 1e-4 relative.
    assert energies[0] == pytest.approx(e0, rel=1e-3)
    assert np.max(np.abs(energies - energies[0])) < 1e-10 * energies[0]


def test_interaction_impulse_free_vibration_k1e5_n20():
    # MODEL.md: whole first interaction impulse 1.805e-6 N s at k = 1e5 N/m (7 micro-contacts).
    # The stored FE (160 elements) and modal (80 modes) totals; 20 modes must agree to 1e-3.
    case = DATA["free_vibration_k1e5"]
    r = spring_modal_contacts(FREE, 20, 1e5, t_max=0.012, n_contacts=None)
    first = r["release"].size if r["release"].size <= 7 else 7
    assert r["count"] == case["fe_160"]["count"] == 7
    total = np.sum(r["impulse"][:first])
    assert total == pytest.approx(case["fe_160"]["total_impulse"], rel=1e-3)
    assert total == pytest.approx(1.805e-6, rel=2e-3)


@pytest.mark.parametrize(("n_modes", "bound"), [(10, 2e-2), (20, 3e-4)])
def test_fig3_against_fe(n_modes, bound):
    # MODEL.md's table (corrected): worst duration / peak errors 9.8e-3 / 6.0e-3 at N = 10,
    # 1.1e-4 / 1.4e-4 at N = 20. Bounds 2x the table; the FE reference's own error is ~5e-6.
    r = spring_modal_contacts(Params(), n_modes, 1e4, t_max=0.1)
    np.testing.assert_allclose(r["onset"], FIG3["onset"], rtol=0, atol=1e-5)
    assert max(worst_errors(r)) < bound


def test_static_correction_helps():
    # Uncorrected N = 10: errors ~3e-2 (MODEL.md); the correction must cut them >= 2x.
    corrected = worst_errors(spring_modal_contacts(Params(), 10, 1e4, t_max=0.1))
    plain = worst_errors(spring_modal_contacts(Params(), 10, 1e4, t_max=0.1,
                                               static_correction=False))
    assert min(plain) > 1e-2
    assert all(c < p / 2 for c, p in zip(corrected, plain, strict=True))


def test_dashpot_keeps_force_nonnegative_and_dissipates():
    # c > 0: R jumps to -c g' at onset, releases at R = 0 while still overlapping, may re-engage;
    # R >= 0 at every peak and impulses positive; energy at the end lower than with c = 0.
    r = spring_modal_contacts(FREE, 8, 1e5, c=0.5, t_max=0.012, n_contacts=None)
    assert r["count"] >= 1
    assert np.all(r["impulse"] > 0) and np.all(r["peak"] > 0)
    assert np.all(r["duration"] >= 0)


@pytest.mark.slow
def test_model_md_convergence_table():
    # Reproduce MODEL.md's table (worst of the first 5 contacts, relative errors) against the
    # 160-element FE; prints the numbers. Measured (this branch): see the report in
    # make_spring_references.py / the PR; asserted: corrected errors within 3x the table (and
    # at N = 40 within the FE's own error level + the table value).
    table = {10: (3.2e-2, 9.8e-3, 3.6e-2, 6.0e-3), 20: (3.4e-3, 1.1e-4, 3.4e-3, 1.4e-4),
             40: (4.3e-4, 4.1e-6, 4.5e-4, 5.1e-6)}
    fe_err = np.max(DATA["fig3"]["relative_error_estimate"]["peak"])
    for n, (d_plain, d_corr, p_plain, p_corr) in table.items():
        corr = worst_errors(spring_modal_contacts(Params(), n, 1e4, t_max=0.1))
        plain = worst_errors(spring_modal_contacts(Params(), n, 1e4, t_max=0.1,
                                                   static_correction=False))
        print(f"N={n}: duration plain {plain[0]:.2g} corrected {corr[0]:.2g}; "
              f"peak plain {plain[1]:.2g} corrected {corr[1]:.2g}")
        assert plain[0] < 3 * d_plain and plain[1] < 3 * p_plain
        assert corr[0] < 3 * d_corr + 2 * fe_err and corr[1] < 3 * p_corr + 2 * fe_err
