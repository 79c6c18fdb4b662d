"""Parameter sweeps: definitions (TOML), validation, chunked parallel runs that resume.

A sweep file (names as in :mod:`impactbeams.params`)::

    t_max = 1.0                          # s, horizon of every cell
    n_modes = 5                          # free modes per beam (contact phase: 2 n_modes)
    observables = ["first_impact_time"]  # default
    [params]                             # fixed parameters; the rest take the defaults
    clearance = 1.1e-5
    [axes.omega]                         # one table per swept parameter, in order
    min = 10.0
    max = 600.0
    num = 400
    scale = "linear"                     # or "log"

The grid is flattened and computed in chunks; each finished chunk is saved at once under
``OUT.nc.partial/``, so an interrupted run (Ctrl-C or a killed process) loses no finished work
and the same command resumes it. The final netCDF is written to a temporary file and renamed,
so it is never left half-written.
"""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
import itertools
import json
import os
import shutil
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from impactbeams import __version__
from impactbeams.io import write_netcdf
from impactbeams.params import (
    DAMPING_LAW,
    LONG_NAMES,
    MATERIAL_KEYS,
    MATERIAL_UNITS,
    UNITS,
    ParameterError,
    Params,
    read_toml,
    require,
)
from impactbeams.variables import attributes

FIRST_IMPACT = "first_impact_time"
DYNAMICS_OBSERVABLES = ("impact_count", "max_contact_force", "mean_restitution",
                        "contact_fraction")
OBSERVABLES = (FIRST_IMPACT, *DYNAMICS_OBSERVABLES)
CELL_PARAMETERS = ("clearance", "force_amplitude", "omega", "uplift1", "uplift2",
                   "damping_ratio")
_TOP_LEVEL = ("t_max", "n_modes", "observables", "params", "axes")
_AXIS_KEYS = ("min", "max", "num", "scale")
_MAX_MODES = 200
MAX_SEGMENTS = 100_000  # phases per cell in a full-dynamics sweep; more: dynamics_status = 1


def parameter_names() -> dict[str, str]:
    """Every parameter that can be fixed or swept, with its unit."""
    names = dict(UNITS)
    names.update({k + i: MATERIAL_UNITS[k] for k in MATERIAL_KEYS for i in ("1", "2")})
    return names


@dataclasses.dataclass(frozen=True)
class Axis:
    """One swept parameter: ``num`` values from ``min`` to ``max`` on a linear or log scale."""

    name: str
    min: float
    max: float
    num: int
    scale: str

    @property
    def values(self) -> np.ndarray:
        """The axis values, in the parameter's unit."""
        if self.num == 1:
            return np.array([self.min])
        space = np.geomspace if self.scale == "log" else np.linspace
        return space(self.min, self.max, self.num)


@dataclasses.dataclass(frozen=True)
class Sweep:
    """A validated sweep definition (see the module docstring)."""

    t_max: float
    n_modes: int
    observables: tuple[str, ...]
    fixed: Mapping[str, Any]
    axes: tuple[Axis, ...]
    source: str = "sweep"

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one entry per axis."""
        return tuple(axis.num for axis in self.axes)

    @property
    def size(self) -> int:
        """Number of cells."""
        return int(np.prod(self.shape))

    def definition(self) -> dict[str, Any]:
        """The sweep as a plain dict in the TOML file's layout (canonical, for hashing)."""
        return {"t_max": self.t_max, "n_modes": self.n_modes,
                "observables": list(self.observables), "params": dict(self.fixed),
                "axes": {a.name: {"min": a.min, "max": a.max, "num": a.num, "scale": a.scale}
                         for a in self.axes}}

    @property
    def base(self) -> Params:
        """The fixed parameters (defaults for the rest), before any axis is applied."""
        return Params.from_mapping(self.fixed, source=f"[params] of {self.source}")

    def fingerprint(self) -> str:
        """Hash of the definition and package version: a resumed run must match it."""
        text = json.dumps({"sweep": self.definition(), "version": __version__}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep TOML file; errors name the key and the value."""
    return sweep_from_mapping(read_toml(path), source=str(path))


def sweep_from_mapping(data: Mapping[str, Any], source: str = "sweep") -> Sweep:
    """Validate a sweep given as a mapping in the TOML file's layout."""
    for key in data:
        require(f"{key!r} in {source}", key, key in _TOP_LEVEL,
                f"unknown key; allowed top-level keys: {', '.join(_TOP_LEVEL)}")
    t_max = _number(data.get("t_max", 1.0), f"t_max in {source}")
    require(f"t_max in {source}", t_max, t_max > 0, "must be > 0", "s")
    n_modes = data.get("n_modes", 5)
    require(f"n_modes in {source}", n_modes,
            isinstance(n_modes, int) and not isinstance(n_modes, bool)
            and 1 <= n_modes <= _MAX_MODES, f"must be an integer from 1 to {_MAX_MODES}")
    observables = tuple(data.get("observables", [FIRST_IMPACT]))
    for name in observables:
        require(f"observables in {source}", name, name in OBSERVABLES,
                f"unknown observable; allowed: {', '.join(OBSERVABLES)}")
    require(f"observables in {source}", list(observables), len(observables) > 0,
            "must name at least one observable")
    fixed = dict(data.get("params", {}))
    base = Params.from_mapping(fixed, source=f"[params] of {source}")
    axes_table = data.get("axes", {})
    require(f"[axes] of {source}", axes_table, isinstance(axes_table, dict) and axes_table,
            "a sweep needs at least one [axes.NAME] table")
    axes = tuple(_axis(name, spec, source) for name, spec in axes_table.items())
    sweep = Sweep(t_max, n_modes, observables, fixed, axes, source)
    _check_grid(sweep, base)
    return sweep


def _number(value: Any, name: str) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)
    require(name, value, ok, "must be a finite number")
    return float(value)


def _axis(name: str, spec: Any, source: str) -> Axis:
    where = f"[axes.{name}] of {source}"
    require(where, name, name in parameter_names(),
            f"unknown parameter; allowed: {', '.join(parameter_names())}")
    require(where, spec, isinstance(spec, dict), "must be a table with min, max, num, scale")
    for key in spec:
        require(f"{key!r} in {where}", key, key in _AXIS_KEYS,
                f"unknown key; allowed: {', '.join(_AXIS_KEYS)}")
    for key in ("min", "max", "num"):
        require(f"{key} in {where}", None, key in spec, "is required")
    lo, hi = _number(spec["min"], f"min in {where}"), _number(spec["max"], f"max in {where}")
    num, scale = spec["num"], spec.get("scale", "linear")
    require(f"num in {where}", num, isinstance(num, int) and not isinstance(num, bool)
            and num >= 1, "must be an integer >= 1")
    require(f"scale in {where}", scale, scale in ("linear", "log"), 'must be "linear" or "log"')
    require(f"max in {where}", hi, hi > lo or (hi == lo and num == 1),
            f"the range [{lo!r}, {hi!r}] is empty or reversed: need max > min "
            "(or max == min with num = 1)")
    if scale == "log":
        require(f"min in {where}", lo, lo > 0, "a log axis needs min > 0")
    return Axis(name, lo, hi, num, scale)


def _check_grid(sweep: Sweep, base: Params) -> None:
    """Reject a grid with any non-physical point before computing anything.

    Single-parameter limits are checked on every axis value; the one joint condition, the
    initial gap clearance + uplift1 - uplift2 > 0, on the whole grid.
    """
    for axis in sweep.axes:
        for value in axis.values:
            try:
                base.replace(**{axis.name: float(value)})
            except ParameterError as error:
                raise ParameterError(f"axis {axis.name!r} of {sweep.source} reaches a "
                                     f"non-physical point: {error}") from None
    grids = _cell_grids(sweep, base)
    gap = grids["clearance"] + grids["uplift1"] - grids["uplift2"]
    if np.any(gap <= 0):
        bad = np.unravel_index(np.argmin(gap), gap.shape)
        point = {a.name: float(a.values[i]) for a, i in zip(sweep.axes, bad, strict=True)}
        raise ParameterError(f"the grid of {sweep.source} has points where the initial gap "
                             f"clearance + uplift1 - uplift2 <= 0, e.g. at {point}")


def _cell_grids(sweep: Sweep, base: Params) -> dict[str, np.ndarray]:
    """Per-cell values of the cell parameters, broadcast to the grid shape."""
    grids = {}
    for name in CELL_PARAMETERS:
        grids[name] = np.full(sweep.shape, getattr(base, name))
        for k, axis in enumerate(sweep.axes):
            if axis.name == name:
                shape = [1] * len(sweep.axes)
                shape[k] = axis.num
                grids[name] = np.broadcast_to(axis.values.reshape(shape), sweep.shape).copy()
    return grids


# ---------------------------------------------------------------------------------------------
# Running a sweep


@dataclasses.dataclass(frozen=True)
class _Plan:
    """What the kernels need per geometry, and how cells map to geometries.

    Free-phase tables always (the first-impact kernel); the contact phase and projections only
    when a full-dynamics observable is asked for (see kernels.observables for the layout).
    """

    base: Params
    tables: np.ndarray  # (geometries, len(TABLE_ROWS), 2 n_modes)
    compliance: np.ndarray  # (geometries,) c_1 in m/N
    geometry_axes: tuple[int, ...]  # positions of the axes that change the geometry
    dynamics: tuple[np.ndarray, ...] | None  # (tables, overlaps, shifts, units, geometry)


def _geometries(sweep: Sweep) -> Iterator[Params]:
    """The parameters of every distinct geometry of the grid, in flat geometry-index order."""
    geometry_axes = [k for k, a in enumerate(sweep.axes) if a.name not in CELL_PARAMETERS]
    for combo in itertools.product(*(range(sweep.axes[k].num) for k in geometry_axes)):
        changes = {sweep.axes[k].name: float(sweep.axes[k].values[i])
                   for k, i in zip(geometry_axes, combo, strict=True)}
        yield sweep.base.replace(**changes) if changes else sweep.base


def _dynamics_tables(params: Params, n_modes: int) -> tuple[np.ndarray, ...]:
    """One geometry's arrays for kernels.observables (both phases, projections)."""
    from impactbeams.model import build_model
    from impactbeams.trajectory import phase_tables

    model = build_model(params, n_modes)
    tables, shifts, accumulation = phase_tables(model)
    geometry = np.array([*params.tip_compliance, accumulation])
    units = np.array([model.free.unit1, model.free.unit2])
    return tables, model.overlap, shifts, units, geometry


def _plan(sweep: Sweep) -> _Plan:
    from impactbeams.model import build_free_phase

    tables, compliance, dynamics = [], [], []
    needs_dynamics = any(name in DYNAMICS_OBSERVABLES for name in sweep.observables)
    for params in _geometries(sweep):
        free = build_free_phase(params, sweep.n_modes)
        tables.append([free.omega, free.tip1 - free.tip2, free.drive, free.unit1, free.unit2])
        compliance.append(params.tip_compliance[0])
        if needs_dynamics:
            dynamics.append(_dynamics_tables(params, sweep.n_modes))
    geometry_axes = tuple(k for k, a in enumerate(sweep.axes) if a.name not in CELL_PARAMETERS)
    stacked = tuple(np.array(arrays) for arrays in zip(*dynamics, strict=True)) or None
    return _Plan(sweep.base, np.array(tables), np.array(compliance), geometry_axes, stacked)


def _chunk_cells(sweep: Sweep, plan: _Plan, start: int, stop: int) -> np.ndarray:
    """The packed cell rows (see kernels.first_impact.CELL_COLUMNS) of flat cells start..stop."""
    index = np.unravel_index(np.arange(start, stop), sweep.shape)
    cells = np.empty((stop - start, len(CELL_PARAMETERS) + 1))
    for column, name in enumerate(CELL_PARAMETERS):
        cells[:, column] = getattr(plan.base, name)
        for k, axis in enumerate(sweep.axes):
            if axis.name == name:
                cells[:, column] = axis.values[index[k]]
    geometry_shape = tuple(sweep.axes[k].num for k in plan.geometry_axes)
    geometry_index = tuple(index[k] for k in plan.geometry_axes)
    cells[:, -1] = np.ravel_multi_index(geometry_index, geometry_shape) if geometry_shape else 0
    return cells


_PLANS: dict[str, _Plan] = {}


def _cached_plan(sweep: Sweep) -> _Plan:
    """The sweep's plan, built once per process (workers reuse it across chunks)."""
    key = sweep.fingerprint()
    if key not in _PLANS:
        _PLANS.clear()  # one sweep at a time: keep memory bounded
        _PLANS[key] = _plan(sweep)
    return _PLANS[key]


def compute_chunk(sweep: Sweep, start: int, stop: int,
                  parallel: bool = True) -> dict[str, np.ndarray]:
    """Observables of the flat cells ``start..stop`` of ``sweep`` (one array per observable).

    Self-contained, so that any process (a Dask worker, say) can compute any chunk. A
    first-impact-only sweep runs the free phase alone; any other observable runs the full
    dynamics of every cell over [0, t_max] (and gives the first impact time from it too).
    """
    from impactbeams.kernels import first_impact, observables

    plan = _cached_plan(sweep)
    cells = _chunk_cells(sweep, plan, start, stop)
    if plan.dynamics is None:
        kernel = (first_impact.first_impact_map_parallel if parallel
                  else first_impact.first_impact_map_serial)
        out = np.empty(cells.shape[0])
        kernel(cells, plan.tables, plan.compliance, sweep.t_max, out)
        return {FIRST_IMPACT: out}
    kernel = (observables.observables_map_parallel if parallel
              else observables.observables_map_serial)
    out = np.empty((cells.shape[0], len(observables.OUT_COLUMNS)))
    kernel(cells, *plan.dynamics, sweep.t_max, MAX_SEGMENTS, out)
    columns = dict(zip(observables.OUT_COLUMNS, out.T, strict=True))
    wanted = [*sweep.observables, "dynamics_status"]
    return {name: np.ascontiguousarray(columns[name]) for name in wanted}


Chunk = tuple[int, int, int]  # (chunk number, first flat cell, end flat cell)
ChunkRunner = Callable[[Sweep, list[Chunk]], Iterator[tuple[int, dict[str, np.ndarray]]]]


def local_runner(parallel: bool = True) -> ChunkRunner:
    """Compute chunks one after the other in this process, each over all Numba threads."""
    def run(sweep: Sweep, chunks: list[Chunk]) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
        for chunk, start, stop in chunks:
            yield chunk, compute_chunk(sweep, start, stop, parallel)

    return run


class _ChunkStore:
    """Finished chunks of one sweep, saved one file each, atomically, next to the output.

    The store records the sweep's fingerprint and the chunk size: chunks are numbered, so a
    resumed run must split the grid the same way (it adopts the recorded size).
    """

    def __init__(self, output: Path, fingerprint: str, chunk_cells: int | None,
                 default_chunk_cells: int) -> None:
        self.directory = output.with_name(output.name + ".partial")
        stamp = self.directory / "fingerprint"
        if not self.directory.exists():
            self.directory.mkdir(parents=True)
            self.chunk_cells = chunk_cells or default_chunk_cells
            _atomic_write_text(stamp, f"{fingerprint} {self.chunk_cells}")
            return
        found, _, size = (stamp.read_text().strip() if stamp.exists() else "(none)").partition(" ")
        if found != fingerprint or not size.isdigit():
            raise ParameterError(
                f"{self.directory} holds a partial run of a different sweep (fingerprint "
                f"{found}, this sweep {fingerprint}): delete it or choose another output")
        if chunk_cells is not None and chunk_cells != int(size):
            raise ParameterError(
                f"chunk_cells = {chunk_cells} is not allowed: the partial run in "
                f"{self.directory} was split into chunks of {size} cells; resume with that "
                "size (or without choosing one)")
        self.chunk_cells = int(size)

    def _path(self, chunk: int) -> Path:
        return self.directory / f"chunk_{chunk:06d}.npz"

    def load(self, chunk: int) -> dict[str, np.ndarray] | None:
        """The saved results of a chunk, or None if it is not finished."""
        path = self._path(chunk)
        if not path.exists():
            return None
        with np.load(path) as data:
            return {name: data[name] for name in data.files}

    def save(self, chunk: int, values: dict[str, np.ndarray]) -> None:
        """Save a finished chunk (write to a temporary name, then rename)."""
        path = self._path(chunk)
        temporary = path.with_name(f".{path.name}.tmp")  # never matches chunk_*.npz
        with open(temporary, "wb") as stream:
            np.savez(stream, **values)
        os.replace(temporary, path)

    def remove(self) -> None:
        """Delete the partial results once the final file is written."""
        shutil.rmtree(self.directory)


def _atomic_write_text(path: Path, text: str) -> None:
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_text(text)
    os.replace(temporary, path)


class Progress:
    """Progress bar with ETA on stderr; one line per 10% when stderr is not a terminal.

    The rate behind the ETA is measured from the end of the first computed chunk, which also
    pays for compiling the kernels (until then the ETA shows as unknown).
    """

    def __init__(self, total: int, enabled: bool = True, stream: Any = None) -> None:
        self.total, self.done, self.enabled = total, 0, enabled
        self.stream = stream or sys.stderr
        self.interactive = self.stream.isatty()
        self.start = time.perf_counter()
        self.reported_decile = -1
        self.warm: tuple[float, int] | None = None  # (time, cells done) after the first chunk

    def update(self, cells: int, computed: bool = True) -> None:
        """Record ``cells`` more finished cells (``computed=False``: loaded from a resume)."""
        self.done += cells
        now = time.perf_counter()
        eta = float("nan")
        if computed and self.warm is None:
            self.warm = (now, self.done)
        elif computed and now > self.warm[0]:
            rate = (self.done - self.warm[1]) / (now - self.warm[0])
            eta = (self.total - self.done) / rate
        if not self.enabled:
            return
        fraction = self.done / self.total
        bar = "#" * int(30 * fraction)
        eta_text = "   ?  " if eta != eta else f"{eta:6.1f}"
        line = (f"[{bar:<30}] {100 * fraction:5.1f}% {self.done}/{self.total} cells "
                f"{now - self.start:6.1f} s elapsed, ETA {eta_text} s")
        if self.interactive:
            self.stream.write("\r" + line + ("\n" if self.done == self.total else ""))
        elif int(10 * fraction) > self.reported_decile:
            self.reported_decile = int(10 * fraction)
            self.stream.write(line + "\n")
        self.stream.flush()


def chunk_bounds(size: int, chunk_cells: int) -> list[tuple[int, int]]:
    """Split ``size`` flat cells into consecutive chunks of at most ``chunk_cells``."""
    return [(start, min(start + chunk_cells, size)) for start in range(0, size, chunk_cells)]


def default_chunk_cells(size: int) -> int:
    """About 100 chunks, each between 4096 and 65536 cells (a second or less of work)."""
    return int(min(max(size // 100, 4096), 65536))


def run_sweep(sweep: Sweep, output: str | Path | None = None, threads: int | None = None,
              progress: bool = True, parallel: bool = True, chunk_cells: int | None = None,
              on_chunk: Callable[[int], None] | None = None,
              runner: ChunkRunner | None = None) -> xr.Dataset:
    """Compute a sweep and return its Dataset; with ``output``, also write it as netCDF.

    ``threads``: Numba threads (default: all). With ``output``, finished chunks are kept
    under ``OUTPUT.partial/`` until the file is complete, and a re-run resumes from them.
    ``on_chunk`` is called with each finished chunk number (for tests and monitoring).
    ``runner`` computes the chunks (default: :func:`local_runner`; see
    :mod:`impactbeams.distributed` for a Dask cluster); chunks may finish in any order.
    """
    if threads is not None:
        import numba

        require("threads", threads, isinstance(threads, int) and 1 <= threads
                <= numba.config.NUMBA_NUM_THREADS,
                f"must be an integer from 1 to {numba.config.NUMBA_NUM_THREADS}")
        numba.set_num_threads(threads)
    store = None
    if output is not None:
        output = Path(output)
        finished = _finished_output(output, sweep)
        if finished is not None:
            return finished
        store = _ChunkStore(output, sweep.fingerprint(), chunk_cells,
                            default_chunk_cells(sweep.size))
        chunk_cells = store.chunk_cells
    bounds = chunk_bounds(sweep.size, chunk_cells or default_chunk_cells(sweep.size))
    results = {name: np.full(sweep.size, np.nan) for name in _stored(sweep)}
    bar = Progress(sweep.size, enabled=progress)
    pending = []
    for chunk, (start, stop) in enumerate(bounds):
        saved = store.load(chunk) if store else None
        if saved is None:
            pending.append((chunk, start, stop))
            continue
        for name in results:
            results[name][start:stop] = saved[name]
        bar.update(stop - start, computed=False)
    for chunk, values in (runner or local_runner(parallel))(sweep, pending):
        if store:
            store.save(chunk, values)
        start, stop = bounds[chunk]
        for name in results:
            results[name][start:stop] = values[name]
        bar.update(stop - start)
        if on_chunk:
            on_chunk(chunk)
    dataset = _dataset(sweep, sweep.base, results)
    if output is not None:
        write_netcdf(dataset, output)
        store.remove()
    return dataset


def _stored(sweep: Sweep) -> list[str]:
    """Arrays a chunk yields: the observables, plus the run status of full-dynamics cells."""
    dynamics = any(name in DYNAMICS_OBSERVABLES for name in sweep.observables)
    return [*sweep.observables, *(["dynamics_status"] if dynamics else [])]


def _finished_output(output: Path, sweep: Sweep) -> xr.Dataset | None:
    """The existing result of this very sweep at ``output``, or None if there is none."""
    if not output.exists():
        return None
    with xr.open_dataset(output) as existing:
        if existing.attrs.get("sweep_fingerprint") == sweep.fingerprint():
            return existing.load()
    raise ParameterError(f"{output} exists and holds a different result: delete it or choose "
                         "another output")


def _dataset(sweep: Sweep, base: Params, results: dict[str, np.ndarray]) -> xr.Dataset:
    units = parameter_names()
    coords = {}
    for axis in sweep.axes:
        long_name = LONG_NAMES.get(axis.name, axis.name)
        coords[axis.name] = (axis.name, axis.values,
                             {"units": units[axis.name], "long_name": long_name,
                              "scale": axis.scale})
    dims = [axis.name for axis in sweep.axes]
    data_vars = {name: (dims, values.reshape(sweep.shape), attributes(name))
                 for name, values in results.items()}
    for name, dtype in (("dynamics_status", np.int8), ("impact_count", np.int32)):
        if name in results:  # counts and codes: stored as integers
            data_vars[name] = (dims, results[name].astype(dtype).reshape(sweep.shape),
                               attributes(name))
    if FIRST_IMPACT in results:
        impacted = np.isfinite(results[FIRST_IMPACT]).astype(np.int8).reshape(sweep.shape)
        data_vars["impacted"] = (dims, impacted, attributes("impacted"))
    swept = {axis.name for axis in sweep.axes}
    for i in ("1", "2"):  # a swept material key makes EI_i and rhoA_i vary too
        if any(k + i in swept for k in MATERIAL_KEYS):
            swept |= {"EI" + i, "rhoA" + i}
    fixed = {name: value for name, value in base.as_dict().items() if name not in swept}
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    attrs = {
        "Conventions": "CF-1.8",
        "title": "impactbeams parameter sweep",
        "history": f"{now}: impactbeams {__version__} run {sweep.source}",
        "source": f"impactbeams {__version__}",
        "references": "Dzyubak & Bhaskar, Procedia Engineering 199 (2017) 589-594",
        "t_max": sweep.t_max,
        "t_max_units": "s",
        "n_modes": sweep.n_modes,
        "observables": " ".join(sweep.observables),
        "swept_parameters": " ".join(dims),
        "sweep_definition": json.dumps(sweep.definition(), sort_keys=True),
        "sweep_fingerprint": sweep.fingerprint(),
        "damping_law": DAMPING_LAW,
        **fixed,
    }
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)
