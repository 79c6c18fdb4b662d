"""A cantilever with attachments: its natural frequencies, modes and static flexibility.

The beam is cut into pieces at every step of its cross-section and every attachment; each
piece is uniform. Two exact descriptions of the same beam are used, each where it is well
conditioned:

* the **dynamic stiffness** (Wittrick-Williams): the nodal DOFs between pieces, each piece's
  exact 4x4 (or, for a free last piece, 2x2) dynamic stiffness and the attachments on the
  diagonal. The number of natural frequencies below omega is
  ``J(omega) = J0(omega) + s(K(omega))``, J0 the pieces' own frequencies below omega with
  their ends held, s the number of negative eigenvalues of K. J brackets every root.
* the **wave coefficients**: four per piece in a bounded basis (``waves``), tied by the
  clamp, the joint conditions at each node and the tip: a matrix A(omega) with rows scaled
  to unit size, pole-free, whose determinant changes sign at each natural frequency. Roots
  are refined on it, and its null vectors are the mode shapes.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence

import numpy as np

from impactbeams.brent import brentq
from impactbeams.checks import is_real, require, require_integer
from impactbeams.structure import flexibility, waves
from impactbeams.structure.parts import (
    Attachment,
    PointMass,
    Segment,
    Spring,
    check_attachments,
    check_clamp,
)

_RTOL = 4 * np.finfo(float).eps
_COINCIDENT = 8 * np.finfo(float).eps  # bracket width (relative) at which roots are one
_CLUSTER = np.sqrt(np.finfo(float).eps)  # roots closer than this (relative) share their shapes
# a field's slope at a rotary inertia by fourth-order one-sided differences with step h =
# SLOPE_STEP / k, k the highest mode's wave number (the shortest scale the modes resolve):
# truncation (k h)^4 / 5 ~ 6e-14 and round-off ~ 11 eps / (k h) ~ 3e-12, both of k |w|
SLOPE_STEP = float(np.finfo(float).eps ** 0.2)
# (offsets in steps, weights / step): one-sided from the clamp side (at the tip), from the tip
# side (at the clamp), and their mean elsewhere; never across the point, where the curvature of
# a mode (or of the static shape) jumps under a rotary inertia or a rotational spring
_BACKWARD = ((0, -1, -2, -3, -4), (25 / 12, -4.0, 3.0, -4 / 3, 0.25))
_FORWARD = ((0, 1, 2, 3, 4), (-25 / 12, 4.0, -3.0, 4 / 3, -0.25))
_BOTH_SIDES = ((-4, -3, -2, -1, 1, 2, 3, 4), (0.125, -2 / 3, 1.5, -2.0, 2.0, -1.5, 2 / 3, -0.125))


@dataclasses.dataclass(frozen=True)
class Pieces:
    """The uniform pieces between nodes; node j is the end of piece j (the last: the tip).

    Arrays per piece: ``starts``, ``lengths`` (m), ``EI`` (N m^2), ``rhoA`` (kg/m); per node:
    ``mass`` (kg), ``inertia`` (kg m^2), ``stiffness`` (N/m), ``rotational`` (N m/rad), the
    attachments there summed; ``clamp`` (N m/rad): the clamp's rotational stiffness, inf if rigid.
    """

    starts: np.ndarray
    lengths: np.ndarray
    EI: np.ndarray
    rhoA: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    stiffness: np.ndarray
    rotational: np.ndarray
    clamp: float

    @property
    def ends(self) -> np.ndarray:
        """Each piece's far end (m)."""
        return self.starts + self.lengths

    @property
    def compliant(self) -> bool:
        """Whether the clamp turns (a rotational spring there)."""
        return math.isfinite(self.clamp)

    @property
    def free_tip(self) -> bool:
        """Whether nothing is attached at the tip (then the last piece ends free)."""
        return not (self.mass[-1] or self.inertia[-1] or self.stiffness[-1]
                    or self.rotational[-1])


def _pieces(segments: tuple[Segment, ...], attachments: tuple[Attachment, ...]) -> Pieces:
    """Cut the segments at every attachment position (attachments at one point summed)."""
    segment_ends = np.cumsum([s.length for s in segments])
    segment_ends[-1] = math.fsum(s.length for s in segments)
    cuts = {float(e) for e in segment_ends} | {a.position for a in attachments if a.position > 0}
    ends = np.array(sorted(cuts))
    starts = np.concatenate([[0.0], ends[:-1]])
    owner = np.minimum(np.searchsorted(segment_ends, starts, side="right"), len(segments) - 1)
    sums = {name: np.zeros(len(ends)) for name in ("mass", "inertia", "stiffness", "rotational")}
    clamp = 0.0
    for a in attachments:
        if a.position == 0.0:
            clamp += a.rotational_stiffness  # check_attachments: only rotational springs here
            continue
        node = int(np.searchsorted(ends, a.position))
        if isinstance(a, PointMass):
            sums["mass"][node] += a.mass
            sums["inertia"][node] += a.rotary_inertia
        else:
            sums["stiffness"][node] += a.stiffness
            sums["rotational"][node] += a.rotational_stiffness
    has_clamp_spring = any(isinstance(a, Spring) and a.position == 0.0 for a in attachments)
    return Pieces(starts, ends - starts, np.array([segments[i].EI for i in owner]),
                  np.array([segments[i].rhoA for i in owner]), **sums,
                  clamp=clamp if has_clamp_spring else math.inf)


@dataclasses.dataclass(frozen=True)
class Cantilever:
    """A cantilever clamped at x = 0, free at x = L, with attachments anywhere on it.

    ``segments``: uniform Segments from the clamp out; ``attachments``: PointMass and Spring
    parts at any positions 0 <= x <= L (m).

    A rotational Spring at x = 0 makes the clamp compliant. Attachments at one position add.
    """

    segments: tuple[Segment, ...]
    attachments: tuple[Attachment, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "segments", tuple(self.segments))
        object.__setattr__(self, "attachments", tuple(self.attachments))
        require("segments", self.segments, len(self.segments) > 0 and all(
            isinstance(s, Segment) for s in self.segments), "must be one or more Segment")
        check_attachments(self.attachments, self.length)
        check_clamp(self.attachments)

    @classmethod
    def uniform(cls, EI: float, rhoA: float, length: float,
                attachments: Sequence[Attachment] = ()) -> Cantilever:
        """A uniform beam (EI in N m^2, rhoA in kg/m, length in m) with ``attachments``."""
        return cls((Segment(length, EI, rhoA),), tuple(attachments))

    @property
    def length(self) -> float:
        """L (m), the sum of the segments' lengths."""
        return math.fsum(s.length for s in self.segments)

    @functools.cached_property
    def pieces(self) -> Pieces:
        """The uniform pieces between attachments and steps."""
        return _pieces(self.segments, self.attachments)

    def frequency_count(self, omega: float) -> int:
        """How many natural frequencies lie below ``omega`` (rad/s): the Wittrick-Williams count."""
        omega = _positive_frequency(omega)
        return _count(self.pieces, omega)

    def modes(self, n: int) -> StructureModes:
        """The first ``n`` natural frequencies (rad/s) and mass-normalised modes."""
        n = require_integer("n", n, 1)
        return _modes(self, n)

    def flexibility(self, x: np.ndarray, y: np.ndarray, derivative: int = 0) -> np.ndarray:
        """Static deflection at each ``x`` (m) under a unit force at each ``y`` (m).

        The Green's function with the springs (m/N), shape (len(x), len(y)); ``derivative``
        1: its slope in x (1/N).
        """
        x, y = self.positions("x", x), self.positions("y", y)
        p = self.pieces
        ports = [(e, 0) for e, k in zip(p.ends, p.stiffness, strict=True) if k]
        ports += [(e, 1) for e, k in zip(p.ends, p.rotational, strict=True) if k]
        stiffness = np.array([k for k in (*p.stiffness, *p.rotational) if k])
        return flexibility.spring_flexibility(x, y, p.starts, p.ends, p.EI, p.clamp, ports,
                                              stiffness, derivative)

    @property
    def closed_form(self) -> bool:
        """Whether this is one uniform segment with nothing attached: the textbook cantilever.

        Its modes are written in closed form by `impactbeams.modes`.
        """
        return len(self.segments) == 1 and not self.attachments

    @property
    def tip_compliance(self) -> float:
        """The tip compliance w(L) under a unit tip force (m/N); L^3 / (3 EI) if uniform."""
        if self.closed_form:
            segment = self.segments[0]
            return segment.length**3 / (3 * segment.EI)
        return float(self.flexibility(self.length, self.length)[0, 0])

    def unit_tip_shape(self, x: np.ndarray, derivative: int = 0) -> np.ndarray:
        """The static deflection under a tip force with unit tip deflection, at ``x`` (m).

        (3 L x^2 - x^3) / (2 L^3) on the textbook cantilever; ``derivative`` 1: its slope (1/m).
        """
        return self.flexibility(x, self.length, derivative)[:, 0] / self.tip_compliance

    @functools.cached_property
    def static_mass(self) -> float:
        """<u, u> (kg) of the unit tip-load shape u, the attachments' mass and inertia included.

        33/140 rhoA L on the textbook cantilever. u is cubic on each piece, so four Gauss points
        per piece integrate u^2 exactly.
        """
        p = self.pieces
        nodes, weights = np.polynomial.legendre.leggauss(4)
        x = (p.starts[:, None] + p.lengths[:, None] * (nodes[None, :] + 1.0) / 2.0).ravel()
        w = (p.rhoA[:, None] * p.lengths[:, None] * weights[None, :] / 2.0).ravel()
        beam = float(w @ self.unit_tip_shape(np.minimum(x, self.length)) ** 2)
        ends = np.minimum(p.ends, self.length)  # the last end is L to the last bit
        return beam + float(p.mass @ self.unit_tip_shape(ends) ** 2
                            + p.inertia @ self.unit_tip_shape(ends, 1) ** 2)

    def positions(self, name: str, x: np.ndarray) -> np.ndarray:
        """``x`` as a 1-D float array, or a ParameterError if a value is not on the beam."""
        x = np.atleast_1d(np.asarray(x))
        ok = x.ndim == 1 and np.issubdtype(x.dtype, np.number) and not np.iscomplexobj(x)
        require(name, x, ok, "must be real positions (m)")
        bad = ~(np.isfinite(x) & (x >= 0.0) & (x <= self.length))
        if bad.any():
            require(name, float(x[bad][0]), False,
                    f"must lie on the beam, 0 <= x <= {self.length!r}", "m")
        return x.astype(float)


def _positive_frequency(omega: float) -> float:
    """``omega`` as a float, or a ParameterError unless it is a finite real number > 0."""
    require("omega", omega, is_real(omega) and math.isfinite(omega) and omega > 0.0,
            "must be a finite frequency > 0", "rad/s")
    return float(omega)


# --- Wittrick-Williams count ----------------------------------------------------------------


def _dofs(p: Pieces) -> tuple[list[list[int | None]], int]:
    """Global DOF indices (w, theta) at each piece's near end and far end, and their number.

    The clamp holds w (and theta unless compliant); a free tip carries no DOFs (its piece
    enters through the free-end stiffness).
    """
    count = 0
    clamp_theta = None
    if p.compliant:
        clamp_theta, count = 0, 1
    nodes = []
    for j in range(len(p.lengths)):
        if j == len(p.lengths) - 1 and p.free_tip:
            nodes.append([None, None])
        else:
            nodes.append([count, count + 1])
            count += 2
    near = [[None, clamp_theta]] + nodes[:-1]
    return [near[j] + nodes[j] for j in range(len(nodes))], count


def _count(p: Pieces, omega: float) -> int:
    """J0 + s(K) at ``omega``: natural frequencies below it."""
    K, held = _dynamic_stiffness(p, omega)
    return held + (int(np.count_nonzero(np.linalg.eigvalsh(K) < 0.0)) if len(K) else 0)


def _dynamic_stiffness(p: Pieces, omega: float) -> tuple[np.ndarray, int]:
    """K(omega) on the nodal DOFs (theta in units of w k), and J0.

    J0: the pieces' own natural frequencies below omega with their nodal DOFs held.
    """
    element_dofs, size = _dofs(p)
    k = waves.wave_number(omega, p.EI, p.rhoA)
    b = k * p.lengths
    # theta DOFs in units of w k (a congruence: the same inertia): every entry ~ EI k^3, so
    # that eigvalsh's error, eps times the largest entry, stays eps of each entry's own size
    slope_unit = k.max()
    K = np.zeros((size, size))
    held = 0
    for j, dofs in enumerate(element_dofs):
        if j == len(b) - 1 and p.free_tip:
            element, dofs = waves.free_end_stiffness(p.EI[j], k[j], b[j]), dofs[:2]
            held += waves.free_count(b[j])
        else:
            element = waves.dynamic_stiffness(p.EI[j], k[j], b[j])
            held += waves.clamped_count(b[j])
        scale = np.array([1.0, slope_unit, 1.0, slope_unit])[: len(dofs)]
        element = element * np.outer(scale, scale)
        index = [i for i, d in enumerate(dofs) if d is not None]
        taken = [dofs[i] for i in index]
        K[np.ix_(taken, taken)] += element[np.ix_(index, index)]
    for j, dofs in enumerate(element_dofs):
        w, theta = dofs[2], dofs[3]
        if w is not None:
            K[w, w] += p.stiffness[j] - p.mass[j] * omega**2
            K[theta, theta] += (p.rotational[j] - p.inertia[j] * omega**2) * slope_unit**2
    if p.compliant:
        K[0, 0] += p.clamp * slope_unit**2
    return K, held


# --- wave coefficients ----------------------------------------------------------------------


def _wave_matrix(p: Pieces, omega: float, short: np.ndarray) -> np.ndarray:
    """A(omega): clamp, joint and tip conditions on the 4 wave coefficients of each piece.

    Joint at node j (piece j's end, piece j+1's start): w and w' continuous, and
    EI w''(+) - EI w''(-) = (kr - J omega^2) w',  EI w'''(-) - EI w'''(+) = (kt - m omega^2) w.
    Each row is divided by its largest entry (a positive factor, continuous in omega).
    """
    n = len(p.lengths)
    k = waves.wave_number(omega, p.EI, p.rhoA)
    scale = k[:, None, None] ** np.arange(4)[None, :, None]  # d/dx = k d/dxi
    start, end = (values * scale for values in waves.end_values(k * p.lengths, short))

    def at(j: int, far: bool, derivative: int) -> np.ndarray:
        """Row block: w^(derivative) on piece j at its start or end, per unit coefficient."""
        return (end if far else start)[j, derivative]

    rows = []

    def row(*blocks: tuple[int, np.ndarray]) -> None:
        r = np.zeros(4 * n)
        for j, values in blocks:
            r[4 * j: 4 * j + 4] += values
        rows.append(r / np.abs(r).max())

    row((0, at(0, False, 0)))
    if p.compliant:
        row((0, p.EI[0] * at(0, False, 2) - p.clamp * at(0, False, 1)))
    else:
        row((0, at(0, False, 1)))
    for j in range(n - 1):
        turn = p.rotational[j] - p.inertia[j] * omega**2
        push = p.stiffness[j] - p.mass[j] * omega**2
        row((j, at(j, True, 0)), (j + 1, -at(j + 1, False, 0)))
        row((j, at(j, True, 1)), (j + 1, -at(j + 1, False, 1)))
        row((j + 1, p.EI[j + 1] * at(j + 1, False, 2)),
            (j, -p.EI[j] * at(j, True, 2) - turn * at(j, True, 1)))
        row((j, p.EI[j] * at(j, True, 3) - push * at(j, True, 0)),
            (j + 1, -p.EI[j + 1] * at(j + 1, False, 3)))
    last = n - 1
    row((last, p.EI[last] * at(last, True, 2)
         + (p.rotational[last] - p.inertia[last] * omega**2) * at(last, True, 1)))
    row((last, p.EI[last] * at(last, True, 3)
         - (p.stiffness[last] - p.mass[last] * omega**2) * at(last, True, 0)))
    return np.array(rows)


def _short(p: Pieces, omega: float) -> np.ndarray:
    """Which pieces use the short (Krylov) basis at ``omega``."""
    return waves.wave_number(omega, p.EI, p.rhoA) * p.lengths <= waves.SHORT


def _secular(omega: float, p: Pieces, short: np.ndarray) -> float:
    """The determinant of A(omega): zero at natural frequencies, continuous, bounded.

    Every row of A has entries of at most 1, so |det A| <= 8^(rows / 2) (Hadamard).
    """
    return float(np.linalg.det(_wave_matrix(p, omega, short)))


# --- roots and shapes -----------------------------------------------------------------------


def _brackets(p: Pieces, n: int) -> list[tuple[float, float, int, int]]:
    """(low, high, index of the first root inside, roots inside) isolating the first n roots.

    Bisection on the count until each interval holds one root, or is too narrow to split
    (coincident roots).
    """
    high = float(np.sqrt(p.EI / p.rhoA).min() * (n * math.pi / p.lengths.sum()) ** 2)
    while _count(p, high) < n:
        high *= 2.0
    low = high
    while _count(p, low) > 0:
        low /= 2.0
    found = []
    stack = [(low, 0, high, _count(p, high))]
    while stack:
        lo, j_lo, hi, j_hi = stack.pop()
        if j_lo >= n or j_hi == j_lo:
            continue
        if j_hi - j_lo == 1 or hi - lo <= _COINCIDENT * hi:
            found.append((lo, hi, j_lo, j_hi - j_lo))
            continue
        mid = 0.5 * (lo + hi)
        j_mid = _count(p, mid)
        stack += [(mid, j_mid, hi, j_hi), (lo, j_lo, mid, j_mid)]
    return sorted(found)


def _root(p: Pieces, lo: float, hi: float, index: int) -> tuple[float, np.ndarray]:
    """The one natural frequency in (lo, hi) (rad/s), and the bases used there."""
    short = _short(p, hi)
    f_lo, f_hi = _secular(lo, p, short), _secular(hi, p, short)
    if f_lo == 0.0:
        return lo, short
    if f_hi == 0.0:
        return hi, short
    if (f_lo < 0) == (f_hi < 0) and hi - lo <= _COINCIDENT * hi:
        return 0.5 * (lo + hi), short  # the count put the root in a bracket of round-off width
    if (f_lo < 0) == (f_hi < 0):
        raise RuntimeError(f"natural frequency {index + 1} not bracketed in [{lo!r}, {hi!r}] "
                           f"rad/s (secular values {f_lo!r}, {f_hi!r}): please report this beam")
    return brentq(_secular, lo, hi, args=(p, short), xtol=1e-300, rtol=_RTOL), short


def _integral_of_square(p: Pieces, k: np.ndarray, short: np.ndarray,
                        c: np.ndarray) -> float:
    """The sum over pieces of rhoA int w^2 dx for wave coefficients ``c`` (pieces x 4).

    For y'''' = y: int_0^b y^2 dxi = [3 y y''' - y' y'' + xi (y^2 - 2 y' y''' + y''^2)]_0^b / 4.
    """
    total = 0.0
    for j in range(len(k)):
        b = k[j] * p.lengths[j]
        ends = []
        for xi in (0.0, b):
            y = [waves.basis(xi, b, short[j], d) @ c[j] for d in range(4)]
            ends.append(3 * y[0] * y[3] - y[1] * y[2]
                        + xi * (y[0] ** 2 - 2 * y[1] * y[3] + y[2] ** 2))
        total += p.rhoA[j] / k[j] * (ends[1] - ends[0]) / 4.0
    return total


def _modes(beam: Cantilever, n: int) -> StructureModes:
    """The first n modes: roots from the count's brackets, shapes per cluster of roots."""
    p = beam.pieces
    roots = []
    for lo, hi, index, multiplicity in _brackets(p, n):
        if multiplicity == 1:
            roots.append(_root(p, lo, hi, index)[0])
        else:
            roots += [0.5 * (lo + hi)] * multiplicity
    roots = roots[:n]
    wave_numbers, bases, coefficients = [], [], []
    for cluster in _clusters(np.array(roots)):
        omega = float(np.mean(cluster))
        short = _short(p, max(cluster))
        null = np.linalg.svd(_wave_matrix(p, omega, short))[2][-len(cluster):]
        k = waves.wave_number(omega, p.EI, p.rhoA)
        for c in _orthonormal(p, k, short, null.reshape(len(cluster), -1, 4)):
            wave_numbers.append(k)
            bases.append(short)
            coefficients.append(c)
    shapes = StructureModes(beam, np.array(roots), np.array(wave_numbers), np.array(bases),
                            np.array(coefficients))
    return shapes.with_signs()


def _clusters(roots: np.ndarray) -> list[np.ndarray]:
    """Runs of roots closer than ``_CLUSTER`` (relative) to the next, whose shapes go together.

    A run's shapes span the null space of A at its mean frequency.
    Alone, a root at a relative distance d from its neighbour gets a null vector accurate to
    eps / d only (A's second smallest singular value is of order d): sqrt(eps) is the
    crossing, where either way the shapes are orthogonal to about 1e-8.
    """
    cut = np.nonzero(np.diff(roots) > _CLUSTER * roots[1:])[0] + 1
    return np.split(roots, cut)


def _orthonormal(p: Pieces, k: np.ndarray, short: np.ndarray,
                 vectors: np.ndarray) -> list[np.ndarray]:
    """Mass-orthonormal combinations of the null vectors of one (possibly repeated) root."""
    out: list[np.ndarray] = []
    for c in vectors:
        for previous in out:
            c = c - _mass_product(p, k, short, previous, c) * previous
        out.append(c / np.sqrt(_mass_product(p, k, short, c, c)))
    return out


def _mass_product(p: Pieces, k: np.ndarray, short: np.ndarray, a: np.ndarray,
                  c: np.ndarray) -> float:
    """<a, c> with the attachments, by polarisation of the quadratic form (one frequency)."""
    def form(v: np.ndarray) -> float:
        value = _integral_of_square(p, k, short, v)
        for j in range(len(k)):
            end = k[j] * p.lengths[j]
            w = waves.basis(end, end, short[j], 0) @ v[j]
            slope = k[j] * waves.basis(end, end, short[j], 1) @ v[j]
            value += p.mass[j] * w**2 + p.inertia[j] * slope**2
        return value
    return (form(a + c) - form(a - c)) / 4.0


def _stencil(at: float, step: float, length: float) -> tuple[tuple[float, ...], ...]:
    """The difference stencil for a slope at ``at`` (m), its points within [0, ``length``]."""
    if 4 * step <= at <= length - 4 * step:
        return _BOTH_SIDES
    return _BACKWARD if at > length - 4 * step else _FORWARD


@dataclasses.dataclass(frozen=True)
class StructureModes:
    """The first natural frequencies (rad/s) of ``beam`` and their mass-normalised shapes.

    ``int rhoA Y_n Y_m dx + sum mass Y_n Y_m + sum rotary_inertia Y_n' Y_m' = delta_nm``
    (Y in kg^-1/2), each with its tip deflection >= 0 (its tip slope > 0 where that is 0).

    Stored as wave coefficients per mode and piece (``coefficients``, modes x pieces x 4) with
    the wave numbers (1/m) and bases they belong to.
    """

    beam: Cantilever
    frequencies: np.ndarray
    wave_numbers: np.ndarray
    short: np.ndarray
    coefficients: np.ndarray

    def __call__(self, x: np.ndarray, derivative: int = 0) -> np.ndarray:
        """d^n Y / dx^n (n = ``derivative``, 0..3) at positions ``x`` (m): (modes, len(x)).

        At a node the value is the clamp side's (the second and third derivatives jump where a
        mass or a spring sits).
        """
        x = self.beam.positions("x", x)
        derivative = require_integer("derivative", derivative, 0, 3)
        p = self.beam.pieces
        piece = np.minimum(np.searchsorted(p.ends, x, side="left"), len(p.ends) - 1)
        values = np.empty((len(self.frequencies), len(x)))
        for j in np.unique(piece):
            at = piece == j
            k = self.wave_numbers[:, j]
            xi = k[:, None] * (x[at] - p.starts[j])[None, :]
            for kind in (True, False):
                modes = self.short[:, j] == kind
                if modes.any():
                    b = (k[modes] * p.lengths[j])[:, None]
                    base = (waves.short_basis(xi[modes], derivative) if kind
                            else waves.long_basis(xi[modes], b, derivative))
                    values[np.ix_(modes, at)] = k[modes, None] ** derivative * np.einsum(
                        "mxi,mi->mx", base, self.coefficients[modes, j])
        return values

    @property
    def length(self) -> float:
        """L (m) of the beam."""
        return self.beam.length

    def tip(self, derivative: int = 0) -> np.ndarray:
        """d^n Y / dx^n at the tip x = L, one value per mode."""
        return self(self.length, derivative)[:, 0]

    def participation(self) -> np.ndarray:
        """Gamma_n = <1, Y_n>: int rhoA Y_n dx + sum mass Y_n(x_mass), per mode (kg^1/2).

        The inertial load of a rigid translation of the clamp (and of the springs' ground,
        which moves with it). On each piece the fourth derivative of Y is k^4 Y, so the
        integral of Y is the jump of its third derivative over k^4.
        """
        p = self.beam.pieces
        out = np.empty(len(self.frequencies))
        for m, (k, short, c) in enumerate(zip(self.wave_numbers, self.short, self.coefficients,
                                              strict=True)):
            start, end = waves.end_values(k * p.lengths, short)
            third = np.einsum("ji,ji->j", end[:, 3] - start[:, 3], c)
            at_nodes = np.einsum("ji,ji->j", end[:, 0], c)
            out[m] = p.rhoA @ (third / k) + p.mass @ at_nodes
        return out

    def projection(self, field: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """<w, Y_n> of a field w(x) of the beam (m or m/s) on each mode (kg^1/2 per unit of w).

        The mass inner product: ``int rhoA w Y_n dx + sum mass w(x_k) Y_n(x_k) + sum
        rotary_inertia w'(x_k) Y_n'(x_k)``, the integral by Gauss quadrature on each piece
        (where Y_n is smooth; two panels per half wave, `waves.quadrature`, as a uniform beam's).
        ``field`` takes positions in [0, L] and returns the field there; the slope w' at a
        rotary inertia is from fourth-order one-sided differences of it (the mean of both
        sides inside the beam), step ``SLOPE_STEP`` / k with k the highest mode's wave number:
        error ~3e-12 of k |w| for a field smooth on the modes' scale. `participation` is this
        product for w = 1, in closed form.
        """
        p, L = self.beam.pieces, self.length
        rules = [waves.quadrature(length, 2.0 * float(np.max(k)))
                 for length, k in zip(p.lengths, self.wave_numbers.T, strict=True)]
        x = np.concatenate([start + nodes for start, (nodes, _) in zip(p.starts, rules,
                                                                       strict=True)])
        weights = np.concatenate([rhoA * w for rhoA, (_, w) in zip(p.rhoA, rules, strict=True)])
        ends = np.minimum(p.ends, L)  # the last end is L to the last bit
        step = SLOPE_STEP / float(np.max(self.wave_numbers))
        stencils = [_stencil(at, step, L) for at in ends[p.inertia > 0]]
        around = [np.clip(at + step * np.array(offsets), 0.0, L)  # (round-off past an end)
                  for at, (offsets, _) in zip(ends[p.inertia > 0], stencils, strict=True)]
        values = field(np.concatenate([x, ends, *around]))
        slopes, start = np.zeros(ends.size), x.size + ends.size
        for node, (offsets, weights_per_step) in zip(np.flatnonzero(p.inertia > 0), stencils,
                                                     strict=True):
            slopes[node] = np.dot(weights_per_step, values[start:start + len(offsets)]) / step
            start += len(offsets)
        return (self(x) @ (weights * values[:x.size])
                + self(ends) @ (p.mass * values[x.size:x.size + ends.size])
                + self(ends, 1) @ (p.inertia * slopes))

    def with_signs(self) -> StructureModes:
        """The same modes, each with a non-negative tip deflection (tip slope if that is 0)."""
        L = self.beam.length
        tip, slope = self(L)[:, 0], self(L, 1)[:, 0]
        scale = np.abs(self(self.beam.pieces.ends)).max(axis=1)
        reference = np.where(np.abs(tip) > 1e-8 * scale, tip, slope)
        signs = np.where(reference < 0, -1.0, 1.0)
        return dataclasses.replace(self, coefficients=self.coefficients * signs[:, None, None])

    def residual_flexibility(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The static flexibility these modes leave out (m/N), (len(x), len(y)).

        G(x, y) - sum_n Y_n(x) Y_n(y) / omega_n^2: what the contact's static correction needs.
        """
        modal = (self(x) / self.frequencies[:, None] ** 2).T @ self(y)
        return self.beam.flexibility(x, y) - modal

