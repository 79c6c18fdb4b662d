"""Two cantilever beams impacting across a clearance: frequencies, trajectories, sweeps, plots.

The command-line interface, a thin argparse layer over the library; the line above is the
description `impactbeams --help` opens with. Subcommands: ``modes`` (natural frequencies),
``run`` (a sweep from a TOML file), ``simulate`` (one full trajectory), ``continue`` (periodic
orbits along a parameter, from a TOML file), ``grazing`` (where the non-impacting orbit first
touches, in closed form), ``basins`` (basins of attraction over a plane of initial states),
``plot`` (draw a saved Dataset), ``contacts`` (which of several contacts closes first and
when, and the contact sequence). Every model
parameter is an option named like the parameter, with dashes
(``--force-amplitude``, ``--EI1``, ``--thickness2``).

Every input (options, files, paths, values, the run's size) is checked before any work starts
or any file is written; a rejected input prints one line ``impactbeams: error: ...`` and exits
with `EXIT_USER_ERROR`.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from impactbeams.configuration import counterpart_named
from impactbeams.params import (
    CHOICES,
    GRAZING_BRACKETS,
    MAX_CHUNK_CELLS,
    MAX_EVENTS,
    MAX_MODES,
    USER_STRUCTURE,
    ParameterError,
    Params,
    modes_per_beam,
    nearest,
    part_field,
    read_toml,
    refuse_beam2,
    refuse_unused_law_keys,
    without_unused_law_keys,
)
from impactbeams.variables import BASIN_POINTS, PARAMETERS

if TYPE_CHECKING:
    import xarray as xr
    from distributed import Client

    from impactbeams.continuation import Continuation
    from impactbeams.continuation.arclength import Point
    from impactbeams.continuation.branch import Branch
    from impactbeams.continuation.twoparameter import CurvePlan
    from impactbeams.orbits.basin_file import BasinPlan
    from impactbeams.sweep import ChunkRunner, Sweep

EXIT_SYSTEM_ERROR = 1  # a file could not be written (full disk, ...) or memory ran out
EXIT_USER_ERROR = 2  # an input was rejected: nothing was computed or written
EXIT_INCOMPLETE = 3  # the result was written, but some runs stopped before t_max
EXIT_INTERRUPTED = 130
GRAZING_POINTS = 201  # frequencies of a grazing curve in a drive or the clearance

_ALIASES = {"force_amplitude": ["--force"]}


def add_parameter_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--params FILE`` and one option per model parameter (SI units)."""
    group = parser.add_argument_group("model parameters (SI units; override --params)")
    group.add_argument("--params", metavar="FILE.toml",
                       help="TOML file with a [params] table (unspecified keys take defaults)")
    for name, parameter in PARAMETERS.items():
        flags = ["--" + name.replace("_", "-"), *_ALIASES.get(name, [])]
        description = parameter.long_name
        if name == "damping_ratio":  # the law itself: docs/model.md, "Modal damping"
            description += " of each cantilever mode, 0 <= zeta < 1"
        if name in CHOICES:
            group.add_argument(*flags, dest=name, choices=CHOICES[name],
                               help=f"{description} (default: {CHOICES[name][0]})")
            continue
        group.add_argument(*flags, dest=name, type=_number, metavar="VALUE",
                           help=f"{description} ({parameter.units})")
    group.add_argument("--structure1", metavar="FILE.npz",
                       help="beam 1 as your own structure: mass and stiffness matrices or modal "
                       "data (docs/model.md, \"Your own structure\"); with the spring law")


def params_from_args(args: argparse.Namespace) -> Params:
    """The parameters of --params (or the defaults) with the command-line overrides applied."""
    from impactbeams.preflight import require_input_file

    params = (Params.from_toml(require_input_file(args.params, "--params")) if args.params
              else Params())
    overrides = {n: getattr(args, n) for n in (*PARAMETERS, USER_STRUCTURE)
                 if getattr(args, n, None) is not None}
    if not counterpart_named(overrides.get("counterpart", params.counterpart)).has_beam2:
        refuse_beam2([f"--{n.replace('_', '-')}" for n in overrides], "the command line")
    refuse_unused_law_keys(overrides, params.contacts,
                           f"the command line (beside the contacts of {args.params})")
    return params.replace(**overrides) if overrides else params


def _contact_frequencies(p: Params, n: int) -> list[float]:
    """The lowest ``n`` contact-phase frequencies (rad/s) of the parameters' contact law.

    Tied: the roots of eq. (9) (against a stop: the clamped-pinned beam 1's); spring: the
    undamped contact oscillators at the n_modes that resolve the contact (at least n).
    """
    if p.law.projects:  # its own contact modes; no SciPy: eq. (9) is solved by impactbeams.brent
        from impactbeams.modes import contact_frequencies

        return contact_frequencies(p, n).tolist()
    from impactbeams.contact import build_free_phase, recommended_modes, spring_contact

    free = build_free_phase(p, max(n, recommended_modes(p)))
    spring = spring_contact(free, free.point_compliance, 0.0, p.contact_stiffness)
    return spring.frequencies[:n].tolist()


def _modes(args: argparse.Namespace) -> int:
    """``modes``: the free beams' frequencies, then each contact's contact phase's.

    Several contacts: the free modes are the structure's (no contact acts in them), and each
    contact's column is its contact phase closed alone, what one contact prints (its run,
    `Params.each_contact`).
    """
    from impactbeams.modes import beam

    p = params_from_args(args)
    beams = ("beam1", "beam2")[:p.partner.beams]
    runs = p.each_contact()
    contact = [_contact_frequencies(run, args.n) for run in runs]
    result = {
        "free": {name: beam(p, int(name[-1])).free_modes(args.n).frequencies.tolist()
                 for name in beams},
        "contact_law": p.contact_law,
        "counterpart": p.counterpart,
        **({"contacts": [{"contact": _contact_words(p, i), "frequencies": frequencies}
                         for i, frequencies in enumerate(contact)]}
           if p.several_contacts else {"contact": contact[0]}),
        **({"structure1": p.structure1.describe(args.n)} if p.structure1 is not None else {}),
    }
    if args.json:
        print(json.dumps(result))
        return 0
    against = f" {p.partner.words}" if p.partner.words else ""
    if p.structure1 is not None:  # its eigenproblem: size, method, memory
        print(p.structure1.describe(args.n))
    names = [f"contacts[{i}]" for i in range(len(runs))] if p.several_contacts else ["contact"]
    print(f"natural frequencies (rad/s); contact phase of the {p.contact_law} law{against}"
          + (", each contact closed alone:" if p.several_contacts else ""))
    for i in range(len(runs) if p.several_contacts else 0):
        print(f"  {_contact_words(p, i)}")
    print(f"{'mode':>4} " + " ".join(f"{'beam ' + b[-1] + ' free':>16}" for b in beams)
          + "".join(f" {name:>16}" for name in names))
    for i in range(args.n):
        row = (*(result["free"][b][i] for b in beams), *(column[i] for column in contact))
        print(f"{i + 1:>4} " + " ".join(f"{w:16.6f}" for w in row))
    return 0


def _run(args: argparse.Namespace) -> int:
    from impactbeams.lock import output_lock
    from impactbeams.preflight import require_input_file
    from impactbeams.sweep import load_sweep
    from impactbeams.sweep.plan import check_contact_phases, reusing_geometries
    from impactbeams.sweep.store import reporting_kept_chunks

    if "basins" in read_toml(require_input_file(args.sweep, "sweep")):  # the basins kind
        return _run_basins(args)
    sweep = load_sweep(args.sweep)
    output = _sweep_output(args, sweep)
    _check_scheduler(args.scheduler)
    _check_threads(args)
    with reusing_geometries():  # the check's geometries are the plan's
        check_contact_phases(sweep)
        with reporting_kept_chunks(output), output_lock(output):  # before anything is printed,
            return _locked_run(args, sweep, output)  # created or computed


def _locked_run(args: argparse.Namespace, sweep: Sweep, output: Path) -> int:
    """``run`` once its output is locked: compute (or reuse) the map, check its statuses."""
    from impactbeams.sweep import write_sweep  # writes netCDF without xarray
    from impactbeams.sweep.definition import run_kind
    from impactbeams.sweep.plan import entry_kernel

    reuse = output.exists()
    if not reuse and not args.quiet:
        _announce(sweep, output, args)
    try:
        # a reused output computes nothing: Numba need not load to watch for compiles
        compiling = (contextlib.nullcontext() if reuse
                     else _running_kernels(run_kind(sweep), args, entry_kernel(sweep)))
        with _cluster_runner(args) as runner, compiling:
            write_sweep(sweep, output, threads=None if runner else args.threads,
                        progress=not args.quiet, chunk_cells=args.chunk_cells, runner=runner,
                        discard_corrupt=args.discard_corrupt)
    except KeyboardInterrupt:
        print(f"\nimpactbeams: finished chunks are kept in {output}.partial/ "
              "and the same command resumes from them", file=sys.stderr)
        raise
    _say(args, f"reused {output}: it already holds the result of this sweep (nothing computed)"
         if reuse else f"wrote {output}")
    if not sweep.needs_dynamics:  # no run status to check: xarray need not load
        return 0
    import xarray as xr

    with xr.open_dataset(output) as dataset:
        return _incomplete_cells(dataset)


def _sweep_output(args: argparse.Namespace, sweep: Sweep) -> Path:
    """The checked output of ``run``: a writable .nc path with room on its disk.

    An existing file there must be a netCDF file of impactbeams (reused if it is this sweep's).
    """
    from impactbeams.preflight import require_disk, require_netcdf, require_output_file
    from impactbeams.sweep.estimate import expected_file_size

    output = require_output_file(args.output or Path("results") / (Path(args.sweep).stem + ".nc"),
                                 "-o/--output", {".nc"}, "netCDF")
    if output.exists():
        # readable; store.finished_output then checks it against the sweep and the registry
        require_netcdf(output, "output")
    else:
        require_disk(output, expected_file_size(sweep), "-o/--output")
    return output


def _announce(sweep: Sweep, output: Path, args: argparse.Namespace) -> None:
    """The run's size, expected cost and destination, on stderr."""
    from impactbeams.compilation import kernels_cached
    from impactbeams.costs import compile_estimate
    from impactbeams.sweep.definition import run_kind
    from impactbeams.sweep.estimate import expected_cost
    from impactbeams.sweep.plan import entry_kernel

    long_time = sweep.long_time
    horizon = (f"t_max = {sweep.t_max} s" if long_time is None else
               f"{sweep.transient_periods} + {long_time.sampled_periods} forcing periods")
    stepping = sweep.stepping
    rows = ("" if stepping is None else
            f" (stepped {' and '.join(stepping.directions)} along {stepping.axis})")
    grid = f"{' x '.join(map(str, sweep.shape))} = " if len(sweep.shape) > 1 else ""
    print(f"{sweep.source}: {grid}{sweep.size} cells over "
          f"{', '.join(a.name for a in sweep.axes)}{rows}; {horizon}, "
          f"{modes_per_beam(sweep.n_modes, sweep.base.partner)} -> {output}\nexpected: "
          f"{expected_cost(sweep, args.threads).describe()}"
          + ("" if kernels_cached(run_kind(sweep), entry_kernel(sweep)) else
             f", after compiling its kernels (once per install), expected "
             f"{compile_estimate(run_kind(sweep), entry_kernel(sweep)).describe()}"),
          file=sys.stderr)


def _running_kernels(kind: str, args: argparse.Namespace, entry: str | None = None,
                     ) -> contextlib.AbstractContextManager[None]:
    """Lines on stderr while the kernels of a run of ``kind`` compile (if they do).

    ``entry``: the kernel the run calls, of its kind's (`impactbeams.sweep.plan.entry_kernel`):
    whether it is cached, and for a first map the compile time expected of its twin
    (`impactbeams.costs.compile_estimate`). In the command's own process, cached kernels load
    with only what running them needs (`impactbeams.cached_kernels`).
    """
    from impactbeams.compilation import kernels_cached, reporting_compiles
    from impactbeams.costs import compile_estimate

    if args.own_process:
        from impactbeams.cached_kernels import load_cached_kernels_lean

        load_cached_kernels_lean()
    if args.quiet:
        return contextlib.nullcontext()
    cached = kernels_cached(kind, entry)
    return reporting_compiles(None if cached else compile_estimate(kind, entry), cached)


def _incomplete_cells(dataset: xr.Dataset) -> int:
    """Warn about cells whose dynamics stopped before t_max; the exit code of the run."""
    if "dynamics_status" not in dataset:
        return 0
    import numpy as np

    from impactbeams.variables import DYNAMICS_STATUSES as STATUS_NAMES

    codes, counts = np.unique(dataset["dynamics_status"].values, return_counts=True)
    stopped = {int(code): int(count) for code, count in zip(codes, counts, strict=True) if code}
    if not stopped:
        return 0
    names = ", ".join(f"{count} {STATUS_NAMES[code] if code < len(STATUS_NAMES) else code}"
                      for code, count in stopped.items())
    _warn(f"{sum(stopped.values())} of {dataset['dynamics_status'].size} cells stopped before "
          f"t_max ({names}; see dynamics_status): their observables cover only the part before "
          "the stop")
    return EXIT_INCOMPLETE


def _check_threads(args: argparse.Namespace) -> None:
    """Check --threads of a local run against Numba's limit now, before anything starts."""
    if args.threads is None or args.scheduler or args.local_cluster:
        return
    from impactbeams.sweep.run import numba_threads

    with numba_threads(args.threads):  # raises ParameterError beyond the limit
        pass


# a Dask scheduler address: [PROTOCOL://]HOST:PORT
_SCHEDULER_ADDRESS = re.compile(
    r"^([a-z][a-z0-9+.-]*://)?(\[[0-9a-fA-F:.]+\]|[^\s/:\[\]]+):\d{1,5}$|^inproc://\S+$")


def _check_scheduler(address: str | None) -> None:
    if address is not None and not _SCHEDULER_ADDRESS.match(address):
        raise ParameterError(f"--scheduler {address!r} is not allowed: give the scheduler's "
                             "address as [PROTOCOL://]HOST:PORT, e.g. tcp://node1:8786")


@contextlib.contextmanager
def _cluster_client(args: argparse.Namespace) -> Iterator[Client | None]:
    """A Dask client for --scheduler / --local-cluster (closed on exit), else None."""
    if args.scheduler is None and args.local_cluster is None:
        yield None
        return
    from impactbeams.sweep.dask_runner import dask_client, require_dask

    try:
        require_dask()
    except ImportError as error:
        raise ParameterError(str(error)) from None
    with dask_client(args.scheduler, args.local_cluster) as client:
        yield client


@contextlib.contextmanager
def _cluster_runner(args: argparse.Namespace) -> Iterator[ChunkRunner | None]:
    """A Dask chunk runner for --scheduler / --local-cluster (closed on exit), else None."""
    with _cluster_client(args) as client:
        if client is None:
            yield None
            return
        from impactbeams.sweep.dask_runner import dask_runner

        yield dask_runner(client, threads_per_task=args.threads)


def _plot(args: argparse.Namespace) -> int:
    if args.own_process:
        _hide_dask()
    from impactbeams.plotting import parse_assignments, parse_levels, plot_dataset
    from impactbeams.plotting.arrays import read_figure_data
    from impactbeams.plotting.events import chosen_events
    from impactbeams.preflight import image_output, read_netcdf

    chosen_events(args.events, "--events")  # before the file is read
    # a map's file is read without xarray (a third of the start-up), a run's with it
    dataset = read_figure_data(args.dataset, "input")
    output = image_output(args.output or Path(args.dataset).with_suffix(".png"), "-o/--output")
    diagram = read_netcdf(args.over, "--over") if args.over else None
    also = [read_netcdf(path, "--with") for path in args.also]
    for path, curve in zip(args.also, also, strict=True):
        from impactbeams.plotting.curves import is_curve  # with --with only: xarray's import

        if not is_curve(curve):
            raise ParameterError(f"--with file {path!r} is not a curve in a plane of two "
                                 "parameters: a bifurcation curve (impactbeams continue with "
                                 "a [curve]) or a closed-form grazing curve (impactbeams "
                                 "grazing PARAMETER)")
    notes = plot_dataset(dataset, output, args.var,
                         values=parse_assignments(args.slice, "--slice"),
                         indices=parse_assignments(args.slice_index, "--slice-index"),
                         scale=args.scale, contours=parse_levels(args.contours),
                         title=args.title, dpi=args.dpi, diagram=diagram, hz=args.hz,
                         events=args.events, curves=also)
    for note in notes:
        _say(args, f"impactbeams: {note}")
    _say(args, f"wrote {output}")
    return 0


def _hide_dask() -> None:
    """Make Dask look absent to xarray in this process (a plot never computes with it).

    xarray, finding Dask installed, imports it (0.2-0.3 s) to ask of every array whether it is
    one of Dask's, and keeps the answer for the process: hence only in the command's own one.
    """
    sys.modules.setdefault("dask", None)  # type: ignore[arg-type]  # importlib: "not found"


def _continue(args: argparse.Namespace) -> int:
    from impactbeams.continuation import (
        ContinuationInterrupted,
        continue_orbits,
        load_continuation,
    )
    from impactbeams.continuation.checkpoint import (
        CourseLog,
        reporting_kept_points,
        saved_points,
    )
    from impactbeams.continuation.definition import load_curve
    from impactbeams.continuation.run import orbits_problem
    from impactbeams.lock import output_lock
    from impactbeams.preflight import require_input_file
    from impactbeams.sweep.store import partial_folder

    continuation = load_continuation(require_input_file(args.file, "continuation"))
    orbits_problem(continuation)  # what the file alone cannot tell (the subspace's room)
    plan = load_curve(args.file, continuation)
    output = _continuation_output(args, continuation)
    if plan is not None:
        return _continue_curve(args, plan, output)
    with reporting_kept_points(output), output_lock(output):  # before anything is printed
        kept = saved_points(output) if CourseLog(output, continuation).check() else 0
        resumed = (f" (resuming from the {kept} branch points saved in "
                   f"{partial_folder(output)}/)" if kept else "")
        _say(args, f"{args.file}: periodic orbits of period {continuation.period} along "
             f"{continuation.parameter} from {continuation.low:g} to {continuation.high:g} "
             f"({continuation.direction}) -> {output}{resumed}\nexpected: "
             f"{_continuation_cost(continuation)}")
        try:
            with _running_kernels("orbits", args):
                dataset = continue_orbits(continuation, None if args.quiet else _BranchProgress(
                    continuation.low, continuation.high), output)
        except ContinuationInterrupted as interrupted:
            folder = partial_folder(output)
            print(f"\nimpactbeams: the {interrupted.dataset.branch_point.size} branch points "
                  f"computed are in {folder / output.name}; the continuation's steps are kept "
                  f"in {folder}/ and the same command resumes from them", file=sys.stderr)
            raise
    _say(args, f"wrote {output}: {_branch_summary(dataset)}")
    short = _short_branches(dataset, continuation)
    for line in short:
        print(f"impactbeams: warning: {line}", file=sys.stderr)
    return EXIT_INCOMPLETE if short and not args.allow_incomplete else 0


def _continue_curve(args: argparse.Namespace, plan: CurvePlan, output: Path) -> int:
    """``continue`` with a ``[curve]``: the branch, then its event in two parameters.

    Both checkpointed under ``OUT.nc.partial/``: the branch (as ``continue`` without a
    curve) into a file named by its continuation and code, read again by the same command,
    then the curve's steps; interrupted, the same command resumes where it stopped.
    """
    from impactbeams.continuation import ContinuationInterrupted
    from impactbeams.continuation.branch import MAX_POINTS
    from impactbeams.continuation.checkpoint import (
        CourseLog,
        reporting_kept_points,
        saved_points,
    )
    from impactbeams.continuation.twoparameter import continue_curve
    from impactbeams.lock import output_lock
    from impactbeams.sweep.store import partial_folder
    from impactbeams.variables import CURVE_EVENTS

    c = plan.continuation
    folder = partial_folder(output)
    with reporting_kept_points(output), output_lock(output):
        _say(args, f"{args.file}: the {plan.kind} of the branch along {c.parameter} from "
             f"{c.low:g} to {c.high:g} (event {plan.which}), followed in {plan.second} from "
             f"{plan.low:g} to {plan.high:g} -> {output}")
        with _running_kernels("orbits", args):
            curve = plan.from_branch(_curve_branch(args, c, folder))
            kept = saved_points(output) if CourseLog(output, curve).check() else 0
            if kept:
                _say(args, f"resuming the curve from the {kept} points saved in {folder}/")
            progress = None if args.quiet else _BranchProgress(plan.low, plan.high)
            try:
                dataset = continue_curve(curve, progress, output)
            except ContinuationInterrupted as interrupted:
                print(f"\nimpactbeams: the {interrupted.dataset.branch_point.size} curve points "
                      f"computed are in {folder / output.name}; the curve's steps are kept in "
                      f"{folder}/ and the same command resumes from them", file=sys.stderr)
                raise
    first, second = dataset.attrs["curve_parameters"].split()
    located = "; ".join(f"{CURVE_EVENTS[code]} at {first} = {float(dataset[first][i]):.9g}, "
                        f"{second} = {float(dataset[second][i]):.9g}"
                        for i, code in enumerate(dataset.curve_event.values) if code)
    _say(args, f"wrote {output}: {dataset.branch_point.size} points of the {plan.kind} curve "
               f"(ended: {dataset.attrs['curve_ending']}); {located}")
    if dataset.attrs["curve_ending"] != MAX_POINTS:  # its box, or an event, ended it
        return 0
    print(f"impactbeams: warning: the {plan.kind} curve stopped at max_points = "
          f"{plan.max_points}, at {first} = {float(dataset[first][-1]):.9g}, {second} = "
          f"{float(dataset[second][-1]):.9g}, short of its box: raise max_points, or follow it "
          "on from there", file=sys.stderr)
    return 0 if args.allow_incomplete else EXIT_INCOMPLETE


def _curve_branch(args: argparse.Namespace, c: Continuation, folder: Path) -> xr.Dataset:
    """The branch a curve starts from: computed into ``folder`` (checkpointed), or read there.

    Its file is named by the continuation's fingerprint and the code's digest, so that
    another continuation's or other code's branch is never read for it.
    """
    from impactbeams.continuation import ContinuationInterrupted, continue_orbits
    from impactbeams.continuation.checkpoint import CONTINUATION_CODE, fingerprint
    from impactbeams.preflight import read_netcdf
    from impactbeams.sweep.plan import code_digest
    from impactbeams.sweep.store import partial_folder

    path = folder / f"branch_{fingerprint(c)}_{code_digest(patterns=CONTINUATION_CODE)}.nc"
    if path.exists():
        branch = read_netcdf(path, "the saved branch")
        _say(args, f"branch: read from {path}: {_branch_summary(branch)}")
        return branch
    progress = None if args.quiet else _BranchProgress(c.low, c.high)
    try:
        branch = continue_orbits(c, progress, path)
    except ContinuationInterrupted as interrupted:
        print(f"\nimpactbeams: the branch's {interrupted.dataset.branch_point.size} points are "
              f"kept in {partial_folder(path)}/ and the same command resumes from them",
              file=sys.stderr)
        raise
    _say(args, f"branch: {_branch_summary(branch)}")
    return branch


def _grazing(args: argparse.Namespace) -> int:
    """``grazing``: the closed-form grazing curve over [--omega-min, --omega-max], to netCDF."""
    import numpy as np

    from impactbeams.io import write_netcdf
    from impactbeams.lock import output_lock
    from impactbeams.orbits import grazing_curve, grazing_frequencies
    from impactbeams.orbits.grazing import check_grazing_parameter
    from impactbeams.preflight import require_output_file

    output = require_output_file(args.output, "-o/--output", {".nc"}, "netCDF")
    params = params_from_args(args)
    n_modes = args.n_modes or 5
    _require_grazing_options(args)
    check_grazing_parameter(params, args.parameter, ("omega",))
    with output_lock(output):
        if args.parameter == "omega":
            dataset = grazing_frequencies(params, n_modes, args.omega_min, args.omega_max,
                                          args.points or GRAZING_BRACKETS)
        else:
            dataset = grazing_curve(params, n_modes, args.parameter, np.linspace(
                args.omega_min, args.omega_max, args.points or GRAZING_POINTS))
        write_netcdf(dataset, output)
    plane = "grazing frequencies" if args.parameter == "omega" else (
        f"points of the grazing curve in (omega, {args.parameter})")
    _say(args, f"wrote {output}: {dataset.grazing_point.size} {plane}, {n_modes} modes per beam")
    return 0


def _basins(args: argparse.Namespace) -> int:
    """``basins``: the basin map of a plane of initial states (or random ones), to netCDF."""
    from impactbeams.orbits.basin_file import BasinPlan
    from impactbeams.preflight import require_output_file

    output = require_output_file(args.output, "-o/--output", {".nc"}, "netCDF")
    axes = (args.axis1, args.axis2)
    plan = BasinPlan(params_from_args(args), None if axes == (None, None) else axes,
                     args.points, args.random, args.seed, args.coordinates, args.n_modes,
                     args.max_periods, *(None if name is None else Path(name)
                                         for name in (args.states, args.attractors)))
    plan.checked()
    return _basin_map(args, plan, output, args.workers, args.chunk_cells)


def _basin_map(args: argparse.Namespace, plan: BasinPlan, output: Path, workers: int | None,
               chunk_cells: int | None) -> int:
    """The basin map of ``plan`` into ``output`` (``basins``, or ``run`` of a basins file)."""
    from impactbeams.variables import basin_fraction_text

    _check_scheduler(args.scheduler)
    with _cluster_client(args) as client:
        dataset = plan.run(output=output, chunk_cells=chunk_cells, workers=workers,
                           progress=not args.quiet, client=client)
    found = ", ".join(f"{k}: period {int(dataset.attractor_period[k])}, "
                      f"{int(dataset.attractor_contacts[k])} contacts, "
                      f"{basin_fraction_text(dataset, k, plan.random is not None)}"
                      for k in dataset.attractor.values)
    _say(args, f"wrote {output}: {dataset.attrs['cells']} initial states, "
               f"{dataset.attractor.size} attractors ({found or 'none'}); not settled "
               f"{dataset.attrs['not_settled_fraction']:.3g}, stopped "
               f"{dataset.attrs['stopped_fraction']:.3g}")
    return 0


def _run_basins(args: argparse.Namespace) -> int:
    """``run`` of a basins file (a ``[basins]`` table): the basins sweep kind."""
    from impactbeams.orbits.basin_file import load_basins
    from impactbeams.preflight import require_output_file

    plan = load_basins(args.sweep)
    if args.discard_corrupt:
        raise ParameterError("--discard-corrupt is not allowed with a basins file: its saved "
                             "chunks are checked and refused whole (delete OUT.nc.partial/)")
    output = require_output_file(args.output or Path("results") / (Path(args.sweep).stem + ".nc"),
                                 "-o/--output", {".nc"}, "netCDF")
    return _basin_map(args, plan, output, args.threads, args.chunk_cells)


def _range(text: str) -> tuple[float, float]:
    """LOW,HIGH: two numbers (the library checks them against the plane)."""
    parts = text.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be LOW,HIGH")
    return _number(parts[0]), _number(parts[1])


def _index_pair(text: str) -> tuple[int, int]:
    """I,J: two integers (the library checks them against the model's coordinates)."""
    parts = text.split(",")
    if len(parts) == 2 and all(re.fullmatch(r"\s*\d+\s*", part) for part in parts):
        return int(parts[0]), int(parts[1])
    raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be I,J, two integers >= 0")


# options that set nothing of the steady orbit's grazing (its start, its one frequency)
_NOT_GRAZING = ("omega", "uplift1", "uplift2", "start")


def _require_grazing_options(args: argparse.Namespace) -> None:
    """Refuse a range that is empty or not above 0, and options that would be ignored."""
    low, high = args.omega_min, args.omega_max
    if not 0.0 < low < float("inf"):
        raise ParameterError(f"--omega-min = {low!r} is not allowed: must be finite and > 0 "
                             "(rad/s)")
    if not high > low:
        raise ParameterError(f"--omega-max = {high!r} is not allowed: the range [{low!r}, "
                             f"{high!r}] is empty: need --omega-max > --omega-min (rad/s)")
    if part_field(args.parameter) is not None:
        raise ParameterError(f"PARAMETER = {args.parameter!r} is not allowed here: a part's "
                             "field has no closed form, its grazing is a root in it searched "
                             "within a range: grazing_curve(..., within=(low, high)) in Python")
    for name in _NOT_GRAZING:
        if getattr(args, name) is not None:
            raise ParameterError(f"--{name} is not allowed with grazing: the steady orbit does "
                                 "not depend on the start, and the frequencies are "
                                 "--omega-min to --omega-max")


def _continuation_cost(continuation: Continuation) -> str:
    """The expected time of a continuation: per point (calibrated), and at least how many."""
    from impactbeams.continuation.run import fewest_points, mode_count, state_size
    from impactbeams.costs import continuation_point_seconds

    per_point, points = continuation_point_seconds(state_size(continuation)), fewest_points(
        continuation)
    return (f"about {per_point * 1e3:.2g} ms of CPU per branch point with "
            f"{modes_per_beam(mode_count(continuation), continuation.params.partner)} "
            f"(measured on the shipped soft stop: stiffer contacts cost more), and at least "
            f"{points} points at max_step ({per_point * points:.2g} s), after the start "
            f"({continuation.transient_periods} transient periods): a floor only, as each "
            "fold, grazing or change of the contacts located costs tens of corrections more "
            "(a stiff contact's branch has hundreds); the progress lines give the time left "
            "as measured")


def _continuation_output(args: argparse.Namespace, continuation: Continuation) -> Path:
    """The checked output of ``continue``: a writable .nc path with room on its disk."""
    from impactbeams.continuation.checkpoint import expected_log_size
    from impactbeams.preflight import require_disk, require_output_file

    output = require_output_file(args.output or Path("results") / (Path(args.file).stem + ".nc"),
                                 "-o/--output", {".nc"}, "netCDF")
    require_disk(output, expected_log_size(continuation), "-o/--output")
    return output


class _BranchProgress:
    """Progress of a continuation on stderr: each labelled point and every 20th.

    With the parameter, the share of the range the branch has covered and the time left at
    the branch's rate so far. A branch switched at a period doubling says where it started
    instead: it ends where it rejoins its origin, closes a loop or leaves the range, which its
    start does not tell (on the stiff stop going down, a period-2 branch of 0.44 rad/s
    announced 1673 s left to the range's end, where the whole run took 74 s).
    """

    def __init__(self, low: float, high: float) -> None:
        self.low, self.high = low, high
        self.started: dict[int, tuple[float, float]] = {}  # id(branch): (time, parameter)

    def __call__(self, branch: Branch, point: Point) -> None:
        count, p = len(branch.points), point.parameter(branch.scaling)
        start = self.started.setdefault(id(branch), (time.perf_counter(), p))
        if not (point.label or count % 20 == 0):
            return
        print(f"  branch of period {branch.period}, point {count}: {p:.10g} "
              f"({self._course(branch, start, p)}), largest |mu| "
              f"{abs(point.evaluation.multipliers[0]):.4g}, {point.evaluation.contacts} "
              f"contacts per orbit {point.label}", file=sys.stderr)

    def _course(self, branch: Branch, start: tuple[float, float], p: float) -> str:
        """How far the branch has come: the share of the range and the time left, if known."""
        if branch.origin is not None:
            return f"switched at {start[1]:.10g}: where it ends is not known in advance"
        seconds, end = time.perf_counter() - start[0], (
            self.high if p >= start[1] else self.low)
        done = abs(p - start[1]) / max(abs(end - start[1]), 1e-300)
        left = f", about {seconds * (1 - done) / done:.0f} s left" if 0 < done < 1 else ""
        return f"{100 * min(done, 1):.0f} % of the way to {end:g}{left}"


def _branch_summary(dataset: xr.Dataset) -> str:
    """Points, branches, what each covered and how it ended, events found (each once)."""
    import numpy as np

    from impactbeams.variables import BIFURCATIONS, located_events

    codes = dataset["bifurcation"].values
    events = codes[located_events(dataset)]
    counts = [(int(np.count_nonzero(events == code)), name)
              for code, name in enumerate(BIFURCATIONS)]
    found = ", ".join(f"{count} {name}" for count, name in counts if count)
    covered = "; ".join(
        f"branch {number}: {low} to {high} ({ending})" for number, ((low, high), ending)
        in enumerate(zip((c.split(":") for c in dataset.attrs["branch_covered"].split()),
                         dataset.attrs["branch_endings"].split(), strict=True)))
    return (f"{dataset.branch_point.size} points on {int(dataset.branch.max()) + 1} branch(es) "
            f"({covered}); {found or 'no bifurcation'}")


def _short_branches(dataset: xr.Dataset, continuation: Continuation) -> list[str]:
    """A line for each branch that stopped short of its range on its own (stalled, ...)."""
    from impactbeams.continuation.branch import INCOMPLETE

    parameter = continuation.parameter
    lines = []
    for number, ending in enumerate(dataset.attrs["branch_endings"].split()):
        if ending not in INCOMPLETE:
            continue
        branch = dataset.isel(branch_point=(dataset.branch == number).values.nonzero()[0])
        last = branch.isel(branch_point=-1)
        lines.append(
            f"branch {number} ended ({ending}) at {parameter} = {float(last[parameter]):.10g}, "
            f"short of [{continuation.low:g}, {continuation.high:g}], with "
            f"{int(last.contacts_per_orbit)} contacts per orbit and largest |mu| "
            f"{float(last.multiplier_modulus.max()):.4g}: try "
            + ", or ".join(_what_to_try(branch, ending, continuation)))
    return lines


# the last points of a branch whose events tell what it was crossing when it ended
ENDING_POINTS = 10


def _what_to_try(branch: xr.Dataset, ending: str, continuation: Continuation) -> list[str]:
    """What may take a branch that ended short (``ending``) further: only what applies.

    More points for one that ran out of them, a smaller min_step for one whose step fell
    below it; summarising micro-contacts only where the branch was crossing changes of the
    contacts within an episode (merges or splits among its last ``ENDING_POINTS`` points)
    and they are located: at a fold on a grazing (the stiff stop case's period-2 branch)
    summarising changes nothing, and the branch turns back or stops the same. A smaller
    max_step for one that jumped back onto itself. A second run from past the end (of the
    branch's period), or from the other end of the range, always.
    """
    from impactbeams.continuation.arclength import LOCATE
    from impactbeams.continuation.branch import MAX_POINTS, MIN_STEP, RETRACED, STALLED
    from impactbeams.variables import BIFURCATIONS

    remedies = []
    if ending == MAX_POINTS:
        remedies.append(f"a larger max_points (now {continuation.max_points})")
    if ending == MIN_STEP:
        remedies.append("a smaller min_step")
    kinds = {BIFURCATIONS[code] for code in branch.bifurcation.values[-ENDING_POINTS:]}
    if (ending in (MIN_STEP, STALLED) and continuation.micro_contacts == LOCATE
            and kinds & {"contact_merge", "contact_split"}):
        remedies.append('micro_contacts = "summarise" (its last points cross changes of '
                        "the contacts within an impact episode, each located)")
    if ending == RETRACED:
        remedies.append("a smaller max_step (a step jumped back onto the branch)")
    period = int(branch.orbit_period.values[0])
    if period == continuation.period:
        other = "down" if continuation.direction == "up" else "up"
        remedies.append(f"a second run from past it (start =) or from the other end "
                        f"(direction = \"{other}\")")
    else:  # a branch switched to at a period doubling
        remedies.append(f"a second run of period {period} from past it (period = {period}, "
                        "start =)")
    return remedies


def _simulate(args: argparse.Namespace) -> int:
    from impactbeams.costs import clearance_hint
    from impactbeams.io import write_netcdf
    from impactbeams.lock import output_lock
    from impactbeams.preflight import require_output_file
    from impactbeams.trajectory import simulate

    output = require_output_file(args.output, "-o/--output", {".nc"}, "netCDF")
    params = params_from_args(args)
    hint = clearance_hint(params, args.t_max) if 0 < args.t_max < float("inf") else None
    with output_lock(output):  # a second simulate on this output would silently replace it
        if hint:
            _warn(hint)
        with _running_kernels("simulate", args):
            dataset = simulate(params, args.t_max, n_modes=args.n_modes,
                               dt_output=args.dt_output, fields=args.fields,
                               energy_balance=args.energy_balance, lyapunov=args.lyapunov,
                               transient_periods=args.transient_periods,
                               max_events=args.max_events, progress=not args.quiet)
        write_netcdf(dataset, output)
    status = dataset.attrs["status"]
    exponent = (f", largest Lyapunov exponent {float(dataset.lyapunov_exponent):.6g} +- "
                f"{float(dataset.lyapunov_exponent_error):.2g} 1/s" if args.lyapunov else "")
    _say(args, f"wrote {output}: {dataset.impact.size} impacts, status {status}{exponent}")
    return 0 if status == "complete" else EXIT_INCOMPLETE  # simulate() warned already


# the contact sequence's columns as the command prints them: name, heading, format
_SEQUENCE_COLUMNS = (("impact_onset_time", "onset (s)", "{:.10f}"),
                     ("impact_duration", "duration (s)", "{:.4e}"),
                     ("impact_impulse", "impulse (N s)", "{:.4e}"),
                     ("impact_peak_force", "peak force (N)", "{:.4e}"),
                     ("impact_velocity", "gap rate in (m/s)", "{:.4e}"),
                     ("separation_velocity", "gap rate out (m/s)", "{:.4e}"))


def _contacts(args: argparse.Namespace) -> int:
    """``contacts``: which contact closes first and when, and every contact of a sequence.

    The sequence (`impactbeams.contact_sequence`) where it is built (one contact, a two-sided
    stop, contacts closing together, dashpots); where it is refused (contacts closed together
    whose phase is overdamped) its refusal is said, and with -o it is an error (before any
    compute).
    """
    import dataclasses

    from impactbeams.lock import output_lock
    from impactbeams.preflight import require_output_file
    from impactbeams.trajectory.several import (
        check_contact_runs,
        contact_sequence,
        first_contact,
    )

    output = (require_output_file(args.output, "-o/--output", {".nc"}, "netCDF")
              if args.output else None)
    params = params_from_args(args)
    check_contact_runs(params, args.t_max, args.n_modes)
    with output_lock(output) if output else contextlib.nullcontext():
        with _running_kernels("simulate", args):
            try:  # refused before any compute: a file must hold it
                sequence = contact_sequence(params, args.t_max, args.n_modes, args.max_contacts)
                why = None
            except ParameterError as refusal:
                if output is not None and params.several_contacts:
                    raise ParameterError(f"-o/--output: {refusal}") from None
                if output is not None or not params.several_contacts:
                    raise
                sequence, why = None, str(refusal)
            first = first_contact(params, args.t_max, args.n_modes)
        if output is not None:
            from impactbeams.io import write_netcdf

            write_netcdf(_described_sequence(sequence, params, args), output)
    if args.json:
        data = {"first_contact": _json_numbers(dataclasses.asdict(first)),
                "sequence": None if sequence is None else {
                    "status": sequence.attrs["status"], **{
                        name: _json_numbers(sequence[name].values.tolist())
                        for name in sequence.data_vars}},
                "sequence_refused": why}
        print(json.dumps(data))
    else:
        _print_contacts(params, args.t_max, first, sequence, why)
    if output is not None:
        _say(args, f"wrote {output}: {sequence.impact.size} contacts, status "
                   f"{sequence.attrs['status']}")
    if sequence is not None and sequence.attrs["status"] != "complete":
        _warn(f"the sequence stopped after --max-contacts {args.max_contacts} contacts, before "
              f"t_max = {args.t_max!r} s (status {sequence.attrs['status']})")
        return EXIT_INCOMPLETE
    return 0


def _json_numbers(value: object) -> object:
    """``value`` (a number, list or dict of them) with NaN as None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {key: _json_numbers(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_json_numbers(item) for item in value]
    return None if isinstance(value, float) and value != value else value


def _contact_words(params: Params, index: int) -> str:
    """Which contact ``index`` is: ``contacts[1] (above, x1 = 0.05 m)``, or ``the contact``."""
    run = params.each_contact()[index]
    x1, x2 = run.contact_point
    where = f"{run.contact_side}, x1 = {x1:g} m" + (f", x2 = {x2:g} m"
                                                      if run.partner.has_beam2 else "")
    name = f"contacts[{index}]" if params.several_contacts else "the contact"
    return f"{name} ({where})"


def _print_contacts(params: Params, t_max: float, first: object, sequence: xr.Dataset | None,
                    why: str | None) -> None:
    """The first contact, then the sequence's table (or why there is none), on stdout."""
    count = len(params.each_contact())
    print(f"{count} contact{'s' * (count > 1)}, "
          f"{modes_per_beam(first.n_modes, params.partner)}, t_max = {t_max!r} s")
    for index in range(count if count > 1 else 0):
        print(f"  {_contact_words(params, index)}")
    if first.contact < 0:
        print("first contact: none closes by t_max")
    else:
        print(f"first contact: {_contact_words(params, first.contact)} at t = {first.onset!r} s,"
              f" gap rate {first.impact_velocity:.6g} m/s")
    if sequence is None:
        print(f"contact sequence: not built for these contacts ({why})")
        return
    print(f"contact sequence: {sequence.impact.size} contacts, status "
          f"{sequence.attrs['status']}")
    if not sequence.impact.size:
        return
    widths = [max(len(heading), 17) for _, heading, _ in _SEQUENCE_COLUMNS]
    print(f"{'n':>5} {'contact':>8} " + " ".join(
        f"{heading:>{width}}" for (_, heading, _), width in zip(_SEQUENCE_COLUMNS, widths,
                                                                strict=True)))
    for row in range(sequence.impact.size):
        cells = [fmt.format(float(sequence[name][row])) for name, _, fmt in _SEQUENCE_COLUMNS]
        print(f"{row + 1:>5} {int(sequence.impact_contact[row]):>8} " + " ".join(
            f"{cell:>{width}}" for cell, width in zip(cells, widths, strict=True)))


def _described_sequence(sequence: xr.Dataset, params: Params,
                        args: argparse.Namespace) -> xr.Dataset:
    """The sequence as written: CF attributes of each column and of the run's parameters."""
    from impactbeams.variables import attributes, global_attributes

    described = sequence.copy()
    for name in described.data_vars:
        described[name].attrs = ({"units": "1", "long_name": "contact that closes",
                                  "description": "its index in the parameters' contacts"}
                                 if name == "impact_contact" else attributes(name))
    described.attrs = global_attributes(
        "impactbeams contact sequence", f"contacts --t-max {args.t_max!r}",
        without_unused_law_keys(params.as_dict()), **sequence.attrs)
    return described


def _say(args: argparse.Namespace, line: str) -> None:
    """An informative line on stderr, unless --quiet (warnings and errors are always shown)."""
    if not args.quiet:
        print(line, file=sys.stderr)


def _number(text: str) -> float:
    """A real number (the library checks its range, naming the parameter)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def _positive_float(text: str) -> float:
    """A finite number > 0 (options the library does not check, such as --dpi)."""
    value = _number(text)
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"{text} is not allowed: must be a finite number > 0")
    return value


def _integer_from(low: int, high: int | None = None) -> Callable[[str], int]:
    """An argparse type: an integer from ``low`` to ``high`` (no upper limit if None)."""
    allowed = f"an integer from {low} to {high}" if high else f"an integer >= {low}"

    def integer(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be {allowed}"
                                             ) from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"{value} is not allowed: must be {allowed}")
        return value

    return integer


_POSITIVE_INTEGER = _integer_from(1)
_MODE_COUNT = _integer_from(1, MAX_MODES)


class UsageError(ParameterError):
    """An error in the command's arguments: one line after the command's usage line."""

    def __init__(self, message: str, usage: str) -> None:
        super().__init__(message)
        self.usage = usage


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are UsageErrors (usage, one line, exit code 2, in main).

    No option may be abbreviated (``--clear`` is not ``--clearance``), and an unknown one is
    reported by the subcommand it was given to, with the nearest option.
    """

    def __init__(self, **kwargs: object) -> None:
        super().__init__(allow_abbrev=False, **kwargs)  # type: ignore[arg-type]
        self.commands: dict[str, _Parser] = {}

    def error(self, message: str) -> NoReturn:
        # one line whatever the terminal's width (argparse wraps a long list of commands)
        raise UsageError(message, " ".join(self.format_usage().split()))

    def parse_args(self, args: Sequence[str] | None = None,  # type: ignore[override]
                   namespace: None = None) -> argparse.Namespace:
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            parser = self.commands.get(getattr(parsed, "command", None), self)
            options = [option for action in parser._actions for option in action.option_strings]
            parser.error(f"unrecognized arguments: {' '.join(extras)}"
                         f"{nearest(extras[0].split('=')[0], options)}")
        return parsed


class _Version(argparse.Action):
    """``--version``: the installed version (read only when asked: it costs the metadata)."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: object) -> None:
        super().__init__(option_strings, dest, nargs=0,
                         help="print the version of impactbeams and exit")

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        import impactbeams

        print(f"impactbeams {impactbeams.__version__}")
        parser.exit()


# a negative number as an option's value (argparse reads "-1e-5" as an option)
_NUMBER = r"(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|inf|infinity|nan"
# a negative number, or a list of numbers with commas that starts with one (basins' LOW,HIGH)
_NEGATIVE_NUMBER = re.compile(rf"^-({_NUMBER})(,[-+]?({_NUMBER}))*$", re.IGNORECASE)


def _attach_negative_values(argv: Sequence[str]) -> list[str]:
    """``--option -1e-5`` as ``--option=-1e-5``, so that negative values reach the checks."""
    joined: list[str] = []
    for token in argv:
        if (joined and _NEGATIVE_NUMBER.match(token) and joined[-1].startswith("--")
                and "=" not in joined[-1]):
            joined[-1] += "=" + token
        else:
            joined.append(token)
    return joined


def build_parser() -> argparse.ArgumentParser:
    """The ``impactbeams`` argument parser with all subcommands."""
    parser = _Parser(prog="impactbeams", description=__doc__.split("\n")[0])
    parser.add_argument("--version", action=_Version)
    commands = parser.add_subparsers(dest="command", required=True,
                                     help="what to do (impactbeams COMMAND --help: its options)")

    def command(name: str, usage: str, **kwargs: str) -> _Parser:
        sub = commands.add_parser(name, usage=f"%(prog)s {usage}", **kwargs)
        sub.add_argument("--quiet", action="store_true",
                         help="print nothing but warnings and errors on stderr")
        parser.commands[name] = sub
        return sub

    modes = command("modes", "[--n N] [--json] [PARAMETER OPTIONS]",
                    help="print natural frequencies of both phases (rad/s)")
    modes.add_argument("--n", type=_MODE_COUNT, default=5,
                       help=f"number of modes (default 5, at most {MAX_MODES})")
    modes.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_parameter_options(modes)
    modes.set_defaults(handler=_modes)

    simulate = command("simulate", "--t-max SECONDS -o RUN.nc [OPTIONS] [PARAMETER OPTIONS]",
                       help="simulate one trajectory, write netCDF")
    simulate.add_argument("--t-max", type=_number, required=True, metavar="SECONDS",
                          help="end time (s)")
    simulate.add_argument("--n-modes", type=_MODE_COUNT, default=None, metavar="N",
                          help="free modes per beam (default: 5 for the tied law; for the "
                               "spring law the number that resolves the contact, 4 n*)")
    simulate.add_argument("--dt-output", type=_number, default=1e-4, metavar="SECONDS",
                          help="output time step (s, default 1e-4, at most t_max)")
    simulate.add_argument("--energy-balance", action="store_true",
                          help="also store the work of F and the dissipation (costly with many "
                               "modes)")
    simulate.add_argument("--fields", action="store_true",
                          help="also store the deflection fields y_i(x, t)")
    simulate.add_argument("--lyapunov", type=_POSITIVE_INTEGER, default=0, metavar="COUNT",
                          help="also compute the COUNT leading Lyapunov exponents (1/s) of the "
                               "run, 1 for the largest (spring law)")
    simulate.add_argument("--transient-periods", type=_integer_from(0), default=0,
                          metavar="PERIODS",
                          help="forcing periods left out of the exponents' average (default 0)")
    simulate.add_argument("--max-events", type=_POSITIVE_INTEGER, default=MAX_EVENTS,
                          metavar="N",
                          help=f"stop the run after N phases, free flights and contacts "
                               f"(default {MAX_EVENTS}), with status event_limit")
    simulate.add_argument("-o", "--output", required=True, metavar="RUN.nc",
                          help="netCDF file to write (replaced if it exists)")
    add_parameter_options(simulate)
    simulate.set_defaults(handler=_simulate)

    contacts = command("contacts", "--t-max SECONDS [OPTIONS] [PARAMETER OPTIONS]",
                       help="which contact closes first and when, and the contact sequence")
    contacts.add_argument("--t-max", type=_number, required=True, metavar="SECONDS",
                          help="end time (s)")
    contacts.add_argument("--n-modes", type=_MODE_COUNT, default=None, metavar="N",
                          help="free modes per beam (default: the most any contact's run needs)")
    contacts.add_argument("--max-contacts", type=_POSITIVE_INTEGER, default=MAX_EVENTS // 2,
                          metavar="N", help=f"stop the sequence after N contacts (default "
                                            f"{MAX_EVENTS // 2}), with status event_limit")
    contacts.add_argument("--json", action="store_true", help="print JSON instead of tables")
    contacts.add_argument("-o", "--output", metavar="OUT.nc",
                          help="also write the sequence to this netCDF file (one contact or a "
                               "two-sided stop)")
    add_parameter_options(contacts)
    contacts.set_defaults(handler=_contacts)

    run = command("run", "SWEEP.toml [-o OUT.nc] [OPTIONS]",
                  help="run a sweep defined in a TOML file (see sweeps/), or a basin map "
                       "(a [basins] table)")
    run.add_argument("sweep", metavar="SWEEP.toml",
                     help="sweep definition, e.g. sweeps/fig5a-omega-force.toml")
    run.add_argument("-o", "--output", metavar="OUT.nc",
                     help="netCDF result (default results/<sweep name>.nc)")
    run.add_argument("--threads", type=_POSITIVE_INTEGER,
                     help="Numba threads (default: all cores); on a cluster, per task "
                     "(default: cores per host / Dask threads per host)")
    run.add_argument("--chunk-cells", type=_integer_from(1, MAX_CHUNK_CELLS),
                     help="most cells per chunk, rounded down to whole lines of the last "
                     "axes (default: 2^20 for a first-impact map, 2^16 for full dynamics)")
    run.add_argument("--discard-corrupt", action="store_true",
                     help="on a resume, delete damaged saved chunks and compute them again "
                     "(default: stop with an error naming the file)")
    cluster = run.add_mutually_exclusive_group()
    cluster.add_argument("--scheduler", metavar="ADDRESS",
                         help="run the chunks on the Dask cluster at ADDRESS, e.g. "
                         "tcp://host:8786 (needs impactbeams[distributed])")
    cluster.add_argument("--local-cluster", type=_POSITIVE_INTEGER, metavar="N",
                         help="run the chunks on a Dask LocalCluster of N worker processes")
    run.set_defaults(handler=_run)

    cont = command("continue", "CONTINUATION.toml [-o OUT.nc] [--quiet]",
                   help="continue periodic orbits along a parameter (see sweeps/)")
    cont.add_argument("file", metavar="CONTINUATION.toml",
                      help="continuation file, e.g. sweeps/continuation-stop-fold.toml")
    cont.add_argument("-o", "--output", metavar="OUT.nc",
                      help="netCDF result (default results/<file name>.nc)")
    cont.add_argument("--allow-incomplete", action="store_true",
                      help="exit 0, not 3, when a branch stops short of its range "
                           "(stalled, max_points, min_step, retraced) or a curve at "
                           "max_points")
    cont.set_defaults(handler=_continue)

    grazing = command("grazing", "PARAMETER --omega-min LOW --omega-max HIGH -o OUT.nc "
                      "[OPTIONS] [PARAMETER OPTIONS]",
                      help="where the non-impacting orbit first touches, in closed form")
    grazing.add_argument("parameter", metavar="PARAMETER",
                         help="force_amplitude, base_amplitude, clearance or one contact's "
                              "contacts.INDEX.clearance: its grazing value at each Omega; "
                              "omega: the grazing frequencies")
    grazing.add_argument("--omega-min", type=_number, required=True, metavar="RAD/S",
                         help="lowest forcing frequency (rad/s)")
    grazing.add_argument("--omega-max", type=_number, required=True, metavar="RAD/S",
                         help="highest forcing frequency (rad/s)")
    grazing.add_argument("--points", type=_integer_from(2), metavar="N",
                         help=f"frequencies, evenly spaced (default {GRAZING_POINTS}; for "
                              f"omega the bracketing grid, default {GRAZING_BRACKETS})")
    grazing.add_argument("--n-modes", type=_MODE_COUNT, default=None, metavar="N",
                         help="free modes per beam (default 5)")
    grazing.add_argument("-o", "--output", required=True, metavar="OUT.nc",
                         help="netCDF file to write (replaced if it exists)")
    add_parameter_options(grazing)
    grazing.set_defaults(handler=_grazing)

    basin = command("basins", "(--axis1 LOW,HIGH --axis2 LOW,HIGH | --states FILE) -o OUT.nc "
                    "[OPTIONS] [PARAMETER OPTIONS]", help="basins of attraction over a plane "
                                                          "of initial states, at fixed "
                                                          "parameters")
    basin.add_argument("--axis1", type=_range, metavar="LOW,HIGH",
                       help="first axis: beam 1's initial tip deflection (m) from its first "
                            "mode, or z[I] with --coordinates")
    basin.add_argument("--axis2", type=_range, metavar="LOW,HIGH",
                       help="second axis: beam 1's initial tip velocity (m/s) from its first "
                            "mode, or z[J] with --coordinates")
    basin.add_argument("--states", metavar="FILE",
                       help="initial states instead of a plane: rows z = (q, q') in a .npy "
                            "or .npz file (its one array, or 'states'), or a basin map's .nc")
    basin.add_argument("--attractors", metavar="CURVE.nc",
                       help="an impactbeams continue output: its orbits where its branches "
                            "cross this --omega (or the continued parameter's value) label "
                            "the basins first")
    basin.add_argument("--coordinates", type=_index_pair, metavar="I,J",
                       help="the plane of modal coordinates z[I], z[J] of z = (q, q'), in "
                            "modal units (default: the tip plane)")
    basin.add_argument("--points", type=_integer_from(1), metavar="N",
                       help=f"initial states along each axis (default {BASIN_POINTS})")
    basin.add_argument("--random", type=_POSITIVE_INTEGER, metavar="N",
                       help="N random initial states in the box instead of a grid (basin "
                            "stability, Wilson intervals)")
    basin.add_argument("--seed", type=_integer_from(0), default=None,
                       help="seed of the random states, with --random (default 0)")
    basin.add_argument("--max-periods", type=_POSITIVE_INTEGER, metavar="N",
                       help="forcing periods a state may run before it counts as not settled "
                            "(default 1200)")
    basin.add_argument("--n-modes", type=_MODE_COUNT, default=None, metavar="N",
                       help="free modes per beam (default: as simulate)")
    basin.add_argument("--chunk-cells", type=_POSITIVE_INTEGER, metavar="N",
                       help="initial states per saved chunk (default 16); resume with the "
                            "same")
    basin.add_argument("--workers", type=_POSITIVE_INTEGER, metavar="N",
                       help="threads running chunks (default: all cores)")
    basin_cluster = basin.add_mutually_exclusive_group()
    basin_cluster.add_argument("--scheduler", metavar="ADDRESS",
                               help="run the chunks on the Dask cluster at ADDRESS, e.g. "
                                    "tcp://host:8786 (needs impactbeams[distributed])")
    basin_cluster.add_argument("--local-cluster", type=_POSITIVE_INTEGER, metavar="N",
                               help="run the chunks on a Dask LocalCluster of N worker "
                                    "processes")
    basin.add_argument("-o", "--output", required=True, metavar="OUT.nc",
                       help="netCDF file; chunks are kept in OUT.nc.partial/ until it is "
                            "complete, and the same command resumes")
    add_parameter_options(basin)
    basin.set_defaults(handler=_basins)

    plot = command("plot", "IN.nc [-o OUT.png] [OPTIONS]",
                   help="draw a saved sweep map, simulated run or continuation")
    plot.add_argument("dataset", metavar="IN.nc",
                      help="a file written by impactbeams run, simulate or continue")
    plot.add_argument("-o", "--output", metavar="OUT.png",
                      help="the figure; its suffix sets the format (default: IN.png, next to "
                           "IN.nc)")
    plot.add_argument("--var", metavar="NAME",
                      help="variable to draw (default: first_impact_time; a run without "
                           "options gets its overview)")
    plot.add_argument("--slice", action="append", default=[], metavar="NAME=VALUE",
                      help="cut a dimension at the grid value nearest VALUE (SI units); "
                           "repeatable")
    plot.add_argument("--slice-index", action="append", default=[], metavar="NAME=I",
                      help="cut a dimension at grid index I (from 0); repeatable")
    colour_scale = plot.add_mutually_exclusive_group()
    colour_scale.add_argument("--log", dest="scale", action="store_const", const="log",
                              help="log colour scale (default when positive values span "
                                   "more than 1.5 decades)")
    colour_scale.add_argument("--linear", dest="scale", action="store_const", const="linear",
                              help="linear colour scale")
    plot.add_argument("--contours", metavar="N|L1,L2,...",
                      help="labelled contour lines: about N at round values, or these levels")
    plot.add_argument("--title", help="title instead of the fixed parameters ('' for none)")
    plot.add_argument("--dpi", type=_positive_float, default=150,
                      help="resolution of raster formats (default 150)")
    plot.add_argument("--over", metavar="DIAGRAM.nc",
                      help="draw a continuation's branches over this long-time sweep of its "
                           "parameter, or a bifurcation curve over this map of its plane")
    plot.add_argument("--with", dest="also", action="append", default=[], metavar="CURVE.nc",
                      help="another bifurcation curve of IN.nc's plane drawn with it, e.g. a "
                           "grazing curve beside a fold curve (repeatable)")
    plot.add_argument("--hz", action="store_true",
                      help="a continuation's frequency axis in Hz (Omega / 2 pi), not rad/s")
    plot.add_argument("--events", metavar="KINDS",
                      help="a continuation's events drawn and labelled: all, none, or kinds with "
                           "commas (fold,grazing,...); default all, merges/splits/chatter "
                           "unlabelled")
    plot.set_defaults(handler=_plot)
    return parser


def _show_warning(message: Warning | str, category: type[Warning], *_: object,
                  **__: object) -> None:
    """Warnings as one line, like the errors."""
    _warn(str(message))


def _warn(text: str) -> None:
    print(f"impactbeams: warning: {text}", file=sys.stderr)


# OpenBLAS's idle-thread spin, 2^4 cycles: its default, 2^28 (about 0.1 s), is paid after each
# call, and a sweep of the spring law makes one per cell (`kernels.contact_spring.spring_drives`)
BLAS_THREAD_TIMEOUT = "4"


def _idle_blas_threads_sleep() -> None:
    """Let SciPy's BLAS threads sleep as soon as a call is done, instead of spinning.

    After each call OpenBLAS's worker threads spin for about 0.1 s, waiting for the next one;
    on two cores that spin competes with the sweep's own threads: the Hertz bifurcation
    diagram on 2 threads took 53 s of CPU with it, 37 s without (issue 24). The threads and the
    results are the same (bit for bit); OpenBLAS reads the setting when it loads, which for
    SciPy's (the kernels' BLAS) is after this. A value set by the user is kept.
    """
    os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", BLAS_THREAD_TIMEOUT)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``impactbeams`` console script; returns the exit code.

    0: done; 1 (`EXIT_SYSTEM_ERROR`): a file could not be written or memory ran out;
    2 (`EXIT_USER_ERROR`): an input was rejected before any work; 3
    (`EXIT_INCOMPLETE`): written, but some runs stopped before t_max; 130: interrupted.

    Without ``argv`` (the console script, ``python -m impactbeams.cli``) the process is the
    command's own, and is set up for a quick start: cached kernels load without Numba's
    compile registries (`impactbeams.cached_kernels`), ``plot`` hides Dask from xarray, and
    idle BLAS threads sleep (`_idle_blas_threads_sleep`). With ``argv`` (a caller's process)
    none is done: the results are the same.
    """
    if argv is None:
        _idle_blas_threads_sleep()
    try:
        args = build_parser().parse_args(
            _attach_negative_values(sys.argv[1:] if argv is None else argv))
        args.own_process = argv is None
        with warnings.catch_warnings():  # each warning a line, whatever the caller's filters
            warnings.simplefilter("default")
            warnings.showwarning = _show_warning
            return args.handler(args)
    except UsageError as error:
        print(error.usage, file=sys.stderr)
        return _fail(error, EXIT_USER_ERROR)
    except ParameterError as error:
        return _fail(error, EXIT_USER_ERROR)
    except (OSError, MemoryError) as error:
        return _fail(error, EXIT_SYSTEM_ERROR)
    except KeyboardInterrupt:
        print("impactbeams: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _fail(error: BaseException, code: int) -> int:
    """Print ``error`` as one line and return the exit ``code``."""
    text = " ".join(str(error).split()) or type(error).__name__
    print(f"impactbeams: error: {text}", file=sys.stderr)
    return code


if __name__ == "__main__":
    sys.exit(main())
