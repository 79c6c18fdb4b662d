"""Continuation of the beams' periodic orbits in one parameter: `continue_orbits`.

The guess is the section state after ``transient_periods`` period maps from the run's start
(``params.start``, rest by default) at the first parameter value, or a given ``state``.
Lengths along the branch count the parameter in units of its range (max - min) and the state in
the energy norm (omega q, q') in units of ``state_scale``: the norm of the start orbit's state
scaled to a tip motion of ``state_scale`` metres (default ten clearances), so that a step of
``max_step`` moves the parameter by at most ``max_step`` and the state by at most the same
fraction of ``state_scale``.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.blas import one_blas_thread
from impactbeams.continuation.arclength import (
    LOCATE,
    MICRO_CONTACTS,
    TURN_AIM,
    Point,
    Scaling,
    Settings,
)
from impactbeams.continuation.beams import BeamOrbits
from impactbeams.continuation.branch import (
    Branch,
    ContinuationInterrupted,
    Span,
    continue_branches,
)
from impactbeams.continuation.checkpoint import CourseLog, checkpointed
from impactbeams.continuation.output import branches_dataset
from impactbeams.orbits.period_map import check_law
from impactbeams.orbits.shooting import GUARD, METHODS
from impactbeams.params import (
    CONTACTS,
    MAX_MODES,
    ParameterError,
    Params,
    check_parameter,
    check_part_field,
    contact_field,
    is_path,
    named_attributes,
    part_field,
    require,
    require_finite,
    require_integer,
    require_type,
    with_parameter,
)
from impactbeams.structure.contacts import FLAT_KEYS
from impactbeams.variables import global_attributes

if TYPE_CHECKING:
    import xarray as xr

# what can be continued: every numeric parameter but the uplifts, which only set a run's start
CONTINUABLE = tuple(name for name in Params.numeric_names() if not name.startswith("uplift"))
# a contact's fields continued as contacts.INDEX.FIELD: its law's (its point is a geometry)
_CONTACT_FIELDS = tuple(field for field, key in FLAT_KEYS.items() if key in CONTINUABLE)
DIRECTIONS = ("up", "down")
STATE_SCALE_CLEARANCES = 10.0  # the default state_scale, in clearances


@dataclasses.dataclass(frozen=True)
class Continuation:
    """What to continue: ``parameter`` of ``params`` from ``low`` to ``high`` (its units).

    ``parameter``: a numeric parameter's name, or with several contacts one contact's law
    field, ``contacts.INDEX.FIELD`` (its clearance, stiffness or damping).

    ``direction``: "up" starts at ``start`` (default ``low``) going up, "down" at ``start``
    (default ``high``) going down. ``period``: forcing periods of the orbit. ``n_modes``: per
    beam (default: the number that resolves the contact). ``state``: the start's section
    state; without it, ``transient_periods`` period maps from the run's start. Steps in the
    parameter's units; ``state_scale`` in m (module docstring). ``method``: the corrector's
    dr/dz, "newton" (full monodromy), "newton-picard" (on ``subspace`` carried directions,
    default 8 but at most the 2 N coordinates) or "auto" (`BeamOrbits`).
    ``micro_contacts``: "locate" every change of the orbit's contact sequence, or
    "summarise" those within an impact episode (labelled chatter at the first point after,
    not located; an episode's appearance and disappearance still are): for stiff contacts,
    where micro-contacts appear and merge many times per unit of the parameter.
    """

    params: Params
    parameter: str
    low: float
    high: float
    direction: str = "up"
    start: float | None = None
    period: int = 1
    n_modes: int | None = None
    transient_periods: int = 300
    state: np.ndarray | None = None
    step: float | None = None
    min_step: float | None = None
    max_step: float | None = None
    max_points: int = 1000
    max_branches: int = 2
    state_scale: float | None = None
    method: str = "auto"
    subspace: int | None = None
    micro_contacts: str = LOCATE

    def __post_init__(self) -> None:
        require_type("params", self.params, isinstance(self.params, Params),
                     "an impactbeams.Params")
        check_law(self.params)
        check_continued(self.params, "parameter", self.parameter)
        for name in ("low", "high"):
            value = require_finite(name, getattr(self, name))
            check_parameter(self.parameter, value)
        require("high", self.high, self.high > self.low,
                f"the range [{self.low!r}, {self.high!r}] is empty: need high > low")
        if self.parameter == "damping_ratio" and self.params.structure1 is not None:
            self.params.structure1.require_run_damping(self.high)  # (its own damping: none)
        require("direction", self.direction, self.direction in DIRECTIONS,
                f"must be one of {', '.join(map(repr, DIRECTIONS))}")
        if self.start is not None:
            require("start", self.start, self.low <= require_finite("start", self.start)
                    <= self.high, f"must lie in [{self.low!r}, {self.high!r}]")
        require_integer("period", self.period, 1)
        require("method", self.method, self.method in METHODS,
                f"must be one of {', '.join(map(repr, METHODS))}")
        if self.subspace is not None:  # its largest, 2 N, is checked with the model
            require_integer("subspace", self.subspace, GUARD + 1)
        require_integer("transient_periods", self.transient_periods, 0)
        require("micro_contacts", self.micro_contacts, self.micro_contacts in MICRO_CONTACTS,
                f"must be one of {', '.join(map(repr, MICRO_CONTACTS))}")
        for name in ("step", "min_step", "max_step", "state_scale"):
            value = getattr(self, name)
            if value is not None:
                require(name, value, require_finite(name, value) > 0, "must be > 0")
        if self.n_modes is not None:
            require_integer("n_modes", self.n_modes, 1, MAX_MODES)
        if self.parameter == "omega":
            require("min", self.low, self.low > 0, "a periodic orbit needs omega > 0", "rad/s")
        for end in (self.low, self.high):  # with the fixed ones, at both ends (monotone rules)
            with_parameter(self.params, self.parameter, end)
        self._check_steps()

    def _check_steps(self) -> None:
        """min_step <= step <= max_step, said in the parameter's units (given or default)."""
        step, low, high = self._steps()
        unit = named_attributes(self.parameter)["units"]
        require("min_step", low, low <= high, f"must be <= max_step = {high:g}", unit)
        require("step", step, low <= step <= high,
                f"must lie from min_step = {low:g} to max_step = {high:g}", unit)

    def _steps(self) -> tuple[float, float, float]:
        """The first, smallest and largest steps in the parameter's units (given or default).

        The default first step is a hundredth of the range, within the given smallest and
        largest.
        """
        width = self.high - self.low
        low = self.min_step if self.min_step is not None else 1e-9 * width
        high = self.max_step if self.max_step is not None else max(
            self.step or width / 100.0, width / 20.0)
        step = self.step if self.step is not None else min(max(width / 100.0, low), high)
        return step, low, high

    @property
    def first(self) -> float:
        """The parameter's value at the start."""
        if self.start is not None:
            return self.start
        return self.low if self.direction == "up" else self.high

    def settings(self) -> Settings:
        """The engine's settings, steps in units of the range."""
        width = self.high - self.low
        step, low, high = self._steps()
        return Settings(step=step / width, min_step=low / width, max_step=high / width,
                        max_points=self.max_points, max_branches=self.max_branches,
                        micro_contacts=self.micro_contacts, turn_aim=TURN_AIM)


def check_continued(params: Params, what: str, name: str) -> None:
    """``name`` (given as ``what``) is continuable; with several contacts, a law's field of one.

    Each contact gives its own law (``contacts.INDEX.FIELD``: that contact's clearance,
    stiffness or damping); its point is not continued (nor the flat point of one).
    """
    contacts = params.contacts
    if part_field(name) is not None:
        check_part_field(params, what, name)
        return
    field = contact_field(name)
    if field is None:
        require(what, name, not (contacts and name in FLAT_KEYS.values()),
                f"with {len(contacts)} contacts each gives its own: continue one contact's "
                f"as '{CONTACTS}.INDEX.FIELD' (FIELD one of {', '.join(_CONTACT_FIELDS)})")
        require(what, name, name in CONTINUABLE,
                f"must be one of {', '.join(CONTINUABLE)}, or with several contacts "
                f"'{CONTACTS}.INDEX.FIELD'")
        require(what, name, name not in params.derived_keys(),
                "it is derived here from the beam's segments or structure: continue a segment's "
                "field ('segments1.INDEX.FIELD', FIELD one of length, EI, rhoA)")
        return
    index, field_name = field
    require(what, name, len(contacts) >= 2,
            f"continues a field of one of several contacts, and params has "
            f"{len(contacts) or 'one or none'}: one contact is the flat keys (continue "
            f"{FLAT_KEYS.get(field_name, 'clearance')})")
    require(what, name, index < len(contacts),
            f"there are {len(contacts)} contacts (indices 0 to {len(contacts) - 1})")
    require(what, name, field_name in _CONTACT_FIELDS,
            f"a contact's continuable fields are {', '.join(_CONTACT_FIELDS)}")


Progress = Callable[[Branch, Point], None]


@one_blas_thread
def continue_orbits(continuation: Continuation, progress: Progress | None = None,
                    output: str | Path | None = None) -> xr.Dataset:
    """Follow the periodic orbits of ``continuation`` and return the branches' Dataset.

    With ``output`` (a netCDF path) the Dataset is also written there, and the continuation
    checkpoints every step under ``OUTPUT.partial/`` (`impactbeams.continuation.checkpoint`):
    killed or interrupted, the same call resumes from its last step and writes the same file,
    bit for bit. One writer per output (the lock of `impactbeams.lock`); the partial run
    of another continuation or other code is refused. An existing ``output`` is replaced.

    On Ctrl-C raises `ContinuationInterrupted` whose ``dataset`` holds what was computed
    (with ``output``, also written to ``OUTPUT.partial/OUTPUT``). ParameterError if the
    start does not converge or an input is not allowed.
    """
    require_type("continuation", continuation, isinstance(continuation, Continuation),
                 "an impactbeams.Continuation")
    require_type("output", output, output is None or is_path(output),
                 "None or the path of a netCDF file (str or pathlib.Path)")
    c = continuation
    if not c.params.damped and c.parameter != "damping_ratio":
        # the free modes' multipliers are then on the unit circle to round-off
        warnings.warn("damping_ratio = 0: the undamped modes' Floquet multipliers lie on the "
                      "unit circle, so stability and the Neimark-Sacker labels are decided by "
                      "round-off; continue a damped model (damping_ratio > 0)", RuntimeWarning,
                      stacklevel=2)
    if c.params.moving_stop():
        warnings.warn(c.params.moving_stop(), UserWarning, stacklevel=2)
    if output is None:
        return _continued(c, progress)
    return checkpointed(Path(output), c, lambda log: _continued(c, progress, log))


def _continued(c: Continuation, progress: Progress | None,
               log: CourseLog | None = None) -> xr.Dataset:
    """The branches' Dataset of ``c``, checkpointed into (and resumed from) ``log``."""
    problem = orbits_problem(c)
    settings = c.settings()
    resume = None if log is None else log.restore(problem, settings)
    if resume is None:
        state = _start_state(problem, c)
        scaling = _scaling(problem, c, state)
    else:  # the start and its scaling are the saved points'
        state, scaling = np.empty(0), resume.branches[0].scaling
    span = Span(c.low, c.high, 1 if c.direction == "up" else -1)
    attrs = _attributes(c, problem)
    try:
        branches = continue_branches(problem, state, c.first, span, scaling, settings, progress,
                                     log, resume)
    except ContinuationInterrupted as interrupted:
        interrupted.dataset = branches_dataset(interrupted.branches, c.parameter, attrs)
        raise
    return branches_dataset(branches, c.parameter, attrs)


def orbits_problem(c: Continuation) -> BeamOrbits:
    """The first branch's problem: the orbits at the first value.

    A ParameterError for a method or subspace that does not fit its coordinates.
    """
    params = with_parameter(c.params, c.parameter, c.first)
    return BeamOrbits(params, c.parameter, mode_count(c), c.period, c.method, c.subspace)


def state_size(c: Continuation) -> int:
    """The section state's length 2 N: positions and velocities of the free coordinates."""
    return 2 * c.params.partner.beams * mode_count(c)


def fewest_points(c: Continuation) -> int:
    """The fewest points the first branch can have: its range in steps of ``max_step``."""
    _, _, largest = c._steps()
    return math.ceil((c.high - c.low) / largest) + 1


def least_clearance(params: Params) -> float:
    """The smallest clearance (m) of ``params``' contacts (its own, for one)."""
    return min(run.clearance for run in params.each_contact())


def mode_count(c: Continuation) -> int:
    """The free modes per beam of ``c``: its ``n_modes``, or those that resolve the contact."""
    from impactbeams.contact import recommended_modes

    if c.n_modes is not None:
        return int(c.n_modes)
    return max(recommended_modes(run) for run in c.params.each_contact())


def _start_state(problem: BeamOrbits, c: Continuation) -> np.ndarray:
    """The periodic orbit at the first value by shooting from ``state`` or the transient."""
    from impactbeams.orbits import OrbitNotConverged, periodic_orbit

    try:
        orbit = periodic_orbit(problem.params, problem.n_modes, c.period,
                               None if c.state is None else np.asarray(c.state, dtype=float),
                               transient_periods=c.transient_periods, measures=False,
                               method=problem.method, subspace=problem.subspace)
    except OrbitNotConverged as error:
        raise ParameterError(f"the start at {c.parameter} = {c.first!r} did not converge "
                             f"({error}): give a state, or more transient_periods") from None
    problem.start_basis(orbit.basis)
    return orbit.state


def _scaling(problem: BeamOrbits, c: Continuation, state: np.ndarray) -> Scaling:
    """x~ of the module's docstring: the state per ``state_scale`` of tip motion."""
    weights = problem.state_weights()
    tip = problem.period_map(c.first)(state).max_tip1
    size = np.linalg.norm(weights * state)
    scale = c.state_scale if c.state_scale is not None else (
        STATE_SCALE_CLEARANCES * least_clearance(c.params))
    per_metre = size / tip if tip > 0 and size > 0 else 1.0
    return Scaling(weights / (per_metre * scale), 1.0 / (c.high - c.low))


def _attributes(c: Continuation, problem: BeamOrbits) -> dict[str, object]:
    params = {name: value for name, value in c.params.as_dict().items()
              if name != c.parameter}
    settings = c.settings()
    return global_attributes(
        "Periodic orbits of two impacting beams along a parameter (continuation)",
        f"continue {c.parameter} from {c.low!r} to {c.high!r}", params,
        n_modes=problem.n_modes, start_period=c.period, direction=c.direction,
        locate_tolerance=settings.locate_tolerance * (c.high - c.low),
        newton_tolerance=settings.tolerance, corrector=problem.method)

