"""Periodic orbits by shooting: Newton, or Newton-Picard, on z = P^p(z) at the section t = 0.

**Newton** (``method="newton"``): each step runs the period map with its full monodromy M
(2 N tangent columns) and solves ``(I - M) dz = P(z) - z``.

**Newton-Picard** (``method="newton-picard"``, Lust, Roose, Spence & Champneys 1998): M has a
few multipliers near or outside the unit circle and a strongly contracting rest (the damped
higher modes). An orthonormal basis V of m columns of the dominant invariant subspace is kept
up to date by subspace iteration (one product M V per step, m tangent columns); on it the
Newton equation is solved exactly (an m x m system), on its complement Q = I - V V^T a Picard
iteration takes its place, ``dq = Q (r + M dz)``, which converges at the rate of the
complement's largest multiplier. A step costs the period map with m + 1 tangent columns and
one without, instead of 2 N columns. All products are taken in the energy coordinates
x = (omega q, q') (orthogonality in the energy norm, where q and q' are comparable).

**Convergence**: the relative residual ``|P(z) - z| / |z|`` (energy norm) at most
``tolerance``; then the multipliers: the eigenvalues of M (Newton), or of ``V^T M V``
(Newton-Picard: the Ritz values of the subspace iteration, once they change by at most
``RITZ_TOLERANCE`` from one iteration to the next; the other multipliers are smaller in
modulus than the smallest of these, as far as the subspace is invariant: its residual
``|Q M V| / |M V|`` is reported). Multipliers below ~1e-16 |M| are round-off (the damped
high modes contract by far more in one period). A step that does not
reduce the residual is halved, up to ``MAX_HALVINGS`` times; no convergence within
``max_iterations`` raises `OrbitNotConverged`, never a silent result.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from impactbeams.blas import one_blas_thread
from impactbeams.kernels.layout import FREE, ROW_FREQUENCY
from impactbeams.orbits.period_map import PeriodMap, PeriodMapResult
from impactbeams.params import ParameterError, Params, require, require_integer, require_type
from impactbeams.trajectory.start import checked_state

MAX_HALVINGS = 8  # step halvings of one Newton step before it is taken as it is
DEFAULT_SUBSPACE = 8  # Newton-Picard's basis: the leading multipliers solved for exactly
# Ritz values left out of the reported multipliers: those next to the complement converge at
# the rate |mu_m+1 / mu_m|, slowly when it is near 1, and the leading ones do not need them
GUARD = 2
# Newton-Picard's multipliers: the Ritz values of V^T M V, converged when they change by at
# most this between two subspace iterations
RITZ_TOLERANCE = 1e-10
AUTO_NEWTON_DIMENSION = 48  # "auto": the full monodromy up to this many coordinates (2 N)
METHODS = ("auto", "newton", "newton-picard")


class OrbitNotConverged(RuntimeError):
    """Shooting did not reach its tolerance; ``history`` holds the relative residuals."""

    def __init__(self, message: str, history: list[float]) -> None:
        super().__init__(message)
        self.history = history


@dataclasses.dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic orbit of period p forcing periods, on the section t = 0 (SI units).

    ``state``: z = (q, q') on the section (2 N free coordinates, `simulate`'s
    ``initial_state``). ``multipliers``: Floquet multipliers (complex, by decreasing modulus;
    Newton-Picard: the m leading ones only, see the module doc); ``stable``: all inside the
    unit circle; ``exponents``: ln|mu| / (p T) (1/s), the orbit's Lyapunov exponents.
    ``contacts``, ``episodes``: contact phases and impact episodes per orbit (p periods);
    ``peak_force`` (N), ``impulse`` (N s per orbit), ``max_tip1``, ``max_tip2`` (m), ``min_gap``
    (m, smallest local minimum of the gap in the free phases, NaN if none) and its time
    ``min_gap_time`` (s) in [0, p T). ``residual``: the final relative residual;
    ``iterations``: shooting steps (each one map with tangents); ``history``: the residual
    before each step; ``method``; ``subspace_residual``: Newton-Picard's |Q M V| / |M V| (0 for
    Newton); ``monodromy``: M (Newton) or None; ``basis``: Newton-Picard's V in the free
    coordinates (or None), a start for the next orbit of a continuation.
    """

    params: Params
    n_modes: int
    period: int
    state: np.ndarray
    multipliers: np.ndarray
    stable: bool
    exponents: np.ndarray
    contacts: int
    episodes: int
    peak_force: float
    impulse: float
    max_tip1: float
    max_tip2: float
    min_gap: float
    min_gap_time: float
    residual: float
    iterations: int
    history: tuple[float, ...]
    method: str
    subspace_residual: float
    monodromy: np.ndarray | None
    basis: np.ndarray | None

    @property
    def duration(self) -> float:
        """P T (s): the orbit's period in time."""
        return self.period * 2.0 * math.pi / self.params.omega

    def to_dataset(self, samples_per_period: int = 256):
        """The orbit over one period p T: `simulate`'s Dataset from ``state``.

        Output times ``samples_per_period`` per forcing period (tips, gap, contact force,
        energies, the contacts' table, with the registry's units), plus the multipliers
        (``floquet_multiplier_real``, ``_imag``, ``floquet_exponent`` along ``multiplier``)
        and the orbit's attributes (residual, iterations, stable, method).
        """
        from impactbeams.orbits.dataset import orbit_dataset

        return orbit_dataset(self, samples_per_period)


@one_blas_thread
def periodic_orbit(params: Params, n_modes: int | None = None, period: int = 1,
                   guess: np.ndarray | PeriodicOrbit | None = None, *,
                   transient_periods: int = 50, tolerance: float = 1e-11,
                   max_iterations: int = 30, method: str = "auto",
                   subspace: int | None = None, measures: bool = True) -> PeriodicOrbit:
    """The periodic orbit z = P^p(z) of ``params`` (spring law, Omega > 0) near ``guess``.

    Args:
        params: the model.
        n_modes: modes per beam (default: the number that resolves the contact, as in
            `simulate`).
        period: p, the orbit's period in forcing periods.
        guess: a section state z (2 N values), an earlier `PeriodicOrbit` (its state, and its
            Newton-Picard basis), or None: the state after ``transient_periods`` forcing
            periods from ``params.start`` (a stable orbit's basin is then reached by simply
            running).
        transient_periods: forcing periods run from ``params.start`` when ``guess`` is None.
        tolerance: on the relative residual |P^p(z) - z| / |z| in the energy norm.
        max_iterations: shooting steps before `OrbitNotConverged`.
        method: "newton" (full monodromy), "newton-picard" (``subspace`` leading directions
            exactly, the rest by Picard iteration), or "auto": Newton up to
            ``AUTO_NEWTON_DIMENSION`` coordinates, Newton-Picard above.
        subspace: m, Newton-Picard's basis size; the leading m - ``GUARD`` Ritz values are
            reported as the multipliers (default ``DEFAULT_SUBSPACE``, at most 2 N).
        measures: also the orbit's peak force, impulse, tip maxima and minimum gap (else NaN;
            the contacts' peak forces cost most, a search at the fastest contact mode's time
            scale per contact).

    Raises ParameterError for bad arguments (the tied law included: no tangent flow) and
    `OrbitNotConverged` when the residual does not reach ``tolerance``.
    """
    period_map = PeriodMap(params, n_modes, require_integer("period", period, 1))
    method = checked_method(method, period_map.dimension)
    tolerance = float(tolerance)
    require("tolerance", tolerance, 0 < tolerance < 1, "must be in (0, 1)")
    max_iterations = require_integer("max_iterations", max_iterations, 1)
    subspace = checked_subspace(subspace, period_map.dimension)
    z, basis = _start(period_map, guess, require_integer("transient_periods",
                                                           transient_periods, 0))
    require_type("measures", measures, isinstance(measures, bool), "True or False")
    solver = _Shooting(period_map, tolerance, max_iterations, measures)
    if method == "newton":
        return solver.newton(z)
    return solver.newton_picard(z, basis, subspace)


def checked_subspace(subspace: int | None, dimension: int) -> int:
    """Newton-Picard's basis size for a map of ``dimension`` coordinates.

    ``subspace`` checked, or by default ``DEFAULT_SUBSPACE`` but no more than the map has (a
    small model's Newton does not use it, and should not be refused for it).
    """
    if subspace is None:
        return min(DEFAULT_SUBSPACE, dimension)
    return require_integer("subspace", subspace, GUARD + 1, dimension)


def checked_method(method: str, dimension: int) -> str:
    """``method`` checked, "auto" resolved for a map of ``dimension`` coordinates."""
    require("method", method, method in METHODS,
            "must be 'auto', 'newton' or 'newton-picard'")
    if method == "auto":
        return "newton" if dimension <= AUTO_NEWTON_DIMENSION else "newton-picard"
    return method


def _start(period_map: PeriodMap, guess: object, transient: int,
           ) -> tuple[np.ndarray, np.ndarray | None]:
    if isinstance(guess, PeriodicOrbit):
        if guess.state.size != period_map.dimension:
            raise ParameterError(f"guess: an orbit of {guess.state.size} coordinates, this "
                                 f"model has {period_map.dimension} (n_modes, counterpart)")
        return guess.state.copy(), guess.basis
    if guess is not None:
        return checked_state(period_map.packed, guess, "guess"), None
    z = period_map.rest_state()
    for _ in range(transient):
        z = period_map(z, measures=False).state
    return z, None


class _Shooting:
    """Newton and Newton-Picard iterations on one period map (see the module doc)."""

    def __init__(self, period_map: PeriodMap, tolerance: float, max_iterations: int,
                 measures: bool) -> None:
        self.map = period_map
        self.measures = measures
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        omega = period_map.packed.tables[FREE, ROW_FREQUENCY]
        self.scale = np.concatenate([omega, np.ones(omega.size)])  # x = D z: energy coordinates

    def norm(self, z: np.ndarray) -> float:
        return float(np.linalg.norm(self.scale * z))

    def relative(self, result: PeriodMapResult, z: np.ndarray) -> float:
        return self.norm(result.state - z) / max(self.norm(z), np.finfo(float).tiny)

    def newton(self, z: np.ndarray) -> PeriodicOrbit:
        history: list[float] = []
        identity = np.eye(z.size)
        result = self.map(z, measures=False)
        for _ in range(self.max_iterations + 1):
            jacobian = self.map.jacobian(result, "all")
            residual = self.relative(result, z)
            history.append(residual)
            if residual <= self.tolerance:
                return self._orbit(z, np.linalg.eigvals(jacobian), history, "newton", 0.0,
                                   jacobian, None)
            if len(history) > self.max_iterations:
                break
            step = np.linalg.solve(identity - jacobian, result.state - z)
            z, result = self._damped(z, step, residual)
        raise self._failure(history, "newton")

    def newton_picard(self, z: np.ndarray, basis: np.ndarray | None, m: int) -> PeriodicOrbit:
        """Newton-Picard iterations; V in energy coordinates, orthonormal.

        One run of the map per iteration (the step's trial run is the next iterate's): M V
        and M Q r come from tangents carried along it.
        """
        v = self._initial_basis(basis, m, z.size)
        history: list[float] = []
        previous = np.full(m, np.inf + 0j)
        result = self.map(z, measures=False)
        for _ in range(self.max_iterations + 1):
            r = self.scale * (result.state - z)
            residual = self.relative(result, z)
            history.append(residual)
            q_r = r - v @ (v.T @ r)
            images = self._products(result, np.column_stack([v, q_r]))  # M V, M Q r
            mv, m_qr = images[:, :-1], images[:, -1]
            h = v.T @ mv
            ritz = by_modulus(np.linalg.eigvals(h))
            reported = leading(ritz)
            settled = np.max(np.abs(ritz[:reported] - previous[:reported])) <= RITZ_TOLERANCE
            if residual <= self.tolerance and settled:
                return self._orbit(z, ritz[:reported], history, "newton-picard",
                                   _invariance(v, mv), None, v / self.scale[:, None])
            if len(history) > self.max_iterations:
                break
            if residual > self.tolerance:
                dp = np.linalg.solve(np.eye(m) - h, v.T @ r + v.T @ m_qr)
                coupled = mv @ dp + m_qr
                dq = q_r + coupled - v @ (v.T @ coupled)
                z, result = self._damped(z, (v @ dp + dq) / self.scale, residual)
            previous = ritz
            v = orthonormal(mv)
        raise self._failure(history, "newton-picard")

    def _products(self, result: PeriodMapResult, columns: np.ndarray) -> np.ndarray:
        """M applied to ``columns`` given in energy coordinates, back in energy coordinates."""
        return self.scale[:, None] * self.map.jacobian(result, columns / self.scale[:, None])

    def _initial_basis(self, basis: np.ndarray | None, m: int, size: int) -> np.ndarray:
        if basis is not None and basis.shape == (size, m):
            return orthonormal(self.scale[:, None] * basis)
        # fixed pseudo-random directions: the same orbit on every machine
        return orthonormal(np.random.default_rng(0).standard_normal((size, m)))

    def _damped(self, z: np.ndarray, step: np.ndarray, residual: float,
                ) -> tuple[np.ndarray, PeriodMapResult]:
        """Z + step, halved while that does not reduce the residual; with its map's result.

        After ``MAX_HALVINGS`` halvings the last trial is taken as it is (if its run
        completes): the next iterate then starts from there.
        """
        for _ in range(MAX_HALVINGS):
            candidate = z + step
            try:
                result = self.map(candidate, measures=False)
            except RuntimeError:  # the run did not complete: too far
                step = 0.5 * step
                continue
            if self.relative(result, candidate) < residual:
                return candidate, result
            step = 0.5 * step
        candidate = z + step
        return candidate, self.map(candidate, measures=False)

    def _failure(self, history: list[float], method: str) -> OrbitNotConverged:
        shown = ", ".join(f"{value:.2e}" for value in history[-5:])
        return OrbitNotConverged(
            f"periodic_orbit ({method}): the relative residual did not reach tolerance = "
            f"{self.tolerance:g} in {self.max_iterations} iterations (last: {shown}); try "
            "another guess (more transient_periods), another period, or a smaller "
            "continuation step", history)

    def _orbit(self, z: np.ndarray, multipliers: np.ndarray, history: list[float],
               method: str, invariance: float, monodromy: np.ndarray | None,
               basis: np.ndarray | None) -> PeriodicOrbit:
        result = self.map(z, measures=self.measures)
        multipliers = by_modulus(multipliers)
        duration = self.map.horizon
        with np.errstate(divide="ignore"):
            exponents = np.log(np.abs(multipliers)) / duration
        return PeriodicOrbit(
            self.map.params, self.map.n_modes, self.map.periods, z, multipliers,
            bool(np.all(np.abs(multipliers) < 1.0)), exponents, result.contacts,
            result.episodes, result.peak_force, result.impulse, result.max_tip1,
            result.max_tip2, result.min_gap, result.min_gap_time, history[-1],
            len(history) - 1, tuple(history), method, invariance, monodromy, basis)


def leading(ritz: np.ndarray) -> int:
    """How many leading Ritz values to report: all but ``GUARD``, a conjugate pair kept whole."""
    count = max(ritz.size - GUARD, 1)
    if count < ritz.size and ritz[count - 1].imag > 0 and ritz[count] == np.conj(
            ritz[count - 1]):
        count -= 1
    return max(count, 1)


def by_modulus(values: np.ndarray) -> np.ndarray:
    """Complex values by decreasing modulus, a conjugate pair's positive imaginary part first."""
    return values[np.lexsort((-values.imag, -np.abs(values)))]


def orthonormal(columns: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the columns' span (QR)."""
    q, _ = np.linalg.qr(columns)
    return q


def _invariance(v: np.ndarray, mv: np.ndarray) -> float:
    """|Q M V| / |M V| (2-norms): how far span V is from an invariant subspace of M."""
    outside = mv - v @ (v.T @ mv)
    return float(np.linalg.norm(outside, 2) / max(np.linalg.norm(mv, 2), np.finfo(float).tiny))
