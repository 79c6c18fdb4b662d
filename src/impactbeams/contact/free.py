"""The free phase: each beam's cantilever modes side by side.

Quasi-static parts (docs/model.md) are multiples of the unit tip-load shapes
``u_i(x) = (3 l_i x^2 - x^3) / (2 l_i^3)`` (unit tip deflection), with ``c_i = l_i^3 / (3 EI_i)``;
in the free phase ``y_1s = -c_1 F(t) u_1``, ``y_2s = 0``. Projections of ``u_i`` use the exact
boundary identity ``rhoA int u Y = (EI Y'''(l) + Y(l) / c) / omega^2`` (integration by parts,
since u'''' = 0 and u''(l) = Y''(l) = 0), which for a free mode (Y'''(l) = 0) is
``Y(l) / (c omega^2)``. With attachments (`impactbeams.modes.AttachedBeam`) u_i is the beam's
own static tip-load shape and c_i its tip compliance; the projection is again
``<u, Y_n> = Y_n(l) / (c omega_n^2)`` (the mass product and the strain energy of the beam with
its attachments: u is the static response to a tip force 1 / c), so nothing else changes.

Against a stop (``counterpart = "stop"``) beam 2 has no modes and no compliance (c2 = 0): the
coordinates are beam 1's ``n`` modes only.

The contact acts at ``Params.contact_point`` (x1 on beam 1, x2 on beam 2; the tips by default),
from ``Params.side`` (s = +1 below beam 1, -1 above): the gap is
``g = clearance + s (y1(x1) - y2(x2))``, whose weights on the coordinates are
``s (Y_1n(x1) - Y_2n(x2))`` and whose quasi-static part under the tip force is
``-s G1(x1, l1) F`` (G the beam's static Green's function). At the tips these are the tip
values and c1 themselves, bit for bit.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from impactbeams.modes import FreeModes, beam, deprecated_omega, values_at
from impactbeams.params import Params, require_integer, require_one_contact, require_type
from impactbeams.structure.waves import quadrature

__all__ = ["FreePhase", "build_free_phase", "quadrature", "unit_tip_shape"]


def unit_tip_shape(length: float, x: np.ndarray) -> np.ndarray:
    """u(x) = (3 l x^2 - x^3) / (2 l^3): static tip-load shape with unit tip deflection."""
    return (3 * length * x**2 - x**3) / (2 * length**3)


@dataclasses.dataclass(frozen=True)
class FreePhase:
    """Free-phase coordinates: beam 1's ``n`` modes, then beam 2's (none against a stop).

    Closed forms only (no quadrature), so that a first-impact map pays for nothing else.

    Attributes (SI units):
        beam1, beam2: cantilever modes of each beam (beam2 empty against a stop).
        frequencies: natural frequencies (rad/s).
        tip1, tip2: tip displacement of each coordinate's shape on beam 1 / beam 2 (zero for
            the other beam's modes).
        unit1, unit2: <u_1, Y_n>, <u_2, Y_n> = Y_n(l_i) / (c_i omega_n^2) (kg^1/2; zero on
            the other beam's modes).
        drive: b_n with q_n'' + omega_n^2 q_n = b_n F''(t): Y_1n(l1) / omega_1n^2, 0 on beam 2.
        static_shift: <s, Y_n> = c_1 unit1 - c_2 unit2.
        point1, point2: each coordinate's deflection at the contact point of beam 1 / beam 2
            (x1, x2; zero for the other beam's modes): the tips' values by default.
        gap_weights: the gap's weight of each coordinate, s (point1 - point2) (m per unit).
        gap_compliance: s G1(x1, l1) (m/N): the gap's quasi-static part is -gap_compliance F.
        point_compliance: (G1(x1, x1), G2(x2, x2)) (m/N): each beam's static flexibility at
            its contact point (c1, c2 at the tips; G2 = 0 against a stop).
        tip_transfer: (G1(l1, x1), G2(l2, x2)) (m/N): each tip's deflection under a unit force
            at its beam's contact point.
        side: s, +1.0 (the counterpart below beam 1) or -1.0 (above).
        own_damping: each coordinate's damping ratio of its own (a user structure's,
            `impactbeams.modes.UserBeam`), zero for the beams': see ``damping_ratios``.
    """

    beam1: FreeModes
    beam2: FreeModes
    frequencies: np.ndarray
    tip1: np.ndarray
    tip2: np.ndarray
    unit1: np.ndarray
    unit2: np.ndarray
    drive: np.ndarray
    static_shift: np.ndarray
    point1: np.ndarray
    point2: np.ndarray
    gap_weights: np.ndarray
    gap_compliance: float
    point_compliance: tuple[float, float]
    tip_transfer: tuple[float, float]
    side: float
    own_damping: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        """Deprecated name of ``frequencies``."""
        return deprecated_omega(self)

    def damping_ratios(self, damping_ratio: float) -> np.ndarray:
        """Each coordinate's damping ratio zeta_n: its own plus the run's ``damping_ratio``.

        `Params` allows a ``damping_ratio`` > 0 only on modes with none of their own, so each
        is one or the other, exactly (0 + zeta is zeta: the beams' ratios bit for bit).
        """
        return self.own_damping + damping_ratio

    def damping_named(self, damping_ratio: float) -> str:
        """The modes' damping as a refusal names it: structure1's own or ``damping_ratio``.

        `Params` allows one or the other; the own damping by its largest ratio.
        """
        if np.any(self.own_damping):
            return (f"structure1's own damping (zeta_n up to {np.max(self.own_damping):.3g}; "
                    "damping_ratio is 0 with it)")
        return f"damping_ratio = {damping_ratio!r}"

    @property
    def modes_per_beam(self) -> tuple[int, int]:
        """Coordinates on beam 1 and on beam 2 (0 against a stop)."""
        return self.beam1.frequencies.size, self.beam2.frequencies.size


def build_free_phase(params: Params, n_modes: int) -> FreePhase:
    """Free-phase modal data: ``n_modes`` cantilever modes per beam (beam 1's only at a stop).

    Each beam's modes come from its `impactbeams.modes.beam`: closed forms or attachments.
    """
    n = _checked(params, n_modes)
    p = params
    c1, c2 = p.tip_compliance
    beam1 = beam(p, 1).free_modes(n)
    beam2 = beam(p, 2).free_modes(n if p.partner.has_beam2 else 0)
    n2 = beam2.frequencies.size
    frequencies = np.concatenate([beam1.frequencies, beam2.frequencies])
    tip1 = np.concatenate([beam1.shapes.tip(), np.zeros(n2)])
    tip2 = np.concatenate([np.zeros(n), beam2.shapes.tip()])
    unit1 = tip1 / (c1 * frequencies**2)
    # a stop: no beam-2 coordinates and c2 = 0 (an empty 0/0 would be fine, but say it)
    unit2 = tip2 / (c2 * frequencies**2) if n2 else np.zeros(n)
    (x1, x2), side = p.contact_point, p.side.sign
    cantilever1, cantilever2 = beam(p, 1), beam(p, 2)
    point1 = np.concatenate([values_at(beam1.shapes, x1, p.l1), np.zeros(n2)])
    point2 = np.concatenate([np.zeros(n), values_at(beam2.shapes, x2, p.l2) if n2
                             else np.zeros(0)])
    compliance2 = cantilever2.flexibility(x2, x2) if n2 else 0.0
    transfer2 = cantilever2.flexibility(p.l2, x2) if n2 else 0.0
    return FreePhase(beam1, beam2, frequencies, tip1, tip2, unit1, unit2,
                     drive=tip1 / frequencies**2, static_shift=c1 * unit1 - c2 * unit2,
                     point1=point1, point2=point2, gap_weights=side * (point1 - point2),
                     gap_compliance=side * cantilever1.flexibility(x1, p.l1),
                     point_compliance=(cantilever1.flexibility(x1, x1), compliance2),
                     tip_transfer=(cantilever1.flexibility(p.l1, x1), transfer2), side=side,
                     own_damping=np.concatenate([cantilever1.own_damping_ratios(n),
                                                 cantilever2.own_damping_ratios(n2)]))


def _checked(params: Params, n_modes: int) -> int:
    """``n_modes`` as an int, once both arguments are checked (ParameterError, TypeError)."""
    n = require_integer("n_modes", n_modes, 1)
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    require_one_contact(params, "a run's free phase (one gap)")
    return n
