"""Independent references for a contact at any point along the beams (tests only).

Numpy and SciPy only, never impactbeams. Cantilever modes from the textbook formula in extended
precision (long double), the static Green's function in closed form, and the modal equations of
the compliant contact integrated by SciPy's DOP853 with the gap's zero as an event.

Model (docs/model.md, "Where the contact acts"): beam i's whole modal coordinates eta_n (its
cantilever modes Y_n, mass-normalised), the tip force F(t) = F0 sin(Omega t) downward on beam 1,
the contact at x1 on beam 1 and x2 on beam 2 (or a rigid stop), from side s (+1: the counterpart
below beam 1). With N modes per beam the deflection at a point is the mode-acceleration form
``y1(x) = -R_N(x, l1) F + sum_n Y_n(x) eta_n``,
``R_N(x, l) = G(x, l) - sum_n Y_n(x) Y_n(l) / omega_n^2``, the gap
``g = clearance + s (y1(x1) - y2(x2))``, and the contact force ``R = -k_e g`` while g < 0
(no dashpot), k_e = k / (1 + k r), r = sum_i R_N,i(x_i, x_i):

    eta_n'' + omega_n^2 eta_n = -Y_n(l1) F(t) [beam 1's modes] + w_n R,
    w_n = s Y_1n(x1) on beam 1's modes, -s Y_2n(x2) on beam 2's.

Units: SI (m, s, N, kg, rad/s).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


def cantilever_roots(n: int) -> np.ndarray:
    """b_n of cos b cosh b + 1 = 0, by brentq on cos b + 1 / cosh b in [(n - 1) pi, n pi]."""
    f = lambda b: math.cos(b) + 1.0 / math.cosh(b)  # noqa: E731
    return np.array([brentq(f, max(j - 1, 0.3) * math.pi, j * math.pi, xtol=1e-15, rtol=1e-15)
                     for j in range(1, n + 1)])


@dataclasses.dataclass(frozen=True)
class Beam:
    """A uniform cantilever (EI N m^2, rhoA kg/m, length m) and its first ``n`` modes."""

    EI: float
    rhoA: float
    length: float
    n: int

    @functools.cached_property
    def roots(self) -> np.ndarray:
        return cantilever_roots(self.n)

    @functools.cached_property
    def frequencies(self) -> np.ndarray:
        """omega_n = b_n^2 sqrt(EI / rhoA) / l^2 (rad/s)."""
        return self.roots**2 * math.sqrt(self.EI / self.rhoA) / self.length**2

    def shapes(self, x: float) -> np.ndarray:
        """Y_n(x), mass-normalised (int rhoA Y^2 = 1), tip value positive (kg^-1/2).

        phi = cosh bx - cos bx - sigma (sinh bx - sin bx), int_0^l phi^2 = l, in long double.
        """
        b = self.roots.astype(np.longdouble)
        xi = b * np.longdouble(x) / np.longdouble(self.length)
        sigma = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))
        phi = np.cosh(xi) - np.cos(xi) - sigma * (np.sinh(xi) - np.sin(xi))
        tip = np.cosh(b) - np.cos(b) - sigma * (np.sinh(b) - np.sin(b))
        return (np.sign(tip) * phi / np.sqrt(np.longdouble(self.rhoA * self.length))).astype(
            float)

    def green(self, x: float, y: float) -> float:
        """Static deflection at x under a unit force at y: a^2 (3 b - a) / (6 EI) (m/N)."""
        a, b = min(x, y), max(x, y)
        return a * a * (3.0 * b - a) / (6.0 * self.EI)

    def residual(self, x: float, y: float) -> float:
        """R_N(x, y) = G(x, y) - sum_n Y_n(x) Y_n(y) / omega_n^2 (m/N)."""
        return self.green(x, y) - float(np.sum(self.shapes(x) * self.shapes(y)
                                               / self.frequencies**2))


@dataclasses.dataclass(frozen=True)
class PointContact:
    """The modal equations of a spring contact at points x1 (beam 1) and x2 (beam 2 or none).

    ``beam2`` None: a rigid stop. ``side``: s. ``stiffness``: k (N/m); ``clearance`` (m);
    ``force_amplitude`` F0 (N), ``omega`` (rad/s); ``uplift`` (m): beam 1's initial static tip
    deflection (its static tip-load shape), at rest.
    """

    beam1: Beam
    beam2: Beam | None
    x1: float
    x2: float
    side: float
    stiffness: float
    clearance: float
    force_amplitude: float
    omega: float
    uplift: float = 0.0

    @functools.cached_property
    def frequencies(self) -> np.ndarray:
        parts = [self.beam1.frequencies] + ([self.beam2.frequencies] if self.beam2 else [])
        return np.concatenate(parts)

    @functools.cached_property
    def load(self) -> np.ndarray:
        """Each coordinate's weight of the tip force: Y_1n(l1), 0 on beam 2's modes."""
        n2 = self.beam2.n if self.beam2 else 0
        return np.concatenate([self.beam1.shapes(self.beam1.length), np.zeros(n2)])

    @functools.cached_property
    def weights(self) -> np.ndarray:
        """w_n: the gap's weights on the coordinates, s (Y_1n(x1), -Y_2n(x2))."""
        parts = [self.beam1.shapes(self.x1)]
        if self.beam2:
            parts.append(-self.beam2.shapes(self.x2))
        return self.side * np.concatenate(parts)

    @functools.cached_property
    def effective_stiffness(self) -> float:
        """k_e = k / (1 + k r), r the modes' missed flexibility between the contact points."""
        r = self.beam1.residual(self.x1, self.x1)
        if self.beam2:
            r += self.beam2.residual(self.x2, self.x2)
        return self.stiffness / (1.0 + self.stiffness * r)

    @functools.cached_property
    def force_gap(self) -> float:
        """The gap's quasi-static part per unit F: -s R_N,1(x1, l1) (m/N)."""
        return -self.side * self.beam1.residual(self.x1, self.beam1.length)

    def point_deflection(self, t: np.ndarray, eta: np.ndarray) -> np.ndarray:
        """y1(x1, t) of whole coordinates eta (rows: coordinates), out of contact."""
        n1 = self.beam1.n
        force = self.force_amplitude * np.sin(self.omega * t)
        return (-self.beam1.residual(self.x1, self.beam1.length) * force
                + self.beam1.shapes(self.x1) @ eta[:n1])

    def initial_state(self) -> np.ndarray:
        """At rest on the uplift's static tip-load shape: eta_n = uplift Y_n(l1) / (c omega^2)."""
        c = self.beam1.green(self.beam1.length, self.beam1.length)
        eta = self.uplift * self.load / (c * self.frequencies**2)
        return np.concatenate([eta, np.zeros_like(eta)])

    def gap(self, t: float, state: np.ndarray) -> float:
        m = self.frequencies.size
        force = self.force_amplitude * math.sin(self.omega * t)
        return self.clearance + self.force_gap * force + float(self.weights @ state[:m])

    def gap_rate(self, t: float, state: np.ndarray) -> float:
        m = self.frequencies.size
        rate = self.force_amplitude * self.omega * math.cos(self.omega * t)
        return self.force_gap * rate + float(self.weights @ state[m:])

    def _rhs(self, in_contact: bool):
        w2, load, weights = self.frequencies**2, self.load, self.weights
        k_e, m = self.effective_stiffness, self.frequencies.size

        def rhs(t: float, state: np.ndarray) -> np.ndarray:
            force = self.force_amplitude * math.sin(self.omega * t)
            contact = -k_e * self.gap(t, state) if in_contact else 0.0
            return np.concatenate([state[m:], -w2 * state[:m] - load * force + weights * contact])

        return rhs

    def contacts(self, t_max: float, count: int, rtol: float = 1e-13,
                 ) -> dict[str, np.ndarray]:
        """The first ``count`` contacts before t_max: onset, release, peak force (s, s, N).

        DOP853 (``rtol``, atol 1e-24 on states of ~1e-8) from t = 0 at rest, each phase to the
        gap's zero (closing in the free phase, opening in contact, where R = -k_e g).
        """
        t, state, in_contact = 0.0, self.initial_state(), False
        onsets, releases, peaks = [], [], []
        while len(releases) < count and t < t_max:
            event = lambda s, y: self.gap(s, y)  # noqa: E731
            event.terminal, event.direction = True, (1.0 if in_contact else -1.0)
            # leave the zero the phase starts on before the event may fire
            solution = solve_ivp(self._rhs(in_contact), (t, t_max), state, method="DOP853",
                                 rtol=rtol, atol=1e-24, events=event, dense_output=True,
                                 first_step=1e-9)
            if not solution.t_events[0].size:
                break
            end = float(solution.t_events[0][0])
            if in_contact:
                peaks.append(self._peak(solution.sol, t, end))
                releases.append(end)
            else:
                onsets.append(end)
            t, state, in_contact = end, solution.sol(end), not in_contact
        return {"onset": np.array(onsets[:count]), "release": np.array(releases),
                "peak": np.array(peaks)}

    def _peak(self, sol, t0: float, t1: float) -> float:
        """Largest -k_e g over a contact [t0, t1]: at a zero of g' (brentq on the dense output)."""
        k_e = self.effective_stiffness
        grid = np.linspace(t0, t1, 2001)
        rates = np.array([self.gap_rate(s, sol(s)) for s in grid])
        best = max(-k_e * self.gap(s, sol(s)) for s in grid)
        for a, b, ra, rb in zip(grid[:-1], grid[1:], rates[:-1], rates[1:], strict=True):
            if ra < 0.0 <= rb:
                s = brentq(lambda u: self.gap_rate(u, sol(u)), a, b, xtol=1e-16, rtol=1e-15)
                best = max(best, -k_e * self.gap(s, sol(s)))
        return best
