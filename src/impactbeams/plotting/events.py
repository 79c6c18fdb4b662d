"""Which of a continuation's located events a frequency-response curve draws and labels.

On a stiff contact a branch carries hundreds of events: the stop-and-shaker case of issue 31 at
the default Hertz contact (``benchmarks/bench_stiff_continuation.py``) has 340 along its 5005
points up (``docs/benchmarks/stiff_continuation.md``: 24 folds, 82 period doublings, 75
Neimark-Sacker points, 67 grazings, 46 contact merges, 46 splits). A label on each would cover
the curve: `EventChoice` says which kinds are drawn (a marker at each event), and of those
which are also labelled where a label fits (`impactbeams.plotting.branches.place_labels`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from impactbeams.params import ParameterError, nearest, require_type
from impactbeams.variables import BIFURCATIONS

KINDS = BIFURCATIONS[1:]  # the event kinds a branch point may carry ("none" is no event)
# the order labels are placed in, the first getting the room: the bifurcations of the smooth
# dynamics, then the onset and end of contacts, then the changes within a contact sequence
PRIORITY = ("fold", "period_doubling", "neimark_sacker", "branch_point", "grazing",
            "contact_merge", "contact_split", "chatter")
# drawn without labels by default: on a stiff contact they are the many (a free interval
# between two contacts closing or opening, micro-contacts), and where they are matters more
# than which is which; their markers are small
MARKED_ONLY = ("contact_merge", "contact_split", "chatter")
ALL, NONE = "all", "none"


@dataclasses.dataclass(frozen=True)
class EventChoice:
    """The event kinds drawn, and of them the ones drawn without labels.

    ``drawn``: None for every kind; ``marked_only``: kinds drawn with small markers and no label.
    """

    drawn: frozenset[str] | None = None
    marked_only: frozenset[str] = frozenset(MARKED_ONLY)

    def is_drawn(self, kind: str) -> bool:
        """Whether the events of ``kind`` are marked."""
        return self.drawn is None or kind in self.drawn

    def is_labelled(self, kind: str) -> bool:
        """Whether the events of ``kind`` are marked and labelled where a label fits."""
        return self.is_drawn(kind) and kind not in self.marked_only


def priority(kind: str) -> int:
    """Where ``kind``'s labels come in the order of placement (an unknown kind last)."""
    return PRIORITY.index(kind) if kind in PRIORITY else len(PRIORITY)


def chosen_events(value: object, name: str = "events") -> EventChoice:
    """The `EventChoice` ``value`` asks for; ParameterError naming ``name`` if it is not one.

    ``value``: None (the default: every kind drawn; folds, period doublings, Neimark-Sacker
    and branch points, then grazings labelled where they fit, in that order; contact merges,
    splits and chatter drawn small and unlabelled), "all" (every kind drawn and labelled where
    it fits), "none" (no event drawn), or kinds (a sequence of names, or one string of names
    separated by commas): those drawn and labelled where they fit, the others not drawn.
    """
    if value is None:
        return EventChoice()
    require_type(name, value, isinstance(value, str) or (
        isinstance(value, Sequence) and all(isinstance(kind, str) for kind in value)),
        "None, 'all', 'none', or event kinds (a sequence of str, or one str separated by "
        "commas)")
    kinds = [kind.strip() for kind in (value.split(",") if isinstance(value, str) else value)]
    if kinds in ([ALL], [NONE]):
        return EventChoice(None if kinds == [ALL] else frozenset(), frozenset())
    for kind in kinds:
        if kind not in KINDS:
            problem = ("'all' and 'none' stand alone" if kind in (ALL, NONE) else
                       f"{kind!r} is not an event kind{nearest(kind, KINDS)}")
            raise ParameterError(f"{name} = {value!r} is not allowed: {problem}; give all, "
                                 f"none, or kinds separated by commas from {', '.join(KINDS)}")
    return EventChoice(frozenset(kinds), frozenset())
