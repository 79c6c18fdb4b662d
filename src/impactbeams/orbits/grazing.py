"""Grazing of the non-impacting periodic orbit, in closed form from the linear response.

Below contact every free coordinate is a linear oscillator driven at the one frequency Omega
(docs/model.md): on the steady (periodic) orbit each mode is ``Im(P_n e^(i Omega t))``,
``P_n = A_n / D_n``, ``D_n = omega_n^2 - Omega^2 + 2 i zeta omega_n Omega``, and the gap

    g(t) = Delta + Im(G e^(i Omega t)),   G = S + sum_n w_n P_n

(``w_n`` the coordinates' gap weights, ``S`` the gap's explicit harmonic: the tip force's
quasi-static part and the clamps' relative motion) is a trigonometric polynomial of degree
one. Its minimum over a period, ``Delta - |G|``, is where the rate ``Re(G e^(i Omega t))``
vanishes rising, ``Omega t = -pi/2 - arg G`` (mod 2 pi): exact, no sampling. The model has no
static load (no gravity, no preload), so nothing shifts the mean gap from ``Delta``.

Every drive enters G linearly: ``G = F0 G_F + U0 G_U`` with ``G_F``, ``G_U`` the phasors per
unit tip force (m/N) and per unit base amplitude (m/m), and G does not depend on the
clearance. The grazing drive or clearance at each Omega is therefore a closed form
(`grazing_curve`); at fixed drives the grazing frequencies are the roots of
``Delta - |G(Omega)|``, bracketed on a grid and refined by Brent's method
(`grazing_frequencies`).

With several contacts each has its own gap on the same linear orbit, ``Delta_j +
Im(G_j e^(i Omega t))`` (its own run's weights and harmonic, `Params.each_contact`): the orbit
first touches where the first of them does, the smallest of their grazing drives, the
largest ``|G_j| - Delta_j`` in Omega; one contact's clearance grazes at its ``|G_j|`` where
no other gap is closed already.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq

from impactbeams.contact import build_free_phase
from impactbeams.drive import base_participation
from impactbeams.params import (
    CONTACTS,
    GRAZING_BRACKETS,
    MAX_MODES,
    ParameterError,
    Params,
    check_parameter,
    check_part_field,
    contact_field,
    named_attributes,
    part_field,
    require,
    require_finite,
    require_integer,
    require_type,
    with_parameter,
)
from impactbeams.variables import (
    GRAZING_PARAMETERS,
    attributes,
    global_attributes,
    parameter_attributes,
    validate,
)

if TYPE_CHECKING:
    import xarray as xr

POINT = "grazing_point"


@dataclasses.dataclass(frozen=True)
class SteadyGap:
    """The gap on the non-impacting steady orbit, ``g(t) = clearance + Im(phasor e^(i omega t))``.

    Attributes (SI units): ``clearance`` Delta (m), ``phasor`` G (m, complex), ``omega`` the
    forcing frequency Omega (rad/s).
    """

    clearance: float
    phasor: complex
    omega: float

    @property
    def minimum(self) -> float:
        """The smallest gap over a forcing period, ``Delta - |G|`` (m); <= 0: the orbit touches."""
        return self.clearance - abs(self.phasor)

    @property
    def phase_of_minimum(self) -> float:
        """The forcing phase ``Omega t`` in [0, 2 pi) where the gap is smallest (rad).

        The root of the rate ``Omega Re(G e^(i Omega t))`` where the gap turns from falling to
        rising: ``Omega t + arg G = -pi/2``.
        """
        return float(phase_of_minimum(self.phasor))

    @property
    def time_of_minimum(self) -> float:
        """The time in [0, 2 pi / Omega) of the smallest gap (s), forcing phase 0 at t = 0."""
        return self.phase_of_minimum / self.omega

    def __call__(self, t: ArrayLike) -> np.ndarray:
        """The gap (m) at times ``t`` (s)."""
        return self.clearance + np.imag(self.phasor * np.exp(1j * self.omega * np.asarray(t)))


class LinearGap:
    """The gap's phasor per unit drive of a configuration, at any forcing frequency.

    Built once per ``(params, n_modes)`` (the free modes and the drives' modal data); the
    phasors at many frequencies are then array sums. ``params``' own ``omega`` is not used.
    """

    def __init__(self, params: Params, n_modes: int) -> None:
        require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
        require_integer("n_modes", n_modes, 1, MAX_MODES)
        free = build_free_phase(params, n_modes)
        moves1, moves2 = params.mount.clamps
        self.params = params
        self.frequencies = free.frequencies
        self.damping_ratios = free.damping_ratios(params.damping_ratio)  # zeta_n
        self.weights = free.gap_weights        # the gap's weight of each free coordinate
        self.force_drive = free.drive          # b_n: Y_1n(l1) / omega_n^2 (m kg^1/2 / N)
        self.base_drive = base_participation(params, free)  # Gamma_n (kg^1/2)
        self.force_harmonic = -free.gap_compliance  # S per unit F0: -s G1(x1, l1), -c1 (m/N)
        # S per unit U0: the clamps' relative motion, seen from the contact's side
        self.base_harmonic = free.side * (moves1 - moves2)

    def per_unit(self, omega: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(G_F, G_U)`` at each Omega (rad/s): the gap's phasor per N of F0, per m of U0.

        A mode's drive is ``A = F0 Omega b (-Omega + 2 i zeta omega_n) + U0 Gamma Omega^2``
        (`impactbeams.kernels.drive.mode_drive`).
        """
        big = np.asarray(omega, dtype=float)[..., None]
        wn, zeta = self.frequencies, self.damping_ratios
        response = self.weights / (wn**2 - big**2 + 2j * zeta * wn * big)  # w_n / D_n
        force = big * self.force_drive * (-big + 2j * zeta * wn)
        base = self.base_drive * big**2
        return (self.force_harmonic + np.sum(response * force, axis=-1),
                self.base_harmonic + np.sum(response * base, axis=-1))

    def phasor(self, omega: ArrayLike) -> np.ndarray:
        """G at each Omega (rad/s) for ``params``' drives F0 and U0 (m, complex)."""
        force, base = self.per_unit(omega)
        p = self.params
        return p.force_amplitude * force + p.base_amplitude * base

    def check_frequencies(self, omega: ArrayLike) -> np.ndarray:
        """``omega`` as an array of positive, finite frequencies with a steady orbit (rad/s).

        Omega = 0 drives nothing; an undamped mode driven exactly at its natural frequency has
        no steady orbit.
        """
        try:
            values = np.atleast_1d(np.asarray(omega, dtype=float))
        except (TypeError, ValueError):  # not numbers: refused below
            values = np.empty((0, 0))
        require("omega", omega, values.ndim == 1 and values.size > 0,
                "must be a positive frequency or a 1-d sequence of them", "rad/s")
        bad = values[~(np.isfinite(values) & (values > 0.0))]
        require("omega", float(bad[0]) if bad.size else 0.0, bad.size == 0,
                "must be finite and > 0: Omega = 0 drives nothing", "rad/s")
        undamped = self.frequencies[self.damping_ratios == 0.0]
        resonant = values[np.isin(values, undamped)]
        require("omega", float(resonant[0]) if resonant.size else 0.0, resonant.size == 0,
                "is a natural frequency and damping_ratio = 0: an undamped mode driven at "
                "resonance has no steady orbit", "rad/s")
        return values


def contact_gaps(params: Params, n_modes: int) -> tuple[LinearGap, ...]:
    """Each contact's `LinearGap`: its own run's (`Params.each_contact`; one free phase)."""
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    return tuple(LinearGap(run, n_modes) for run in params.each_contact())


def check_grazing_parameter(params: Params, parameter: str, others: tuple[str, ...] = (),
                            ) -> None:
    """``parameter`` has a grazing curve: a drive, or the clearance (one contact's, of several).

    With several contacts each gives its own clearance: ``contacts.INDEX.clearance``.
    ``others``: more names the caller takes (the command line's ``omega``).
    """
    if part_field(parameter) is not None:
        check_part_field(params, "parameter", parameter)
        return
    count = len(params.each_contact())
    field = contact_field(parameter)
    if count == 1:
        named, allowed = (*GRAZING_PARAMETERS, *others), ""
    else:
        named = (*(name for name in GRAZING_PARAMETERS if name != "clearance"), *others)
        allowed = (f" or one contact's clearance, '{CONTACTS}.INDEX.clearance' with INDEX from 0 "
                   f"to {count - 1} (with {count} contacts each gives its own)")
    require("parameter", parameter, parameter in named or (
        count > 1 and field is not None and field[0] < count and field[1] == "clearance"),
        f"must be one of {', '.join(map(repr, named))}{allowed}, or a part's field "
        "'attachments1.INDEX.FIELD' or 'segments1.INDEX.FIELD' (with within=(low, high))")


def steady_gap(params: Params, n_modes: int) -> SteadyGap:
    """The gap of ``params``' non-impacting steady orbit at its ``omega``, exactly.

    Its smallest value over a period is ``SteadyGap.minimum`` (m), reached at
    ``SteadyGap.time_of_minimum`` (s); the orbit is that of the linear free phase whether or
    not it touches (``minimum <= 0``: it does, and the true orbit impacts). ``n_modes``: free
    modes per beam, as in `impactbeams.simulate`. Every counterpart and drive: tip force,
    base motion of either or both clamps, or both drives. The uplifts and ``start`` do not
    enter: they set a run's start, not its periodic orbit.
    """
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    if params.several_contacts:
        raise ParameterError(
            f"{CONTACTS}: {len(params.contacts)} contacts are not allowed in steady_gap, which "
            "gives one gap: the gap of contact INDEX is steady_gap(params.each_contact()[INDEX], "
            "n_modes)")
    linear = LinearGap(params, n_modes)
    (omega,) = linear.check_frequencies(params.omega)
    return SteadyGap(params.clearance, complex(linear.phasor(omega)), float(omega))


def grazing_values(linear: LinearGap, parameter: str,
                   omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The value of ``parameter`` at which the orbit first touches at each Omega, and G there.

    The clearance: ``|G|``. A drive x with the rest of G fixed, ``G = x g + r``: the positive
    root of ``|x g + r| = Delta``, unique while ``|r| < Delta`` (NaN where the other drive
    already closes the gap), in the form without cancellation. Values in SI units, G in m.
    """
    force, base = linear.per_unit(omega)
    p = linear.params
    if parameter == "clearance":
        touching = p.force_amplitude * force + p.base_amplitude * base
        return np.abs(touching), touching
    unit, rest = (force, p.base_amplitude * base) if parameter == "force_amplitude" else (
        base, p.force_amplitude * force)
    a = np.abs(unit) ** 2
    b = np.real(unit * np.conj(rest))
    c = np.abs(rest) ** 2 - p.clearance**2  # < 0 where the other drive leaves a gap
    root = np.sqrt(np.maximum(b * b - a * c, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        x = np.where(c < 0.0, np.where(b > 0.0, -c / (b + root), (root - b) / a), np.nan)
    return x, x * unit + rest


def phase_of_minimum(phasor: ArrayLike) -> np.ndarray:
    """The forcing phase in [0, 2 pi) where ``Im(G e^(i Omega t))`` is least, per G (rad)."""
    return (-0.5 * math.pi - np.angle(phasor)) % (2.0 * math.pi)


def first_grazing(gaps: tuple[LinearGap, ...], parameter: str, omega: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`grazing_values` of the contact of ``gaps`` that touches first, and which it is.

    A drive: the smallest of the contacts' grazing values (NaN where the other drive alone
    already closes a gap: the orbit touches at no drive); one contact's clearance
    (``contacts.INDEX.clearance``): that contact's, NaN where another gap is closed at any
    clearance of it. The contact's index, -1 where the value is NaN.
    """
    field = contact_field(parameter)
    if field is None:
        values, touching = (np.array(rows) for rows in zip(
            *(grazing_values(gap, parameter, omega) for gap in gaps), strict=True))
    else:  # the others' gaps do not depend on it: closed (NaN) or never touched (inf)
        touching = np.array([gap.phasor(omega) for gap in gaps])
        values = np.where(np.abs(touching) < [[gap.params.clearance] for gap in gaps],
                          np.inf, np.nan)
        values[field[0]] = np.abs(touching[field[0]])
    closed = np.any(np.isnan(values), axis=0)
    contact = np.where(closed, -1, np.argmin(np.where(np.isnan(values), np.inf, values),
                                             axis=0))
    columns = np.arange(omega.size)
    first = np.where(closed, np.nan, values[contact, columns])
    return first, np.where(closed, np.nan, touching[contact, columns]), contact


def grazing_curve(params: Params, n_modes: int, parameter: str, omega: ArrayLike,
                  within: tuple[float, float] | None = None) -> xr.Dataset:
    """The grazing curve in the plane (Omega, ``parameter``): where the orbit first touches.

    At each forcing frequency of ``omega`` (rad/s), the value of ``parameter`` (N for
    ``force_amplitude``, m for ``base_amplitude`` or ``clearance``) at which the
    non-impacting steady orbit of ``params`` (``n_modes`` free modes per beam) touches: below
    it (above it, for the clearance) the orbit has no contact. Closed form (module
    docstring): the response is linear in each drive and does not depend on the clearance;
    a drive's grazing value keeps the other drive at ``params``' value, and is NaN where that
    drive alone already closes the gap. With several contacts the first contact's to touch
    (`first_grazing`; the clearance one contact's, ``contacts.INDEX.clearance``).

    Returns a Dataset along ``grazing_point``, one point per frequency: the coordinate
    ``omega``, the variables ``parameter`` and ``grazing_phase`` (the forcing phase of the
    touch), with several contacts ``grazing_contact`` (which one touches), the fixed
    parameters as attributes. A curve continued in two parameters is checked against it
    point by point: `grazing_curve` at the continued points' frequencies.

    A part's field (``attachments1.INDEX.FIELD``: a mass, a spring's stiffness, a place;
    ``segments1.INDEX.FIELD``: a segment's length, EI or rhoA)
    moves the modes, so G is no closed form in it: at each Omega its grazing value is the
    first root of the least gap from ``within`` = (low, high) upward (where the orbit starts
    or stops touching), bracketed on ``FIELD_BRACKETS`` values of the field (each its own
    modes) and refined by Brent's method; NaN where no bracket changes sign.
    """
    gaps = contact_gaps(params, n_modes)
    check_grazing_parameter(params, parameter)
    frequencies = gaps[0].check_frequencies(omega)
    if part_field(parameter) is not None:
        values, touching, contact = field_grazing(params, n_modes, parameter, frequencies,
                                                  within)
        method = (f"first root of the least gap Delta - |G| in {parameter} from {within[0]}:"
                  f" a sign change on {FIELD_BRACKETS} values refined by Brent's method")
    else:
        require("within", within, within is None, f"is for a part's field: {parameter} has "
                "a closed form (leave it None)")
        values, touching, contact = first_grazing(gaps, parameter, frequencies)
        method = ("closed form: the steady gap's amplitude |G|, linear in each drive, equal "
                  "to the clearance")
    return _dataset(params, n_modes, parameter, frequencies, values, touching, contact, method)


# the values of a part's field on which its grazing is bracketed (each value its own modes)
FIELD_BRACKETS = 17


def field_grazing(params: Params, n_modes: int, parameter: str, omega: np.ndarray,
                  within: object) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`first_grazing`'s values in a part's field ``parameter`` (`grazing_curve`'s docstring).

    The least gap of all contacts at each Omega is a function of the field through the
    modes alone (the drives and clearances fixed): its first sign change on an even grid of
    ``within`` is refined by `scipy.optimize.brentq` to 4 machine epsilons of the field.
    """
    require("within", within, isinstance(within, (tuple, list)) and len(within) == 2,
            f"give the range of {parameter} to search, within=(low, high)")
    low, high = (require_finite("within", value) for value in within)
    require("within", within, low < high, "is empty: need low < high")
    for value in (low, high):
        check_parameter(parameter, value)
    grid = np.linspace(low, high, FIELD_BRACKETS)
    least = np.array([_least_gap(_gaps_at(params, n_modes, parameter, value), omega).min(axis=0)
                      for value in grid])  # (field value, Omega)
    values = np.full(omega.size, np.nan)
    touching = np.full(omega.size, np.nan, dtype=complex)
    contact = np.full(omega.size, -1)
    for i, frequency in enumerate(omega):
        touches = least[:, i] <= 0.0
        changed = np.flatnonzero(touches != touches[0])
        if not changed.size:
            continue  # touched throughout the range, or nowhere in it

        def gap(value: float, at: np.ndarray = omega[i:i + 1]) -> float:
            return float(_least_gap(_gaps_at(params, n_modes, parameter, value), at).min())

        k = int(changed[0])
        values[i] = brentq(gap, grid[k - 1], grid[k], xtol=1e-300,
                           rtol=4 * np.finfo(float).eps)
        gaps = _gaps_at(params, n_modes, parameter, values[i])
        contact[i] = int(np.argmin(_least_gap(gaps, np.array([frequency]))[:, 0]))
        touching[i] = complex(gaps[contact[i]].phasor(frequency))
    return values, touching, contact


def _gaps_at(params: Params, n_modes: int, parameter: str,
             value: float) -> tuple[LinearGap, ...]:
    """Each contact's `LinearGap` with ``parameter`` (a part's field) set to ``value``."""
    return contact_gaps(with_parameter(params, parameter, float(value)), n_modes)


def _least_gap(gaps: tuple[LinearGap, ...], omega: np.ndarray) -> np.ndarray:
    """Each contact's smallest gap ``Delta_j - |G_j|`` (m) at each Omega, rows by contact."""
    return np.array([gap.params.clearance - np.abs(gap.phasor(omega)) for gap in gaps])


def grazing_frequencies(params: Params, n_modes: int, low: float, high: float,
                        brackets: int = GRAZING_BRACKETS) -> xr.Dataset:
    """The forcing frequencies in [low, high] (rad/s) where ``params``' orbit just touches.

    The roots of the smallest gap ``Delta - |G(Omega)|`` (m) at ``params``' drives and
    clearance (with several contacts the smallest of theirs): bracketed on ``brackets``
    evenly spaced frequencies, each sign change refined by Brent's method
    (`scipy.optimize.brentq`, to 4 machine epsilons of Omega). Two roots closer together
    than the grid's step (a curve just touching the line of fixed drive) can be missed: a
    finer grid finds them. Returns the `grazing_curve` Dataset of the roots, in increasing
    Omega, with the drives and clearance as attributes.
    """
    gaps = contact_gaps(params, n_modes)
    require_integer("brackets", brackets, 2)
    low, high = require_finite("low", low, "rad/s"), require_finite("high", high, "rad/s")
    require("high", high, low < high, f"the range [{low!r}, {high!r}] is empty: need high > low",
            "rad/s")
    grid = gaps[0].check_frequencies(np.linspace(low, high, brackets))

    def smallest_gap(omega: float) -> float:
        return float(np.min(_least_gap(gaps, np.array([omega]))))

    least = _least_gap(gaps, grid).min(axis=0)
    roots = [brentq(smallest_gap, a, b, xtol=1e-300, rtol=4 * np.finfo(float).eps)
             for a, b, ga, gb in zip(grid[:-1], grid[1:], least[:-1], least[1:], strict=True)
             if ga * gb < 0.0]
    roots = np.array(sorted([*roots, *grid[least == 0.0]]))
    contact = np.argmin(_least_gap(gaps, roots), axis=0)
    touching = np.array([gaps[j].phasor(root) for j, root in zip(contact, roots, strict=True)],
                        dtype=complex)
    return _dataset(params, n_modes, "omega", roots, roots, touching, contact,
                    f"roots of Delta - |G(Omega)|: sign changes on {brackets} evenly spaced "
                    "frequencies refined by Brent's method")


def _dataset(params: Params, n_modes: int, parameter: str, omega: np.ndarray,
             values: np.ndarray, touching: np.ndarray, contact: np.ndarray,
             method: str) -> xr.Dataset:
    """A grazing curve's points along ``grazing_point`` (registry: impactbeams.variables).

    ``contact``: which contact touches at each point, a variable with several contacts.
    """
    import xarray as xr

    coords = {POINT: (POINT, np.arange(omega.size, dtype=np.int64), attributes(POINT)),
              "omega": (POINT, omega, parameter_attributes("omega"))}
    # the grazing value is data, not a coordinate: NaN where the other drive closes the gap
    data = {} if parameter == "omega" else {
        parameter: (POINT, values, named_attributes(parameter))}
    data["grazing_phase"] = (POINT, phase_of_minimum(touching), attributes("grazing_phase"))
    if params.several_contacts:
        data["grazing_contact"] = (POINT, contact.astype(np.int32), attributes(
            "grazing_contact"))
    fixed = {name: value for name, value in params.as_dict().items()
             if name not in ("omega", parameter)}
    dataset = xr.Dataset(
        data, coords=coords,
        attrs=global_attributes(
            "Grazing curve of the non-impacting steady orbit (linear response)",
            f"grazing curve in (omega, {parameter})", fixed, n_modes=n_modes,
            grazing_parameter=parameter, grazing_method=method))
    validate(dataset)
    return dataset
