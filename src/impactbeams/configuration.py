"""A configuration's variants as objects: contact law, counterpart, contact side, shaker mount.

`Params` keeps each as a name (``contact_law``, ``counterpart``, ``contact_side``, ``shaker``:
the flat keys of TOML files, the command line and Datasets) and hands out its object
(``Params.law``, ``Params.partner``, ``Params.side``, ``Params.mount``). What the code does
differently for each variant is an attribute of its object, read where it matters; this
module is the only Python place that names them (``tests/test_architecture.py`` fails on a
branch on a name elsewhere), and `impactbeams.kernels.contact` and `impactbeams.kernels.drive`
the only kernels that dispatch on a law's index or a clamp's motion.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from impactbeams.kernels import layout


@dataclasses.dataclass(frozen=True)
class ContactLaw:
    """A contact law of the tips.

    ``compliant``: a contact of stiffness k and dashpot c (``contact_stiffness``,
    ``contact_damping``), whose contact phase follows from the free one and the damping ratio,
    and whose contacts need the modes that resolve k (`impactbeams.contact.required_modes`).
    ``projects``: a contact phase of its own modes, entered and left by projections at the
    switches; otherwise the free coordinates are kept through contact, a flow with tangent
    dynamics (Lyapunov exponents, periodic orbits), which a single moving clamp may drive.
    ``note``: the Datasets' ``contact_law_note``. ``impact_cycle``: what a cycle of an impacting
    cell costs, by kind of run (``"dynamics"``, ``"lyapunov"``: a tangent flow's only,
    ``"long_time"``, ``"simulate"``): (a, p) of ``a n^p`` s per cycle at n modes per beam
    (`impactbeams.costs.dynamics_seconds`), measured by ``benchmarks/calibrate_costs.py``.
    """

    name: str
    compliant: bool
    projects: bool
    note: str
    impact_cycle: Mapping[str, tuple[float, float]] = dataclasses.field(compare=False)

    @property
    def index(self) -> int:
        """The kernels' integer code of the law (`kernels.layout.CONTACT_LAWS`)."""
        return layout.CONTACT_LAWS.index(self.name)

    @property
    def tangent_flow(self) -> bool:
        """Whether the dynamics is a flow whose linearisation converges in n_modes."""
        return not self.projects


@dataclasses.dataclass(frozen=True)
class Counterpart:
    """What beam 1's tip meets: beam 2's tip, or a fixed rigid stop (no modes, no compliance).

    ``beams``: the beams that move (2, or 1 against a stop); ``words``: how a title says so
    (``""`` or ``"against a stop"``); ``second_tip``: the legend of tip 2's trace (a stop's is its
    position, -Delta); ``modes_words``: how a count of modes is said (``"per beam"``).
    """

    name: str
    beams: int
    words: str
    second_tip: str
    modes_words: str

    @property
    def has_beam2(self) -> bool:
        """Whether beam 2 exists (its modes, its keys, its tip compliance)."""
        return self.beams == 2


@dataclasses.dataclass(frozen=True)
class Side:
    """Which way beam 1 moves to close the contact (``contact_side``).

    ``sign``: s in the gap ``g = clearance + s (y1(x1) - y2(x2))`` (docs/model.md, "Where the
    contact acts"): +1.0 when what beam 1 meets is below it (beam 1 moves down onto it, today's
    and the paper's configuration), -1.0 when it is above (beam 1 moves up onto it); the
    contact force pushes beam 1 by s R and beam 2 by -s R. ``words``: where the counterpart is.
    """

    name: str
    sign: float
    words: str


@dataclasses.dataclass(frozen=True)
class Mount:
    """Which clamps the shaker carries (``shaker``): a stop's mount is beam 2's clamp.

    ``clamps``: (1.0 if beam 1's clamp moves else 0.0, likewise beam 2's); ``words``,
    ``words_at_stop``: where it sits, in words, against beam 2 and against a stop.
    """

    name: str
    clamps: tuple[float, float]
    words: str
    words_at_stop: str

    @property
    def carries_both_clamps(self) -> bool:
        """Whether both clamps move (beam 1's and beam 2's, or a stop's mount)."""
        return all(moves > 0.0 for moves in self.clamps)

    def place(self, partner: Counterpart) -> str:
        """Where the shaker sits against ``partner``, e.g. ``"on both clamps"``."""
        return self.words if partner.has_beam2 else self.words_at_stop

    def moves_stop(self, partner: Counterpart) -> bool:
        """Whether this shaker carries a stop's mount (beam 2's clamp, against a stop)."""
        return not partner.has_beam2 and self.clamps[1] > 0.0

    def shaken_beams(self, partner: Counterpart) -> tuple[str, ...]:
        """The beams ("1", "2") whose tips the shaker's motion deflects against ``partner``.

        Against a stop beam 1 only (its clamp, the stop's mount, or both move it).
        """
        if not partner.has_beam2:
            return ("1",)
        return tuple(i for i, moves in zip("12", self.clamps, strict=True) if moves)


# --- impact-cycle costs from docs/benchmarks/costs.json (benchmarks/calibrate_costs.py) ------
SPRING_CYCLE = {
    "dynamics": (1.9e-05, 1.4),
    "lyapunov": (2.7e-05, 0.81),
    "long_time": (1.8e-05, 0.72),
    "simulate": (9.1e-05, 1.2),
}
TIED_CYCLE = {"dynamics": (5.2e-06, 1.8), "long_time": (3.3e-06, 1.1), "simulate": (3.9e-05, 1.4)}
# ----------------------------------------------------------------------------------------------

SPRING_LAW = ContactLaw(
    "spring", compliant=True, projects=False,
    note="compliant tip contact R = -k g - c g' while positive, free coordinates kept in both "
         "phases, static correction of the missed modes; the first contacts and episodes' "
         "totals converge in n_modes, the chaotic trace after the first rattle does not "
         "(docs/model.md, Compliant contact)", impact_cycle=SPRING_CYCLE)
TIED_LAW = ContactLaw(
    "tied", compliant=False, projects=True,
    note="the paper's tied tips with projections at the switches; results after the first "
         "impact do not converge in n_modes (docs/model.md)", impact_cycle=TIED_CYCLE)
BEAM = Counterpart("beam", 2, "", r"$y_2(l_2) - \Delta$", "per beam")
STOP = Counterpart("stop", 1, "against a stop", r"stop, $-\Delta$", "of beam 1")
BELOW = Side("below", 1.0, "below beam 1")
ABOVE = Side("above", -1.0, "above beam 1")
BOTH = Mount("both", (1.0, 1.0), "on both clamps", "on beam 1's clamp and the stop")
BEAM1 = Mount("beam1", (1.0, 0.0), "on beam 1's clamp", "on beam 1's clamp")
BEAM2 = Mount("beam2", (0.0, 1.0), "on beam 2's clamp", "on the stop")

# each variant by its name, the default first (the order users are offered them in)
LAWS = {law.name: law for law in (SPRING_LAW, TIED_LAW)}
COUNTERPARTS = {partner.name: partner for partner in (BEAM, STOP)}
MOUNTS = {mount.name: mount for mount in (BOTH, BEAM1, BEAM2)}
SIDES = {side.name: side for side in (BELOW, ABOVE)}


def counterpart_named(name: object) -> Counterpart:
    """The counterpart of a name not yet checked (a file's, the command line's, a Dataset's).

    Beam 2 for anything that names no counterpart: a wrong name is refused by `Params` later.
    """
    return COUNTERPARTS.get(name, BEAM) if isinstance(name, str) else BEAM
