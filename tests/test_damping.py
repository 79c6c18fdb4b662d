"""Modal damping acts on each mode's whole coordinate (docs/model.md, "Modal damping").

The package splits beam 1's deflection into the quasi-static shape and the modes; these tests
check it against formulations without that split: closed-form damped modal sums for the steady
state, and per-mode closed forms of the whole modal coordinates for first impacts.
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from impactbeams import Params, simulate
from impactbeams.kernels.first_impact import first_impact_cells
from impactbeams.model import build_free_phase
from impactbeams.packing import free_tables, geometry_row
from references import damped_modal_gap, reference_first_impact


def cantilever_wavenumbers(count: int) -> np.ndarray:
    """k_n l of a cantilever, roots of cos x + 1 / cosh x = 0 (one in each [(n-1) pi, n pi])."""
    def f(x):
        return np.cos(x) + 1.0 / np.cosh(x)

    return np.array([brentq(f, (n - 1) * np.pi, n * np.pi, xtol=1e-15, rtol=1e-15)
                     for n in range(1, count + 1)])


def tip_receptance(params: Params, forcing_frequency: float, zeta: float,
                   count: int = 20_000) -> complex:
    """Steady tip deflection of beam 1 per unit downward tip force, y = Im(H F0 e^(i Omega t)).

    Modal sum without a quasi-static split: mass-normalised cantilever modes have
    Y_n(l)^2 = 4 / (rhoA l); H = -sum_n Y_n(l)^2 / (w_n^2 - Omega^2 + 2 i zeta w_n Omega).
    The tail beyond ``count`` modes is below 1e-13 of the sum (terms fall like n^-4).
    """
    k_l = cantilever_wavenumbers(200)
    n = np.arange(201, count + 1)
    k_l = np.concatenate([k_l, (2 * n - 1) * np.pi / 2])  # exact to double beyond n ~ 20
    a = np.sqrt(params.EI1 / params.rhoA1)
    w = a * (k_l / params.l1) ** 2
    denominator = w**2 - forcing_frequency**2 + 2j * zeta * w * forcing_frequency
    return -np.sum(4.0 / (params.rhoA1 * params.l1) / denominator)


def test_wavenumbers_and_static_limit():
    """The independent reference itself: textbook roots and the static tip compliance."""
    assert cantilever_wavenumbers(3) == pytest.approx([1.8751040687, 4.6940911330,
                                                       7.8547574382], abs=1e-9)
    params = Params()
    static = tip_receptance(params, 0.0, 0.0, count=200_000)
    assert static.real == pytest.approx(-params.tip_compliance[0], rel=1e-12)


OMEGA_1, OMEGA_2 = build_free_phase(Params(), 2).beam1.frequencies


@pytest.mark.parametrize(("zeta", "forcing_frequency"), [
    (0.005, 100.0), (0.005, OMEGA_1), (0.05, 800.0), (0.05, OMEGA_2),
    (0.02, 0.5 * (OMEGA_1 + OMEGA_2)), (0.3, OMEGA_1), (0.3, 2500.0)])
def test_steady_state_equals_damped_modal_sum(zeta, forcing_frequency):
    """After the transient, simulate's tip response is the damped modal sum to 1e-6."""
    # a clearance the tips never close (the steady amplitude is at most F0 c1 / (2 zeta) =
    # 3.7 mm): the free phase alone (no contact law needed)
    params = Params(clearance=0.02, force_amplitude=1e-3, omega=forcing_frequency,
                    damping_ratio=zeta, contact_law="tied")
    # the slowest transient (beam 1's first mode) decays below 1e-10 of the response
    t_end = 23.0 / (zeta * OMEGA_1)
    period = 2 * np.pi / forcing_frequency
    times = t_end - period * np.linspace(0.0, 1.0, 17)[::-1]
    n_modes = 40 if zeta > 0.1 else 10  # see the truncation estimate below
    ds = simulate(params, t_end, n_modes=n_modes, times=times)
    h = tip_receptance(params, forcing_frequency, zeta)
    expected = np.imag(h * params.force_amplitude * np.exp(1j * forcing_frequency * times))
    amplitude = abs(h) * params.force_amplitude
    # The split model holds the modes beyond N at their static deflection: it misses their
    # damping force, sum_{n>N} Y_n^2 2 zeta Omega / w_n^3, which falls like N^-6 and grows
    # with zeta. Above resonance, where the response is small, this is 1.5e-4 of it at
    # N = 10 (zeta = 0.3, Omega = 2500 rad/s), ~5e-8 at N = 40, and below 3e-7 at N = 10 for
    # zeta <= 0.05 in these cases. The transient is below 1e-10: 1e-6 is the bound.
    np.testing.assert_allclose(ds.tip_deflection_1.values, expected, rtol=0,
                               atol=1e-6 * amplitude)


def damped_rows(seed, n):
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        uplift1 = rng.choice([0.0, 10 ** rng.uniform(-6.5, -5)])
        uplift2 = rng.choice([0.0, 10 ** rng.uniform(-6.5, -5.3)])
        rows.append([10 ** rng.uniform(-5.3, -4.5), 10 ** rng.uniform(-4.5, -3),
                     rng.uniform(1, 600), uplift1, uplift2, 10 ** rng.uniform(-2.5, -0.6)])
    return rows


def test_damped_first_impacts_against_whole_coordinate_closed_form():
    """A damped map with uplifts: classification and t* against the unsplit closed form."""
    free = build_free_phase(Params(), 5)
    c1 = Params().tip_compliance[0]
    rows = damped_rows(3, 60)
    rows += [[1.1e-5, 4e-4, 60.0, 0, 0, 0.02], [1.1e-5, 3e-5, free.frequencies[0], 0, 0, 0.01],
             [1.1e-5, 2e-4, 300.0, 3e-6, 0, 0.05], [1.1e-5, 3e-4, 50.0, 2e-6, 1e-6, 0.3]]
    cells = np.array([[*row, 0.0] for row in rows])
    got = np.empty(len(rows))
    first_impact_cells(cells, free_tables(free)[None], geometry_row(Params(), free)[None], 1.0,
                       got)
    hits = 0
    for row, t in zip(rows, got, strict=True):
        clearance, force, omega, uplift1, uplift2, zeta = row
        args = (free, c1, clearance, force, omega, zeta, uplift1, uplift2)
        ref = reference_first_impact(damped_modal_gap(*args), 1.0, free.frequencies.max(),
                                     scan=damped_modal_gap(*args, dtype=np.float64))
        assert np.isnan(ref) == np.isnan(t), (row, ref, t)
        if not np.isnan(ref):
            hits += 1
            # two formulations of one model, both exact: round-off of the gap (~1e-16 of
            # the clearance) over the closing speed; measured worst ~1e-14 relative
            assert abs(t - ref) <= 1e-12 * ref, (row, ref, t)
    assert 10 <= hits <= len(rows) - 10  # the sample has both outcomes


def test_undamped_drive_has_no_cosine_part():
    """With zeta = 0 the drive is a pure sine (undamped results are bitwise unchanged)."""
    from impactbeams.kernels.drive import mode_drives

    free = build_free_phase(Params(), 5)
    cell = np.array([1.1e-5, 1e-3, 50.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # layout.CELL_COLUMNS
    amplitudes = np.empty(free.frequencies.size, dtype=np.complex128)
    mode_drives(free.drive, np.zeros(free.frequencies.size), free.frequencies,
                np.zeros(free.frequencies.size), cell, amplitudes)
    assert np.all(amplitudes.imag == 0.0)
    np.testing.assert_array_equal(amplitudes.real, -50.0**2 * 1e-3 * free.drive)
