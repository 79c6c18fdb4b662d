"""The peak contact force's certified search (kernels/peaks.py) against dense sampling.

The contact phase of the default Hertz spring at 32 modes per beam (zeta = 0: nothing decays),
started in its steady state plus a slow hump (the slowest contact mode) and a ring of a fast
mode: R has dozens of local maxima near the hump's top, within the ring's amplitude of each
other, over a 35 ms contact. The reference is written here in NumPy (closed-form modes,
steady state plus free transient), sampled 64 times per ring period, and every sampled local
maximum near the top is refined by Brent's method.
"""

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from impactbeams import Params
from impactbeams.kernels.layout import (
    CONTACT,
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
)
from impactbeams.kernels.peaks import peak_force
from impactbeams.orbits import PeriodMap

EPS = np.finfo(float).eps
T_START, DURATION = 0.0123, 0.035  # s
HUMP, RING = 2e-3, 3e-5  # N: the slow mode's and the fast mode's share of R
RING_FREQUENCY = 1e5  # rad/s: the ringing mode is the first contact mode above it


class ContactForce:
    """R(t) of a contact phase in closed form: steady states plus free (damped) transients."""

    def __init__(self, packed, q_s, v_s, t_s):
        table, self.scalars = packed.tables[CONTACT], packed.phase_scalars[CONTACT]
        self.omega = packed.params.omega
        self.w, zeta = table[ROW_FREQUENCY], table[ROW_ZETA]
        self.weights = table[ROW_EVENT]
        self.sigma = zeta * self.w
        self.wd = self.w * np.sqrt(1.0 - zeta**2)
        self.steady = packed.forces[CONTACT] / (
            self.w**2 - self.omega**2 + 2j * zeta * self.w * self.omega)
        steady_q, steady_v = self.steady_state(t_s)
        self.q0, self.v0, self.t_s = q_s - steady_q, v_s - steady_v, t_s

    def steady_state(self, t):
        phasor = self.steady * np.exp(1j * self.omega * np.asarray(t))[..., None]
        return phasor.imag, self.omega * phasor.real

    def terms(self, t):
        """The terms summed into R at times ``t``: (times, modes + 3)."""
        t = np.atleast_1d(t)
        tau = (t - self.t_s)[:, None]
        decay = np.exp(-self.sigma * tau)
        transient = decay * (self.q0 * np.cos(self.wd * tau)
                             + (self.v0 + self.sigma * self.q0) / self.wd * np.sin(self.wd * tau))
        steady_q, _ = self.steady_state(t)
        s = self.scalars
        return np.column_stack([np.full(t.size, s[SCALAR_CONST]),
                                s[SCALAR_SINE] * np.sin(self.omega * t),
                                s[SCALAR_COSINE] * np.cos(self.omega * t),
                                (transient + steady_q) * self.weights])

    def __call__(self, t):
        return self.terms(t).sum(axis=1)


@pytest.fixture(scope="module")
def ringing_contact():
    """The contact phase's arrays and a start state with a slow hump and a fast ring."""
    packed = PeriodMap(Params(), n_modes=32).packed
    reference = ContactForce(packed, 0.0, 0.0, T_START)
    q_s, v_s = reference.steady_state(T_START)
    w, weights = reference.w, reference.weights
    ring = int(np.argmax(w > RING_FREQUENCY))
    # a sine of the slowest mode (its top a quarter period, 7.5 ms, in) and one of the ring's
    v_s[0] += HUMP / abs(weights[0]) * w[0]
    v_s[ring] += RING / abs(weights[ring]) * w[ring]
    return packed, q_s, v_s, ContactForce(packed, q_s, v_s, T_START), w[ring]


def reference_peak(force, ring_frequency):
    """Max of R over the contact: 64 samples per ring period, sampled maxima near the top
    (within twice the sampling's worst miss, max|R''| h^2 / 8) refined by Brent's method."""
    spacing = 2.0 * np.pi / ring_frequency / 64
    t = np.linspace(T_START, T_START + DURATION, int(DURATION / spacing) + 1)
    values = force(t)
    h = t[1] - t[0]
    miss = (HUMP * force.w[0] ** 2 + RING * ring_frequency**2) * h * h / 8
    interior = (values[1:-1] >= values[:-2]) & (values[1:-1] >= values[2:])
    candidates = 1 + np.flatnonzero(interior & (values[1:-1] >= values.max() - 2.0 * miss))
    best = (values.max(), t[np.argmax(values)])
    for i in candidates:
        result = minimize_scalar(lambda x: -force(x)[0], bounds=(t[i - 1], t[i + 1]),
                                 method="bounded", options={"xatol": 1e-15})
        best = max(best, (-result.fun, result.x))
    return best, values, candidates.size


def test_peak_force_of_a_ringing_contact_against_dense_sampling(ringing_contact):
    packed, q_s, v_s, force, ring_frequency = ringing_contact
    (value, time), values, candidates = reference_peak(force, ring_frequency)
    top = (values[1:-1] >= values[:-2]) & (values[1:-1] >= values[2:]) & (
        values[1:-1] >= values.max() - 2.0 * RING)
    assert np.count_nonzero(top) >= 10  # dozens of local maxima compete for the peak
    assert candidates >= 2
    found, found_time = peak_force(packed.tables[CONTACT], packed.forces[CONTACT],
                                   packed.phase_scalars[CONTACT], packed.settings, q_s, v_s,
                                   T_START, T_START + DURATION)
    # both are R's maximum to within its own rounding: R (~2 mN) is a sum of terms of up to
    # `scale` (tens of N) that cancel, each side rounds to a few eps of it
    scale = np.abs(force.terms(time)).sum()
    assert abs(found - value) <= 16 * EPS * scale
    # the same local maximum: a ring period is 63 us, and R within 16 eps scale of its top
    # lies within sqrt(32 eps scale / (RING w^2)) ~ 1e-10 s of it
    assert abs(found_time - time) < 1e-9


def test_peak_force_of_an_instant_contact_is_the_force_there(ringing_contact):
    packed, q_s, v_s, force, _ = ringing_contact
    found, found_time = peak_force(packed.tables[CONTACT], packed.forces[CONTACT],
                                   packed.phase_scalars[CONTACT], packed.settings, q_s, v_s,
                                   T_START, T_START)
    assert found_time == T_START
    assert found == pytest.approx(force(T_START)[0], abs=16 * EPS * np.abs(
        force.terms(T_START)).sum())
