"""Lyapunov exponents of several contacts (issue 33, item 5) against what is known apart.

The tangents of a run of several contacts are carried through each active set's phase and
the saltation at every switch (`impactbeams.kernels.contacts_tangent`), renormalised every
forcing period as one contact's. Checked against: the single contact's exponents beside a
contact that never closes; the Floquet multipliers of the periodic orbit the run is on
(themselves checked against the finite differences' monodromy in
`tests/test_orbits_several.py`); the phase-space contraction of modal damping, which the
springs leave alone; and `simulate` for a sweep's cell. The runs are
`tests/test_orbits_several.py`'s (8 modes, k = 1e4 N/m, zeta = 0.05, stable period-1 orbits).
"""

import math

import numpy as np
import pytest

from impactbeams import Contact, ParameterError, simulate
from impactbeams.modes import beam
from impactbeams.orbits import periodic_orbit
from impactbeams.sweep import run_sweep, sweep_from_mapping
from test_orbits_several import FORCED, MID, N_MODES, RUNS, STOP

PERIOD = 2 * math.pi / FORCED.omega  # s
TRANSIENT = 10  # forcing periods left out of the averages
AVERAGED = 30


def exponents(params, count, transient=TRANSIENT, periods=AVERAGED, **options):
    """simulate's spectrum of ``count`` exponents over transient + periods forcing periods."""
    dataset = simulate(params, (transient + periods) * PERIOD, N_MODES, dt_output=PERIOD,
                       lyapunov=count, transient_periods=transient, **options)
    return dataset.lyapunov_spectrum.values if count > 1 else dataset.lyapunov_exponent.values


@pytest.mark.parametrize("damping", [0.0, 0.5])
def test_beside_a_contact_that_never_closes_the_exponents_are_the_single_contacts(damping):
    """A tip stop (with or without a dashpot: the saltation at each closing) beside a mid-span
    one 1 mm away, which never closes: the six leading exponents of the single contact's run,
    to round-off (the set phases' complex modes against the free table's real ones; measured
    1.2e-13 of the largest without a dashpot)."""
    single = FORCED.replace(clearance=2e-6, contact_damping=damping)
    two = single.replace(contacts=(Contact(clearance=2e-6, damping=damping),
                                   Contact(MID, clearance=1e-3)))
    with pytest.warns(RuntimeWarning, match="does not resolve"):  # one contact's own advice
        one = simulate(single, 40 * PERIOD, N_MODES, dt_output=PERIOD, lyapunov=6,
                       transient_periods=TRANSIENT)
    several = simulate(two, 40 * PERIOD, N_MODES, dt_output=PERIOD, lyapunov=6,
                       transient_periods=TRANSIENT)
    assert several.impact_contact.size >= 20 and np.all(several.impact_contact.values == 0)
    reference = one.lyapunov_spectrum.values
    assert np.abs(several.lyapunov_spectrum.values - reference).max() < (
        1e-12 * np.abs(reference).max())
    assert (several.lyapunov_spectrum.attrs["averaged_periods"]
            == one.lyapunov_spectrum.attrs["averaged_periods"] == 30)


@pytest.fixture(scope="module")
def orbits():
    return {name: periodic_orbit(params, N_MODES, method="newton")
            for name, params in RUNS.items()}


@pytest.mark.parametrize("name", list(RUNS))
def test_leading_pair_grows_as_the_orbits_largest_multiplier(orbits, name):
    """From the orbit's section state the run stays on it. Its leading multipliers are a
    complex pair, mu and its conjugate: the plane they span grows by |mu|^2 a period, so the
    mean of the two leading exponents is ln|mu_1| / T (one alone oscillates about it, 2-4 1/s
    apart over 30 periods). The tangents start off that plane; after the transient their
    misalignment is of order (|mu_3| / |mu_1|)^10 (1.4e-6 two-sided, 1.8e-7 together, 5.8e-9
    with dashpots), and what it leaves in the summed log growth over the 30 averaged periods
    is bounded by ten times that (measured 2.2e-6, 1.7e-8, 3.8e-10)."""
    orbit = orbits[name]
    mu = np.abs(orbit.multipliers)
    assert mu[0] == pytest.approx(mu[1], rel=1e-12) and orbit.multipliers[0].imag != 0
    pair = exponents(RUNS[name], 2, initial_state=orbit.state)
    expected = math.log(mu[0]) / PERIOD
    misalignment = (mu[2] / mu[0]) ** TRANSIENT
    assert abs(pair.mean() - expected) * AVERAGED * PERIOD < 10 * misalignment
    assert expected < -5.0  # a stable orbit: a test that an unchanged tangent fails


@pytest.mark.parametrize("name", ["two-sided", "together"])
def test_the_whole_spectrum_sums_to_the_modal_damping_trace(orbits, name):
    """Without a dashpot the springs change the stiffness only: every phase's flow has the
    trace -sum 2 zeta omega_n of the free modes, and every switch's saltation is the identity,
    so the 2 N exponents sum to it exactly (their product is the flow's determinant, whatever
    the inner product). Round-off: Gram-Schmidt of 16 directions whose growth over a period
    spans e^-31 (the fastest mode's decay, 2 zeta omega_8 T) loses the smallest ones' last
    digits (measured 5e-9 two-sided, 4e-16 together): within 1e-7."""
    frequencies = beam(RUNS[name].each_contact()[0], 1).free_modes(N_MODES).frequencies
    trace = -2.0 * STOP.damping_ratio * float(np.sum(frequencies))
    spectrum = exponents(RUNS[name], 2 * N_MODES, initial_state=orbits[name].state)
    assert spectrum.sum() == pytest.approx(trace, rel=1e-7)


def test_a_sweeps_exponent_is_simulates():
    """A sweep's cell of several contacts runs as `simulate` runs (the same recorded run and
    tangents; the batches summed in another order): 1e-12."""
    period = 2 * math.pi / 420.0
    sweep = sweep_from_mapping({
        "t_max": 40 * period, "n_modes": N_MODES, "transient_periods": TRANSIENT,
        "observables": ["lyapunov_exponent", "impact_count"],
        "params": {"counterpart": "stop", "contact_stiffness": 1e4, "damping_ratio": 0.05,
                   "force_amplitude": 1e-3,
                   "contacts": [{"position1": MID, "clearance": 1e-6, "damping": 0.5},
                                {"clearance": 2e-6}]},
        "axes": {"omega": {"min": 400.0, "max": 420.0, "num": 2}}})
    with pytest.warns(RuntimeWarning, match="does not resolve"):
        maps = run_sweep(sweep)
    assert np.all(maps.dynamics_status == 0) and np.all(maps.impact_count > 10)
    dataset = simulate(sweep.params_at({"omega": 420.0}), 40 * period, N_MODES,
                       dt_output=period, lyapunov=True, transient_periods=TRANSIENT)
    assert float(maps.lyapunov_exponent[1]) == pytest.approx(float(dataset.lyapunov_exponent),
                                                             rel=1e-12)
    assert float(dataset.lyapunov_exponent) < 0


def test_undefined_requests_are_refused_as_for_one_contact():
    """The same one-line checks as one contact's: the count against 2 N (a stop: one beam)."""
    with pytest.raises(ParameterError, match=r"lyapunov.*from 1 to 16"):
        simulate(RUNS["together"], 20 * PERIOD, N_MODES, lyapunov=17, transient_periods=1)
    with pytest.raises(ParameterError, match="transient_periods"):
        simulate(RUNS["together"], 5 * PERIOD, N_MODES, lyapunov=True, transient_periods=5)
