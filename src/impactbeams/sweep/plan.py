"""A sweep's kernel inputs (the per-geometry plan, a chunk's cells) and `compute_chunk`.

The grid is flattened in C order; a chunk is a range of flat cells. `Chunking` cuts the
grid into chunks that are also boxes of the array (whole lines of the last axes), so that a
chunk's cells are built by broadcasting the axis values, never the whole grid's, and a chunk is
one compressed block of the netCDF file. Axes over `CELL_PARAMETERS` change a cell's
forcing, initial state or damping only; the other axes change the geometry, whose modes are
computed once per geometry (the plan).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import itertools
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from impactbeams.kernels import layout
from impactbeams.longtime import LongTime
from impactbeams.params import Params, flat_parameter
from impactbeams.sweep.definition import (
    CELL_PARAMETERS,
    CONTACT_OBSERVABLES,
    DYNAMICS_OBSERVABLES,
    FIRST_CONTACT,
    FIRST_IMPACT,
    LONG_RUN_CAPACITY,
    LYAPUNOV,
    MAX_SEGMENTS,
    STEPPED_END_STATE,
    Axis,
    Sweep,
    contact_axes,
    contact_laws,
    contact_sweeps,
    geometry_axes,
)
from impactbeams.variables import VARIABLES

# The code that decides a sweep's numbers: every kernel and the modules that build their inputs
# (paths in the package). Saved chunks and finished files of other code are never reused.
NUMERIC_CODE = ("kernels/*.py", "packing.py", "contact/*.py", "drive.py", "modes.py", "blas.py",
                "brent.py", "params.py", "checks.py", "structure/*.py", "configuration.py",
                "sweep/definition.py", "sweep/plan.py")
MAX_PHASES_PER_PERIOD = 2000  # cap of a long run, per forcing period; more: dynamics_status = 1


@dataclasses.dataclass(frozen=True)
class Plan:
    """What the kernels need per geometry, and how cells map to geometries.

    ``tables``: the free phase of every geometry (first-impact map), or both phases with the
    switching arrays (the geometries' switching records stacked,
    `impactbeams.packing.stacked_switching`) when a full-dynamics
    observable is asked for (see kernels.layout). ``fingerprint`` is the sweep's: a plan
    serves only the sweep it was built for.
    """

    fingerprint: str
    base: Params
    tables: np.ndarray  # (geometries, phases, len(TABLE_ROWS), 2 n_modes)
    geometry: np.ndarray  # (geometries, len(GEOMETRY))
    geometry_axes: tuple[int, ...]  # positions of the axes that change the geometry
    switching: tuple[np.ndarray, ...] | None  # a dynamics map's switching arrays, stacked
    axis_values: tuple[np.ndarray, ...]  # every axis's values, computed once for all chunks
    # several contacts: each contact's own sweep's plan (`contact_sweeps`); the fields above
    # are then the first's
    per_contact: tuple[Plan, ...] = ()


def code_digest(package: Path = Path(__file__).parents[1],
                patterns: tuple[str, ...] = NUMERIC_CODE) -> str:
    """Short hash of the files of ``package`` (default: this one) that ``patterns`` match.

    Part of a run's identity next to the sweep's fingerprint: a changed kernel without a new
    version number must not resume from the old code's chunks.
    """
    paths = sorted(path for pattern in patterns for path in package.glob(pattern))
    digest = hashlib.sha256()
    for path in paths:
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def contact_resolution(sweep: Sweep) -> int | None:
    """n_modes that resolves a spring-law dynamics map's every contact; None otherwise.

    The most any contact (`Params.each_contact`) needs (`needed_modes`) at any geometry of
    the grid: every combination of the values of the axes that change the modes (a length,
    a contact's point, a beam's stiffness, ...; `geometry_axes`), a contact stiffness axis at
    its largest value only (a stiffer contact needs no fewer modes), the other parameters the
    first point's. At most ``MAX_GEOMETRIES`` combinations, each some 1 ms.
    """
    compliant = [law for law in contact_laws(sweep) if law.compliant]
    if not sweep.needs_dynamics or not compliant:
        return None
    from impactbeams.contact.spring import needed_modes  # SciPy's optimisers: only when needed

    axes = [sweep.axes[k] for k in geometry_axes(sweep) if not sweep.axes[k].choices]
    values = [[axis.max] if flat_parameter(axis.name) == "contact_stiffness" else axis.values
              for axis in axes]
    law = {"contact_law": compliant[0].name}
    return max(needed_modes(run) for point in itertools.product(*values)
               for run in sweep.params_at({**dict(zip((axis.name for axis in axes), point,
                                                      strict=True)), **law}).each_contact())


def _first_contact(sweep: Sweep, start: int, stop: int, parallel: bool, plan: Plan,
                   ) -> dict[str, np.ndarray]:
    """The first contact among several: each contact's own map's chunk, the earliest.

    ``first_contact``: which (the lowest index of equal times; -1 where none closes).
    """
    times = np.array([_contact_times(sweep, index, each, start, stop, parallel, each_plan)
                      for index, (each, each_plan) in enumerate(zip(
                          contact_sweeps(sweep), plan.per_contact, strict=True))])
    closed = np.isfinite(times)
    first = np.argmin(np.where(closed, times, np.inf), axis=0)
    return {FIRST_IMPACT: np.ascontiguousarray(np.fmin.reduce(times, axis=0)),
            FIRST_CONTACT: np.where(closed.any(axis=0), first, -1)}


def _several_dynamics(sweep: Sweep, start: int, stop: int, parallel: bool,
                      ) -> dict[str, np.ndarray]:
    """Full-dynamics and long-time observables of several contacts on cells start..stop.

    Each cell is the runs `impactbeams.simulate` makes of its parameters (the active sets'
    phases, `active_phases.cell_observables`), cell by cell, the active sets' phases built once
    per geometry of the chunk (`geometry_axes`: a clearance or a drive does not change them);
    with ``parallel`` the cells run on Numba's thread count of threads (the kernel releases
    the GIL), each alone: the same values. A stepped sweep runs its rows (`stepped_rows`) so,
    each row's cells one after the other, each long run from where the one before ended
    (`_carried_start`).
    """
    from concurrent.futures import ThreadPoolExecutor

    import numba

    from impactbeams.active_phases import cell_observables
    from impactbeams.contact.active_sets import SeveralContacts, several_contacts

    # the axes' indices (a stepped sweep's directions come first, `Sweep.shape`)
    index = np.unravel_index(np.arange(start, stop), sweep.shape)[-len(sweep.axes):]
    values = [axis.values for axis in sweep.axes]  # (the plan's are its first contact's)
    dynamics = any(name in (FIRST_IMPACT, *DYNAMICS_OBSERVABLES, *CONTACT_OBSERVABLES)
                   for name in sweep.observables)
    geometry = geometry_axes(sweep)
    phases: dict[tuple[int, ...], SeveralContacts] = {}  # each geometry's active sets, once

    def one(i: int, state: np.ndarray | None = None) -> dict[str, object]:
        changes = {axis.name: values[k][index[k][i]] for k, axis in enumerate(sweep.axes)}
        params = sweep.params_at(changes)
        key = tuple(int(index[k][i]) for k in geometry)
        if key not in phases:
            phases[key] = several_contacts(params, sweep.n_modes)
        return cell_observables(params, sweep.n_modes, sweep.t_max, MAX_SEGMENTS, dynamics,
                                sweep.long_time, sweep.transient_periods, phases[key],
                                LYAPUNOV in sweep.observables,
                                None if state is None else _carried_start(state))

    def row(cells: np.ndarray) -> list[tuple[int, dict[str, object]]]:
        out, state = [], None
        for i in cells:
            out.append((int(i), one(int(i), state)))
            if sweep.stepping is not None:
                state = np.concatenate([out[-1][1][name] for name in STEPPED_END_STATE])
        return out

    rows = (stepped_rows(sweep, start, stop) if sweep.stepping is not None
            else np.arange(stop - start)[:, None])
    if parallel and rows.shape[0] > 1:
        with ThreadPoolExecutor(numba.get_num_threads()) as pool:
            done = list(pool.map(row, rows))
    else:
        done = [row(cells) for cells in rows]
    cells = dict(itertools.chain.from_iterable(done))
    return {name: np.array([cells[i][name] for i in range(stop - start)],
                           dtype=VARIABLES[name].dtype) for name in sweep.stored}


def _carried_start(state: np.ndarray):
    """A stepped cell's start from the state z = (q, q') its predecessor ended in.

    As `impactbeams.simulate` starts from that ``initial_state`` (`active_phases.contacts_start`:
    the closed contacts from the state), so that the cell is the run simulate makes. Where the
    predecessor stopped early (NaN) or ended inside a dashpot's early release (no set of
    closed contacts fits the state, which simulate refuses) the cell starts from rest, as one
    contact's stepped cell after a run that stopped early; the latter with a RuntimeWarning.
    """
    import warnings

    from impactbeams.active_phases import contacts_start
    from impactbeams.params import ParameterError

    def start(packed):
        if not np.all(np.isfinite(state)):
            return None
        try:
            return contacts_start(packed, state)
        except ParameterError as error:
            warnings.warn(f"a stepped cell starts from rest: {error}", RuntimeWarning,
                          stacklevel=2)
            return None

    return start


def _contact_times(sweep: Sweep, index: int, each: Sweep, start: int, stop: int,
                   parallel: bool, plan: Plan) -> np.ndarray:
    """Contact ``index``'s first impacts on flat cells start..stop of ``sweep``.

    From its own sweep ``each`` (`contact_sweeps`), over the axes that change its run
    (`contact_axes`): along the others (other contacts' fields) each cell is the same run,
    computed once (a chunk's box of the grid is a box of its grid too).
    """
    kept = contact_axes(sweep, index)
    if len(kept) == len(sweep.axes):
        return compute_chunk(each, start, stop, parallel, plan)[FIRST_IMPACT]
    cells = np.unravel_index(np.arange(start, stop), sweep.shape)
    own = (np.ravel_multi_index(tuple(cells[k] for k in kept), each.shape) if kept
           else np.zeros(stop - start, dtype=np.intp))
    low = int(own.min())
    return compute_chunk(each, low, int(own.max()) + 1, parallel, plan)[FIRST_IMPACT][own - low]


def _geometries(sweep: Sweep) -> Iterator[Params]:
    """The parameters of every distinct geometry of the grid, in flat geometry-index order."""
    axes = geometry_axes(sweep)
    for combo in itertools.product(*(range(sweep.axes[k].num) for k in axes)):
        changes = {sweep.axes[k].name: sweep.axes[k].value(i)
                   for k, i in zip(axes, combo, strict=True)}
        yield sweep.params_at(changes)


# the geometries built while a run is prepared (`reusing_geometries`), by (parameters, n_modes,
# full dynamics): what the checks before a run build, its plan takes, not building it again
_BUILT: list[dict[tuple[Params, int, bool], tuple[np.ndarray | tuple, ...]]] = []


@contextlib.contextmanager
def reusing_geometries() -> Iterator[None]:
    """Within the body (a run: its checks, then its plan) each geometry is built once.

    The arrays a check builds (`check_contact_phases`) are kept until the plan (`build_plan`)
    takes them; a body inside another shares the outer one's; the rest go at its end.
    """
    if _BUILT:
        yield
        return
    _BUILT.append({})
    try:
        yield
    finally:
        _BUILT.clear()


def _geometry_arrays(params: Params, sweep: Sweep, keep: bool = False,
                     ) -> tuple[np.ndarray | tuple, ...]:
    """One geometry's packed arrays: (tables, geometry row[, switching record]).

    Those a check built in this run (`reusing_geometries`) are taken, not built again;
    ``keep``: a check's, left for the run's plan.
    """
    key = (params, sweep.n_modes, sweep.needs_dynamics)
    built = _BUILT[0] if _BUILT else {}
    arrays = built.get(key) if keep else built.pop(key, None)
    if arrays is None:
        arrays = _build_geometry_arrays(params, sweep)
    if keep:
        built[key] = arrays
    return arrays


def _build_geometry_arrays(params: Params, sweep: Sweep,
                           ) -> tuple[np.ndarray | tuple, ...]:
    from impactbeams import packing
    from impactbeams.contact.free import build_free_phase

    if not sweep.needs_dynamics:
        free = build_free_phase(params, sweep.n_modes)
        return packing.free_tables(free, params), packing.geometry_row(params, free)
    dynamics = packing.dynamics_arrays(params, sweep.n_modes)
    return dynamics.tables, dynamics.geometry, dynamics.switching


def check_contact_phases(sweep: Sweep) -> None:
    """Refuse a sweep whose damped spring contact cannot oscillate, before any work starts.

    Also a steady start at an undamped resonance (`_check_steady_start`).

    An overdamped contact phase (real eigenvalues) is found only when its modes are built, so
    the geometries with a damped spring contact build their dynamics arrays here, the plan's
    own SciPy work (kept for the run's plan within `reusing_geometries`); a ParameterError
    names the largest contact damping allowed. Other sweeps cost nothing.
    """
    _check_steady_start(sweep)
    if not sweep.needs_dynamics:
        return
    if sweep.base.several_contacts:  # every set of contacts closed together, each contact's too
        from impactbeams.contact.active_sets import several_contacts

        for params in _geometries(sweep):
            if params.damped or any(run.contact_damping for run in params.each_contact()):
                several_contacts(params, sweep.n_modes)
        return
    for params in _geometries(sweep):
        if params.law.compliant and (params.contact_damping or params.damped):
            _geometry_arrays(params, sweep, keep=True)


def _check_steady_start(sweep: Sweep) -> None:
    """Refuse ``start = "steady"`` where a cell drives an undamped free mode exactly at resonance.

    Such a mode has no steady state (`impactbeams.drive.check_steady`, which names the cell's
    Omega); found from the axes' values at the natural frequencies, without building an axis.
    """
    axes = {axis.name: axis for axis in sweep.axes}
    if sweep.base.start != "steady" or not _takes(axes, sweep.base, "damping_ratio", 0.0):
        return
    from impactbeams.contact.free import build_free_phase  # SciPy: only when needed
    from impactbeams.drive import check_steady
    for params in _geometries(sweep):  # (the free phase does not depend on the contacts)
        for frequency in build_free_phase(params.each_contact()[0],
                                          sweep.n_modes).frequencies:
            if _takes(axes, sweep.base, "omega", float(frequency)):
                undamped = params.replace(omega=float(frequency), damping_ratio=0.0)
                check_steady(undamped, build_free_phase(undamped, sweep.n_modes))


def _takes(axes: dict[str, Axis], base: Params, name: str, value: float) -> bool:
    """Whether parameter ``name`` takes exactly ``value`` somewhere on the grid.

    On an axis, only the two values around ``value``'s place on the spacing are compared.
    """
    axis = axes.get(name)
    if axis is None:
        return getattr(base, name) == value
    if axis.num == 1 or not axis.min <= value <= axis.max:
        return axis.first == value
    if axis.scale == "log":
        position = math.log(value / axis.min) / math.log(axis.max / axis.min)
    else:
        position = (value - axis.min) / (axis.max - axis.min)
    near = position * (axis.num - 1)
    return any(axis.value(i) == value for i in {math.floor(near), math.ceil(near)}
               if 0 <= i < axis.num)


def build_plan(sweep: Sweep) -> Plan:
    """The modes of every geometry of ``sweep``, packed for the kernels (SciPy work).

    With several contacts, each contact's own sweep's plan (`per_contact`).
    """
    from impactbeams.packing import stacked_switching

    if sweep.base.several_contacts:
        plans = tuple(build_plan(each) for each in contact_sweeps(sweep))
        return dataclasses.replace(plans[0], fingerprint=sweep.fingerprint(), base=sweep.base,
                                   per_contact=plans)
    per_geometry = [_geometry_arrays(params, sweep) for params in _geometries(sweep)]
    tables, geometry, *switching = zip(*per_geometry, strict=True)
    return Plan(sweep.fingerprint(), sweep.base, np.array(tables), np.array(geometry),
                geometry_axes(sweep), stacked_switching(switching[0]) if switching else None,
                tuple(axis.values for axis in sweep.axes))


def chunk_cells(sweep: Sweep, plan: Plan, start: int, stop: int) -> np.ndarray:
    """The packed cell rows (kernels.layout.CELL_COLUMNS) of flat cells start..stop.

    A stepped sweep's rows of every direction hold the same cells.
    """
    rows = [_box_cells(sweep, plan, box) for box in flat_boxes(start, stop, sweep.shape)]
    return rows[0] if len(rows) == 1 else np.concatenate(rows)


def _box_cells(sweep: Sweep, plan: Plan, box: tuple[slice, ...]) -> np.ndarray:
    """The cell rows of one box of the grid, in C order, from the axis values by broadcasting."""
    from impactbeams import packing

    if sweep.stepping is not None:  # the rows' directions first: the same cells in each
        box, directions = box[1:], box[0].stop - box[0].start
        return np.tile(_box_cells(dataclasses.replace(sweep, stepping=None), plan, box),
                       (directions, 1))

    columns: dict[str, float | np.ndarray] = {name: getattr(plan.base, name)
                                              for name in CELL_PARAMETERS}
    for k, axis in enumerate(sweep.axes):
        if axis.name in columns:
            columns[axis.name] = _along(plan.axis_values[k][box[k]], k, len(box))
    geometry, stride = 0, 1  # the flat index over the geometry axes, the last one fastest
    for k in reversed(plan.geometry_axes):
        geometry = geometry + _along(np.arange(box[k].start, box[k].stop) * stride, k, len(box))
        stride *= sweep.axes[k].num
    columns["geometry"] = geometry
    return packing.cell_rows(columns, tuple(s.stop - s.start for s in box))


def _along(values: np.ndarray, axis: int, ndim: int) -> np.ndarray:
    """``values`` shaped to broadcast along ``axis`` of an ``ndim``-D box."""
    return values.reshape([-1 if k == axis else 1 for k in range(ndim)])


def flat_boxes(start: int, stop: int, shape: tuple[int, ...]) -> Iterator[tuple[slice, ...]]:
    """The boxes (one slice per axis) that tile the flat C-order cells start..stop, in order.

    A range aligned on whole lines (a `Chunking` chunk) is one box; any other range is
    at most ``2 len(shape) - 1`` boxes.
    """
    if len(shape) == 1:
        yield (slice(start, stop),)
        return
    inner = math.prod(shape[1:])
    first, head = divmod(start, inner)
    last, tail = divmod(stop, inner)
    if first == last:
        for box in flat_boxes(head, tail, shape[1:]):
            yield slice(first, first + 1), *box
        return
    if head:
        for box in flat_boxes(head, inner, shape[1:]):
            yield slice(first, first + 1), *box
        first += 1
    if last > first:
        yield slice(first, last), *(slice(0, n) for n in shape[1:])
    if tail:
        for box in flat_boxes(0, tail, shape[1:]):
            yield slice(last, last + 1), *box


@dataclasses.dataclass(frozen=True)
class Chunking:
    """The chunks of a grid: ``run`` indices of axis ``axis`` times every later axis whole.

    Each chunk is one index of the axes before ``axis`` and a run along it, so it is both a
    contiguous range of flat cells and a box of the array (the last run along ``axis`` may be
    shorter). Chunks are numbered in C order; chunk ``k`` covers the same cells in every run
    with the same chunking, which is what a resume relies on.
    """

    shape: tuple[int, ...]
    axis: int
    run: int

    @classmethod
    def at_most(cls, shape: tuple[int, ...], cells: int) -> Chunking:
        """The largest chunks of at most ``cells`` cells (at least one), whole lines if they fit.

        The outermost axis whose later axes hold at most ``cells`` cells is cut into runs.
        """
        cells = max(cells, 1)
        axis = next(k for k in range(len(shape)) if math.prod(shape[k + 1:]) <= cells)
        return cls(tuple(shape), axis, min(shape[axis], cells // math.prod(shape[axis + 1:])))

    @property
    def box(self) -> tuple[int, ...]:
        """The shape of a (full) chunk."""
        return (1,) * self.axis + (self.run,) + self.shape[self.axis + 1:]

    @property
    def cells(self) -> int:
        """The number of cells of a (full) chunk."""
        return math.prod(self.box)

    @property
    def count(self) -> int:
        """The number of chunks."""
        return math.prod(self.shape[:self.axis]) * -(-self.shape[self.axis] // self.run)

    def bounds(self, chunk: int) -> tuple[int, int]:
        """The flat cells start..stop of chunk number ``chunk``."""
        per_line = -(-self.shape[self.axis] // self.run)
        outer, j = divmod(chunk, per_line)
        line = math.prod(self.shape[self.axis + 1:])
        first = outer * self.shape[self.axis] + j * self.run
        last = outer * self.shape[self.axis] + min((j + 1) * self.run, self.shape[self.axis])
        return first * line, last * line


MAX_COLUMN_CELLS = 4096  # a first-impact map's columns: at most this many cells each
_AFFINE_AXES = {"force_amplitude": layout.CELL_F0, "clearance": layout.CELL_CLEARANCE,
                "base_amplitude": layout.CELL_U0}


@dataclasses.dataclass(frozen=True)
class Columns:
    """A chunk's first-impact columns.

    Cells ``start..stop`` (the chunk widened to whole columns), column c being
    ``bounds[c]..bounds[c + 1]`` of them, along the cell column ``key`` (kernels.layout).
    """

    start: int
    stop: int
    bounds: np.ndarray
    key: int


def by_columns(sweep: Sweep) -> bool:
    """Whether a first-impact map runs by columns: its last axis is F0, U0 or the clearance."""
    return bool(sweep.axes) and sweep.axes[-1].name in _AFFINE_AXES and sweep.axes[-1].num > 1


def first_impact_columns(sweep: Sweep, start: int, stop: int) -> Columns:
    """The columns of flat cells ``start..stop`` along the sweep's last axis, if affine.

    The gap is affine in F0 and in the clearance, so a run of cells along such an axis shares
    one modal response (kernels.first_impact). Columns are fixed segments of the grid (at
    most ``MAX_COLUMN_CELLS`` of the last axis), and a chunk is widened to whole columns, so
    that every cell's result is the same for any chunking. Other sweeps: columns of one cell.
    """
    if not by_columns(sweep):
        return Columns(start, stop, np.arange(stop - start + 1, dtype=np.int64),
                       layout.CELL_F0)
    last = sweep.axes[-1]
    length = min(last.num, MAX_COLUMN_CELLS)
    rows = np.arange(start // last.num, (stop - 1) // last.num + 1, dtype=np.int64)
    # the segments tile each row and the rows follow each other: one edge per segment start
    starts = (rows[:, None] * last.num + np.arange(0, last.num, length)).ravel()
    ends = np.minimum(starts + length, (starts // last.num + 1) * last.num)
    touched = (ends > start) & (starts < stop)
    starts, end = starts[touched], int(ends[touched][-1])
    return Columns(int(starts[0]), end, np.append(starts, end) - starts[0],
                   _AFFINE_AXES[last.name])


def first_impact_kernel(sweep: Sweep, parallel: bool = True) -> str:
    """The name of the first-impact map kernel that every chunk of ``sweep`` calls.

    A map of one block runs on one thread either way: the serial twin, which compiles faster.
    A larger map calls the parallel twin for all its chunks, its last short one too, since each
    twin compiles its callees anew (`kernels.jit`: they are linked into it, not cached alone).
    """
    from impactbeams.kernels.first_impact import _BLOCK

    return ("first_impact_map_parallel" if parallel and sweep.size > _BLOCK
            else "first_impact_map_serial")


def entry_kernel(sweep: Sweep) -> str:
    """The kernel, of its kind's in `compilation.ENTRY_KERNELS`, that ``sweep``'s chunks call.

    A long-time sweep calls the stepped map's kernel when stepped, the stroboscope's when not:
    each compiles apart (a stepped sweep after a plain one compiled 169 kernels); the serial
    twins, which a local run calls. Other kinds: `first_impact_kernel` (used by a first map).
    """
    if sweep.long_time is not None:
        return "stepped_map_serial" if sweep.stepping is not None else "stroboscope_map_serial"
    return first_impact_kernel(sweep)


def compute_chunk(sweep: Sweep, start: int, stop: int, parallel: bool = True,
                  plan: Plan | None = None) -> dict[str, np.ndarray]:
    """Observables of the flat cells ``start..stop`` of ``sweep`` (one array per observable).

    Self-contained, so that any process (a Dask worker, say) can compute any chunk; pass the
    sweep's ``plan`` (`build_plan`) to reuse it across chunks. A first-impact-only sweep
    runs the free phase alone; any other observable runs the full dynamics of every cell over
    [0, t_max] (and gives the first impact time from it too), except the long-time ones, which
    run each cell over (transient + sampled) forcing periods (`impactbeams.longtime`);
    ``dynamics_status`` is then the worse of the runs'.
    """
    from impactbeams.kernels import first_impact

    if plan is None:
        plan = build_plan(sweep)
    if plan.fingerprint != sweep.fingerprint():
        raise ValueError("the plan was built for another sweep")
    if plan.per_contact:
        return (_several_dynamics(sweep, start, stop, parallel) if sweep.needs_dynamics
                else _first_contact(sweep, start, stop, parallel, plan))
    if plan.switching is None:
        columns = first_impact_columns(sweep, start, stop)
        cells = chunk_cells(sweep, plan, columns.start, columns.stop)
        kernel = getattr(first_impact, first_impact_kernel(sweep, parallel))
        out = np.empty(cells.shape[0])
        kernel(cells, columns.bounds, columns.key, plan.tables, plan.geometry, sweep.t_max, out)
        out = out[start - columns.start:stop - columns.start]
        undecided = np.flatnonzero(np.isneginf(out))  # kernels.events.GAVE_UP
        if undecided.size:
            raise RuntimeError(f"{undecided.size} cells of cells {start}..{stop} reached the "
                               f"event search's step cap (first: cell {start + undecided[0]}); "
                               "please report this as a bug")
        return {FIRST_IMPACT: np.ascontiguousarray(out)}
    cells = chunk_cells(sweep, plan, start, stop)
    columns = {}
    if any(name in (FIRST_IMPACT, *DYNAMICS_OBSERVABLES) for name in sweep.observables):
        from impactbeams.kernels import observables  # not for a first-impact map

        kernel = (observables.observables_map_parallel if parallel
                  else observables.observables_map_serial)
        out = np.empty((cells.shape[0], len(layout.OUT_COLUMNS)))
        kernel(cells, plan.tables, plan.switching, plan.geometry, sweep.t_max, MAX_SEGMENTS,
               out)
        columns = dict(zip(layout.OUT_COLUMNS, out.T, strict=True))
    if LYAPUNOV in sweep.observables:
        columns.update(_lyapunov_columns(sweep, plan, cells, parallel, columns))
    if sweep.long_time is not None:
        long_run = (_long_run(sweep.long_time, sweep.transient_periods, plan, cells, parallel)
                    if sweep.stepping is None else
                    _with_end_states(sweep, *_stepped_run(
                        sweep, plan, cells, stepped_rows(sweep, start, stop), parallel)))
        long_run["dynamics_status"] = np.maximum(
            long_run["dynamics_status"], columns.get("dynamics_status", 0))
        columns.update(long_run)
    return {name: np.ascontiguousarray(columns[name]) for name in sweep.stored}


def _long_run(long_time: LongTime, transient_periods: int, plan: Plan, cells: np.ndarray,
              parallel: bool) -> dict[str, np.ndarray]:
    """The long-time observables of every cell and its run's ``dynamics_status``.

    Each cell runs (transient + sampled) forcing periods, in windows of LONG_RUN_CAPACITY.
    """
    import numba

    from impactbeams.kernels import stroboscope
    from impactbeams.longtime import long_time_values

    kernel = (stroboscope.stroboscope_map_parallel if parallel
              else stroboscope.stroboscope_map_serial)
    omega = cells[:, layout.CELL_FORCING_FREQUENCY]
    samples = np.empty((cells.shape[0], long_time.sampled_periods, len(layout.TIP_COLUMNS)))
    summary = np.empty((cells.shape[0], len(layout.STROBOSCOPE_COLUMNS)))
    # cells differ in cost by orders of magnitude (a rattle at every period, or no contact at
    # all): the threads take them one at a time instead of in equal contiguous blocks
    with numba.parallel_chunksize(1):
        kernel(cells, plan.tables, plan.switching, plan.geometry,
               long_time.sample_times(omega, transient_periods),
               long_time.horizon(omega, transient_periods), LONG_RUN_CAPACITY,
               MAX_PHASES_PER_PERIOD, samples, summary)
    return long_time_values(long_time, transient_periods, omega,
                            cells[:, layout.CELL_CLEARANCE], samples, summary)


def stepped_rows(sweep: Sweep, start: int, stop: int) -> np.ndarray:
    """The stepped rows of flat cells ``start..stop`` (whole rows), as cell indices from start.

    Row r runs cells ``rows[r, 0], rows[r, 1], ...`` in that order: increasing along the
    stepped axis up, decreasing down.
    """
    blocks, offset = [], 0
    step = sweep.stepped_dimension
    for box in flat_boxes(start, stop, sweep.shape):
        shape = tuple(s.stop - s.start for s in box)
        cells = np.moveaxis(offset + np.arange(math.prod(shape)).reshape(shape), step, -1)
        directions = np.moveaxis(np.broadcast_to(
            np.arange(box[0].start, box[0].stop).reshape((-1,) + (1,) * (len(shape) - 1)),
            shape), step, -1)[..., 0].ravel()
        if shape[step] != sweep.shape[step]:
            raise ValueError(f"cells {start}..{stop} do not hold whole stepped rows")
        rows = cells.reshape(-1, shape[step])
        down = np.array(sweep.stepping.directions)[directions] == "down"
        rows[down] = rows[down, ::-1]
        blocks.append(rows)
        offset += math.prod(shape)
    return np.ascontiguousarray(np.concatenate(blocks), dtype=np.int64)


def _stepped_run(sweep: Sweep, plan: Plan, cells: np.ndarray, rows: np.ndarray,
                 parallel: bool) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The long-time observables of stepped ``rows`` of ``cells`` (`stepped_rows`).

    Also the carried states: each cell's start and end phase (``NO_STATE``: its own start,
    or a run that stopped early) and state (rows q, q' as observed; NaN with ``NO_STATE``).
    """
    from impactbeams.kernels import stroboscope
    from impactbeams.longtime import long_time_values

    long_time, transient = sweep.long_time, sweep.transient_periods
    kernel = stroboscope.stepped_map_parallel if parallel else stroboscope.stepped_map_serial
    omega = cells[:, layout.CELL_FORCING_FREQUENCY]
    samples = np.empty((cells.shape[0], long_time.sampled_periods, len(layout.TIP_COLUMNS)))
    summary = np.empty((cells.shape[0], len(layout.STROBOSCOPE_COLUMNS)))
    carried = {name: np.empty(cells.shape[0], dtype=np.int64)
               for name in ("start_phase", "end_phase")}
    carried.update({name: np.empty((cells.shape[0], 2, plan.tables.shape[-1]))
                    for name in ("start_state", "end_state")})
    kernel(cells, rows, plan.tables, plan.switching, plan.geometry,
           long_time.sample_times(omega, transient), long_time.horizon(omega, transient),
           LONG_RUN_CAPACITY, MAX_PHASES_PER_PERIOD, samples, summary, carried["start_phase"],
           carried["start_state"], carried["end_phase"], carried["end_state"])
    return (long_time_values(long_time, transient, omega, cells[:, layout.CELL_CLEARANCE],
                             samples, summary), carried)


def _with_end_states(sweep: Sweep, values: dict[str, np.ndarray],
                     carried: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A stepped run's ``values`` with each cell's end state, (q, q') as `simulate` stores it.

    NaN where the run stopped early, and (as `simulate`'s) where a tied-law run ends in
    contact, whose coordinates are the contact modes'.
    """
    end = carried["end_state"][:, :, :sweep.free_coordinates].copy()
    if sweep.base.law.projects:  # the contact modes' coordinates, not the free ones
        end[carried["end_phase"] == layout.CONTACT] = np.nan
    return {**values, **dict(zip(STEPPED_END_STATE, (end[:, 0], end[:, 1]), strict=True))}


def _lyapunov_columns(sweep: Sweep, plan: Plan, cells: np.ndarray, parallel: bool,
                      columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The cells' largest Lyapunov exponents, each from its own windowed run, and the status.

    The status is the worse of that run's and the other observables' run (if any).
    """
    from impactbeams.kernels import lyapunov

    kernel = lyapunov.lyapunov_map_parallel if parallel else lyapunov.lyapunov_map_serial
    out = np.empty((cells.shape[0], 2))
    kernel(cells, plan.tables, plan.switching, plan.geometry, sweep.t_max,
           sweep.transient_periods, MAX_SEGMENTS, out)
    status = np.maximum(out[:, 1], columns.get("dynamics_status", out[:, 1]))
    return {LYAPUNOV: out[:, 0], "dynamics_status": status}
