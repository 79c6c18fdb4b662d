"""Natural frequencies and mode shapes of both phases (SciPy, evaluated once per geometry).

Every shape here is a clamped cantilever shape with zero bending moment at the tip,

    psi(xi) = tau (cosh xi - cos xi) - (sinh xi - sin xi),   xi = k x,  b = k l,
    tau = (sinh b + sin b) / (cosh b + cos b),

written with decaying exponentials only, ``psi = A e^(xi - b) + B e^-xi + C cos xi + D sin xi``,
so that it keeps all its digits at any ``b`` (the textbook form cancels ``e^b`` terms and loses
every digit past mode 7 or so; Goncalves, Brennan & Elliott, J. Sound Vib. 2007).

* Free phase: ``b`` is a root of ``cos b cosh b + 1 = 0``; the tip shear vanishes too.
* Contact phase: each beam carries ``C_i psi(k_i x)`` with ``omega = a_1 k_1^2 = a_2 k_2^2``;
  ``(C_1, C_2)`` is the null vector of the 2x2 tip system (equal tip displacements, tip shears
  that cancel). The roots are found in brackets given by interlacing: the contact phase is the
  free phase with one added constraint (tied tips), so the k-th contact frequency lies between
  the k-th and (k+1)-th of the merged, sorted free frequencies of both beams, where the tip
  receptance equation is monotone. No root is missed, close or double roots included.
"""

from __future__ import annotations

import dataclasses
import functools
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.brent import brentq  # not SciPy's: it costs 0.3 s of start-up (brent.py)
from impactbeams.params import MAX_MODES, Params
from impactbeams.structure.waves import quadrature

if TYPE_CHECKING:  # their modules load with the beams that need them (`Params.structure`)
    from impactbeams.structure import Cantilever, StructureModes
    from impactbeams.structure.user import MatrixStructure, ModalStructure, UserModes

_RTOL = 4 * np.finfo(float).eps
_COINCIDENT = 1e-12  # relative distance below which two free frequencies are one double pole


def sech(b: np.ndarray) -> np.ndarray:
    """1 / cosh(b) for b >= 0, as 2 e^-b / (1 + e^-2b): no overflow at any b."""
    e = np.exp(-np.asarray(b, dtype=float))
    return 2.0 * e / (1.0 + e * e)


def psi(b: np.ndarray, xi: np.ndarray, derivative: int = 0) -> np.ndarray:
    """d^n psi / d xi^n (n = ``derivative``, 0..3) of the shape with tip parameter ``b``.

    ``b`` and ``xi`` broadcast against each other; 0 <= xi <= b. Dimensionless.
    """
    b, xi = np.broadcast_arrays(np.asarray(b, dtype=float), np.asarray(xi, dtype=float))
    e = np.exp(-b)
    s, c = np.sin(b), np.cos(b)
    denominator = 1.0 + e * e + 2.0 * c * e  # 2 (cosh b + cos b) e^-b > 0
    tau = (1.0 - e * e + 2.0 * s * e) / denominator
    grow = (s - c - e) / denominator * np.exp(xi - b)  # (tau - 1)/2 e^xi, bounded
    decay = (tau + 1.0) / 2.0 * np.exp(-xi) * (-1.0) ** derivative
    # -tau cos xi + sin xi, differentiated n times: a rotation by n quarter turns
    phase = xi + derivative * np.pi / 2
    return grow + decay - tau * np.cos(phase) + np.sin(phase)


def psi_tip(b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """psi(b), psi'(b) and psi'''(b) (psi''(b) = 0), cancellation-free."""
    b = np.asarray(b, dtype=float)
    c, th, s = np.cos(b), np.tanh(b), sech(b)
    denominator = 1.0 + c * s
    value = 2.0 * (np.sin(b) - c * th) / denominator
    third = -2.0 * (s + c) / denominator
    return value, psi(b, b, 1), third


def psi_norm_squared(b: np.ndarray) -> np.ndarray:
    """Integral of psi^2 over [0, b], from the boundary-term identity valid for psi'''' = psi."""
    value, slope, third = psi_tip(b)
    return b / 4.0 * (value**2 - 2.0 * slope * third) + 0.75 * value * third


def cantilever_roots(n: int) -> np.ndarray:
    """First ``n`` roots b = k l of cos b cosh b + 1 = 0 (1.8751040687, 4.6940911330, ...)."""
    # cos b + sech b changes sign exactly once on each [(j - 1) pi, j pi]
    f = lambda b: np.cos(b) + sech(b)  # noqa: E731
    return np.array([brentq(f, max(j - 1, 0.5) * np.pi if j > 1 else 1.0, j * np.pi,
                            xtol=1e-300, rtol=_RTOL) for j in range(1, n + 1)])


@dataclasses.dataclass(frozen=True)
class BeamShapes:
    """Shapes ``Y_n(x) = amplitude_n psi(k_n x)`` of ``n`` modes on one beam.

    ``k``: wave numbers (1/m); ``amplitude``: scale factors (m^-1/2 kg^-1/2 mass-normalised);
    ``length``: beam length (m).
    """

    k: np.ndarray
    amplitude: np.ndarray
    length: float

    def __call__(self, x: np.ndarray, derivative: int = 0) -> np.ndarray:
        """d^n Y / dx^n at positions ``x`` (m), shape (modes, len(x))."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        k = self.k[:, None]
        values = psi(k * self.length, k * x[None, :], derivative)
        return self.amplitude[:, None] * k**derivative * values

    def tip(self, derivative: int = 0) -> np.ndarray:
        """d^n Y / dx^n at the tip x = length, one value per mode."""
        if derivative == 2:
            return np.zeros_like(self.k)
        b = self.k * self.length
        value, slope, third = psi_tip(b)
        psi_n = {0: value, 1: slope, 3: third}[derivative]
        return self.amplitude * self.k**derivative * psi_n


def deprecated_omega(owner: object) -> np.ndarray:
    """``owner.frequencies``, with the DeprecationWarning of the old attribute name ``omega``.

    ``omega`` alone names the forcing frequency everywhere (Params, TOML, CLI, netCDF); the
    natural frequencies are ``frequencies``.
    """
    warnings.warn(f"{type(owner).__name__}.omega is deprecated: use .frequencies (omega "
                  "names the forcing frequency)", DeprecationWarning, stacklevel=3)
    return owner.frequencies  # type: ignore[attr-defined]


@dataclasses.dataclass(frozen=True)
class FreeModes:
    """Cantilever modes of one beam alone: ``frequencies`` (rad/s) and mass-normalised shapes."""

    frequencies: np.ndarray
    shapes: BeamShapes

    @property
    def omega(self) -> np.ndarray:
        """Deprecated name of ``frequencies``."""
        return deprecated_omega(self)


@dataclasses.dataclass(frozen=True)
class ContactModes:
    """Modes of the contact phase: ``frequencies`` (rad/s), shapes on beam 1 and 2.

    Two beams: tied tips, mass-normalised in <u, v> = rhoA_1 int u_1 v_1 + rhoA_2 int u_2 v_2.
    A stop: the clamped-pinned beam 1 (tip held), no shapes on beam 2.
    """

    frequencies: np.ndarray
    beam1: BeamShapes
    beam2: BeamShapes

    @property
    def omega(self) -> np.ndarray:
        """Deprecated name of ``frequencies``."""
        return deprecated_omega(self)


@functools.lru_cache(maxsize=32)
def free_modes(EI: float, rhoA: float, length: float, n: int) -> FreeModes:
    """First ``n`` cantilever modes of a beam (EI in N m^2, rhoA in kg/m, length in m).

    Built once per process for each (EI, rhoA, length, n), which is all they depend on: a run
    asks for a beam's modes several times (counting the modes its contact needs, then its
    model). Shared, hence read-only.
    """
    b = cantilever_roots(n)
    k = b / length
    norm = np.sqrt(rhoA / k * psi_norm_squared(b))
    sign = np.sign(psi_tip(b)[0])  # tip displacement positive
    frequencies, amplitude = np.sqrt(EI / rhoA) * k**2, sign / norm
    for array in (frequencies, k, amplitude):
        array.flags.writeable = False
    return FreeModes(frequencies, BeamShapes(k, amplitude, length))


def participation(shapes: BeamShapes, rhoA: float) -> np.ndarray:
    """``Gamma_n = rhoA int_0^l Y_n dx`` of each closed-form shape on one beam (kg^1/2).

    From the beam equation ``Y'''' = k^4 Y``: ``int_0^l Y dx = (Y'''(l) - Y'''(0)) / k^4``
    (no quadrature); a free tip has ``Y'''(l) = 0``, a tied contact shape carries the shear.
    """
    third_at_clamp = shapes(np.zeros(1), derivative=3)[:, 0]
    return rhoA * (shapes.tip(3) - third_at_clamp) / shapes.k**4


# --- one beam's modal data: the seam between a beam and the engine ---------------------------


@dataclasses.dataclass(frozen=True)
class UniformBeam:
    """The textbook cantilever (EI in N m^2, rhoA in kg/m, length in m): closed forms.

    Each beam of a run is one of these or an `AttachedBeam`; both give the engine the same
    data: ``free_modes(n)``, ``tip_compliance`` (m/N), ``participation(shapes)`` (Gamma_n),
    ``projection(shapes, field)`` (<w, Y_n> of a field w), ``unit_tip_shape(x)``,
    ``static_mass_per_length`` (for <u, u> of that shape), ``own_damping_ratios(n)`` (its
    modes' damping of their own, added to the run's ``damping_ratio``) and ``closed_form``,
    ``continuous`` (fields along x) and ``mode_limit`` (the most modes).
    """

    EI: float
    rhoA: float
    length: float

    closed_form = True  # the tied law's contact modes and the quadratures assume it
    continuous = True
    mode_limit = MAX_MODES

    def free_modes(self, n: int) -> FreeModes:
        """The first ``n`` cantilever modes, in closed form."""
        return free_modes(self.EI, self.rhoA, self.length, n)

    def own_damping_ratios(self, n: int) -> np.ndarray:
        """None of its own: the run's ``damping_ratio`` damps its ``n`` modes (zeros)."""
        return np.zeros(n)

    @property
    def tip_compliance(self) -> float:
        """The tip compliance c = l^3 / (3 EI) (m/N)."""
        return self.length**3 / (3 * self.EI)

    def flexibility(self, x: float, y: float) -> float:
        """Deflection at ``x`` (m) under a unit force at ``y`` (m): the Green's function (m/N).

        ``G(x, y) = a^2 (3 b - a) / (6 EI)``, a = min(x, y), b = max(x, y); at the tip
        (x = y = l) the tip compliance itself, bit for bit.
        """
        if x == y == self.length:
            return self.tip_compliance
        a, b = min(x, y), max(x, y)
        return a * a * (3.0 * b - a) / (6.0 * self.EI)

    def participation(self, shapes: BeamShapes) -> np.ndarray:
        """Gamma_n of ``shapes`` (kg^1/2), in closed form (`participation`)."""
        return participation(shapes, self.rhoA)

    def projection(self, shapes: BeamShapes,
                   field: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """<w, Y_n> = rhoA int w Y_n dx of a field w(x) (m or m/s) on each of ``shapes``.

        Composite Gauss quadrature, two panels per half wave of the highest mode's square
        (kg^1/2 per unit of w); ``field`` takes positions in [0, l] (m).
        """
        x, weights = quadrature(self.length, 2.0 * float(np.max(shapes.k)))
        return self.rhoA * (shapes(x) @ (weights * field(x)))

    def unit_tip_shape(self, x: np.ndarray) -> np.ndarray:
        """u(x) = (3 l x^2 - x^3) / (2 l^3): static tip-load shape with unit tip deflection."""
        return (3 * self.length * x**2 - x**3) / (2 * self.length**3)

    @property
    def static_mass_per_length(self) -> float:
        """RhoA (kg/m): the unit tip-load shape's <u, u> is 33/140 of it times l."""
        return self.rhoA


@dataclasses.dataclass(frozen=True)
class AttachedBeam:
    """A stepped cantilever or one with attachments (`impactbeams.structure.Cantilever`).

    The same data as `UniformBeam`: exact modes by Wittrick-Williams and wave coefficients,
    built once per (beam, n) and process; the static data from its Green's function.
    """

    structure: Cantilever

    closed_form = False
    continuous = True
    mode_limit = MAX_MODES

    def free_modes(self, n: int) -> FreeModes:
        """The first ``n`` modes, mass-normalised with the attachments."""
        modes = _structure_modes(self.structure, n)
        return FreeModes(modes.frequencies, modes)

    def own_damping_ratios(self, n: int) -> np.ndarray:
        """None of its own: the run's ``damping_ratio`` damps its ``n`` modes (zeros)."""
        return np.zeros(n)

    @property
    def length(self) -> float:
        """L (m)."""
        return self.structure.length

    @property
    def tip_compliance(self) -> float:
        """w(L) under a unit tip force (m/N), the springs included."""
        return self.structure.tip_compliance

    def flexibility(self, x: float, y: float) -> float:
        """Deflection at ``x`` (m) under a unit force at ``y`` (m), the springs included (m/N).

        The tip compliance itself at the tip (x = y = L).
        """
        if x == y == self.length:
            return self.tip_compliance
        return float(self.structure.flexibility(x, y)[0, 0])

    def participation(self, shapes: StructureModes) -> np.ndarray:
        """Gamma_n = <1, Y_n> of ``shapes`` (kg^1/2), the point masses included."""
        return shapes.participation()

    def projection(self, shapes: StructureModes,
                   field: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """<w, Y_n> of a field w(x) (m or m/s), the point masses and rotary inertias included.

        `StructureModes.projection`: quadrature per piece, the slope at a rotary inertia by
        differences of ``field`` (kg^1/2 per unit of w).
        """
        return shapes.projection(field)

    def unit_tip_shape(self, x: np.ndarray) -> np.ndarray:
        """The static tip-load shape with unit tip deflection at ``x`` (m)."""
        return self.structure.unit_tip_shape(x)

    @property
    def static_mass_per_length(self) -> float:
        """The rhoA (kg/m) of the uniform beam of this length whose u has this <u, u>.

        <u, u> of the unit tip-load shape u with the attachments is 33/140 of it times L.
        """
        return self.structure.static_mass * 140.0 / (33.0 * self.length)


@dataclasses.dataclass(frozen=True)
class UserBeam(AttachedBeam):
    """Beam 1 as the user's own structure (`impactbeams.structure.user`).

    Matrices or modal data: the same data as `AttachedBeam` at its contact DOF; no fields.
    """

    structure: MatrixStructure | ModalStructure  # type: ignore[assignment]

    continuous = False

    @property
    def mode_limit(self) -> int:  # type: ignore[override]
        """The modes it has (its DOFs, or the modal data given), at most ``MAX_MODES``."""
        return min(MAX_MODES, self.structure.mode_limit)

    def own_damping_ratios(self, n: int) -> np.ndarray:
        """Its ``n`` lowest modes' own damping ratios; zeros if it has none.

        `Params` lets the run's ``damping_ratio`` damp modes without their own, else requires
        it 0.
        """
        ratios = _structure_modes(self.structure, n).damping_ratios
        return np.zeros(n) if ratios is None else ratios


@functools.lru_cache(maxsize=16)
def _structure_modes(structure: Cantilever | MatrixStructure | ModalStructure,
                     n: int) -> StructureModes | UserModes:
    """``structure.modes(n)``, once per process: a run asks for a beam's modes several times."""
    return structure.modes(n)


def beam(params: Params, which: int) -> UniformBeam | AttachedBeam:
    """Beam ``which`` (1 or 2) of ``params``, as the engine sees it.

    The one place that tells a textbook cantilever (closed forms) from a stepped beam or one
    with attachments and from the user's own structure (``params.structure1``).
    """
    if which == 1 and params.structure1 is not None:
        return UserBeam(params.structure1)
    if params.uniform_beam(which):
        i = str(which)
        return UniformBeam(getattr(params, "EI" + i), getattr(params, "rhoA" + i),
                           getattr(params, "l" + i))
    return AttachedBeam(params.structure(which))


def values_at(shapes: BeamShapes | StructureModes | UserModes, x: float,
              length: float) -> np.ndarray:
    """Each mode's deflection at ``x`` (m) of its beam of ``length`` (m), per unit coordinate.

    At the tip, ``shapes.tip()`` itself (the closed forms' tip values, bit for bit; a user
    structure's contact DOF).
    """
    if x == length:
        return shapes.tip()
    return shapes(np.array([x]))[:, 0]


def _merged_free_frequencies(params: Params, n: int) -> np.ndarray:
    """The n + 1 lowest cantilever frequencies of both beams together, sorted (rad/s)."""
    a1, a2 = params.wave_constant
    b = cantilever_roots(n + 1)
    merged = np.concatenate([a1 * (b / params.l1) ** 2, a2 * (b / params.l2) ** 2])
    return np.sort(merged)[: n + 1]


def _contact_secular(omega: float, params: Params) -> float:
    """(f_1 + f_2) E_1 A_1 E_2 A_2: zero at contact frequencies, smooth, no poles.

    f_i = N_i / (E_i A_i) is beam i's tip receptance, E_i = EI_i k_i^3,
    A_i = sech b_i + cos b_i (zero at cantilever frequencies), N_i = sin b_i - cos b_i tanh b_i.
    """
    a1, a2 = params.wave_constant
    k1, k2 = np.sqrt(omega / a1), np.sqrt(omega / a2)
    b1, b2 = k1 * params.l1, k2 * params.l2
    E1, E2 = params.EI1 * k1**3, params.EI2 * k2**3
    A1, A2 = sech(b1) + np.cos(b1), sech(b2) + np.cos(b2)
    N1, N2 = np.sin(b1) - np.cos(b1) * np.tanh(b1), np.sin(b2) - np.cos(b2) * np.tanh(b2)
    return (E1 * A1 * N2 + E2 * A2 * N1) / (E1 + E2)


def contact_frequencies(params: Params, n: int) -> np.ndarray:
    """First ``n`` natural frequencies of the contact phase (rad/s), one per interlacing bracket.

    Coincident free frequencies (equal tip-to-tip beams) are themselves contact frequencies;
    next to such a double pole the secular function has a simple zero at the bracket end, so
    that end is moved inside by a relative 1e-9 of the bracket width before root finding.
    Against a stop (``params.partner``): the clamped-pinned beam 1's, roots of tan b = tanh b.
    """
    if not params.partner.has_beam2:
        return clamped_pinned_modes(params.EI1, params.rhoA1, params.l1, n).frequencies
    poles = _merged_free_frequencies(params, n + 1)
    coincident = np.diff(poles) <= _COINCIDENT * poles[1:]
    roots = np.empty(n)
    for j in range(n):
        lo, hi = poles[j], poles[j + 1]
        if coincident[j]:
            roots[j] = 0.5 * (lo + hi)
            continue
        inset = 1e-9 * (hi - lo)
        lo_eval = lo + inset if j > 0 and coincident[j - 1] else lo
        hi_eval = hi - inset if coincident[j + 1] else hi
        f_lo = _contact_secular(lo_eval, params)
        f_hi = _contact_secular(hi_eval, params)
        if np.sign(f_lo) == np.sign(f_hi):
            raise RuntimeError(
                f"contact root {j + 1} not bracketed in [{lo!r}, {hi!r}] rad/s "
                f"(secular values {f_lo!r}, {f_hi!r}): please report these parameters")
        roots[j] = brentq(_contact_secular, lo_eval, hi_eval, args=(params,), xtol=1e-300,
                          rtol=_RTOL)
    return roots


def _tip_null_vector(omega: float, params: Params) -> np.ndarray:
    """Amplitudes (C_1, C_2) of the contact shape on each beam at frequency ``omega``.

    They make the tip displacements equal, C_1 psi_1(b_1) = C_2 psi_2(b_2), and the tip shears
    cancel, EI_1 k_1^3 C_1 psi_1'''(b_1) + EI_2 k_2^3 C_2 psi_2'''(b_2) = 0: the right singular
    vector of the smallest singular value of that 2x2 system.
    """
    a1, a2 = params.wave_constant
    k1, k2 = np.sqrt(omega / a1), np.sqrt(omega / a2)
    w1, _, v1 = psi_tip(k1 * params.l1)
    w2, _, v2 = psi_tip(k2 * params.l2)
    E1, E2 = params.EI1 * k1**3, params.EI2 * k2**3
    scale = max(E1, E2)  # both rows O(1): psi and psi''' are bounded at the tip
    system = np.array([[w1, -w2], [E1 * v1 / scale, E2 * v2 / scale]])
    return np.linalg.svd(system)[2][-1]


def pinned_roots(n: int) -> np.ndarray:
    """First ``n`` roots b = k l of tan b = tanh b (3.9266023120, 7.0685827500, ...).

    The clamped-pinned beam's: psi(b) = 0, the tip held. sin b - cos b tanh b changes sign
    once on each [j pi, (j + 1/2) pi].
    """
    f = lambda b: np.sin(b) - np.cos(b) * np.tanh(b)  # noqa: E731
    return np.array([brentq(f, j * np.pi, (j + 0.5) * np.pi, xtol=1e-300, rtol=_RTOL)
                     for j in range(1, n + 1)])


def clamped_pinned_modes(EI: float, rhoA: float, length: float, n: int) -> ContactModes:
    """The contact phase against a stop: first ``n`` modes of beam 1 with its tip held.

    Shapes ``C psi(k x)`` with psi(b) = 0 (psi''(b) = 0 already); mass-normalised, beam 1's
    amplitude positive; no shapes on beam 2.
    """
    b = pinned_roots(n)
    k = b / length
    amplitude = 1.0 / np.sqrt(rhoA / k * psi_norm_squared(b))
    empty = BeamShapes(np.zeros(0), np.zeros(0), 0.0)
    return ContactModes(np.sqrt(EI / rhoA) * k**2, BeamShapes(k, amplitude, length), empty)


def contact_modes(params: Params, n: int) -> ContactModes:
    """First ``n`` mass-normalised modes of the contact phase (tied tips, or a stop)."""
    if not params.partner.has_beam2:
        return clamped_pinned_modes(params.EI1, params.rhoA1, params.l1, n)
    omega = contact_frequencies(params, n)
    a1, a2 = params.wave_constant
    k1, k2 = np.sqrt(omega / a1), np.sqrt(omega / a2)
    C = np.array([_tip_null_vector(w, params) for w in omega])
    C1, C2 = C[:, 0], C[:, 1]
    mass = (params.rhoA1 / k1 * C1**2 * psi_norm_squared(k1 * params.l1)
            + params.rhoA2 / k2 * C2**2 * psi_norm_squared(k2 * params.l2))
    tip = C1 * psi_tip(k1 * params.l1)[0]
    # sign: tip displacement positive; for tip-node modes, beam 1's amplitude positive
    reference = np.where(np.abs(tip) > 1e-8 * np.hypot(C1, C2), tip, C1)
    scale = np.sign(reference) / np.sqrt(mass)
    return ContactModes(omega, BeamShapes(k1, C1 * scale, params.l1),
                        BeamShapes(k2, C2 * scale, params.l2))
