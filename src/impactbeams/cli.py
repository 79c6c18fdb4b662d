"""Command-line interface: a thin argparse layer over the library.

Subcommands: ``modes`` (natural frequencies), ``run`` (a sweep from a TOML file), ``simulate``
(one full trajectory), ``plot`` (draw a saved Dataset). Every model parameter is an option
named like the parameter, with dashes (``--force-amplitude``, ``--EI1``, ``--thickness2``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from impactbeams.params import CONTACT_LAWS, ParameterError, Params
from impactbeams.variables import DAMPING_LAW, PARAMETERS

if TYPE_CHECKING:
    from impactbeams.sweep import ChunkRunner

_ALIASES = {"force_amplitude": ["--force"]}


def add_parameter_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--params FILE`` and one option per model parameter (SI units)."""
    group = parser.add_argument_group("model parameters (SI units; override --params)")
    group.add_argument("--params", metavar="FILE.toml",
                       help="TOML file with a [params] table (unspecified keys take defaults)")
    for name, parameter in PARAMETERS.items():
        flags = ["--" + name.replace("_", "-"), *_ALIASES.get(name, [])]
        description = parameter.long_name
        if name == "damping_ratio":
            description += ", " + DAMPING_LAW
        if name == "contact_law":
            group.add_argument(*flags, dest=name, choices=CONTACT_LAWS,
                               help=f"{description} (default: spring)")
            continue
        group.add_argument(*flags, dest=name, type=float, metavar="VALUE",
                           help=f"{description} ({parameter.units})")


def params_from_args(args: argparse.Namespace) -> Params:
    """The parameters of --params (or the defaults) with the command-line overrides applied."""
    params = Params.from_toml(args.params) if args.params else Params()
    overrides = {n: getattr(args, n) for n in PARAMETERS if getattr(args, n, None) is not None}
    return params.replace(**overrides) if overrides else params


def _contact_frequencies(p: Params, n: int) -> list[float]:
    """The lowest ``n`` contact-phase frequencies (rad/s) of the parameters' contact law.

    Tied: the roots of eq. (9); spring: the undamped contact oscillators at the n_modes that
    resolve the contact (at least n).
    """
    from impactbeams.compliant import recommended_modes, spring_contact
    from impactbeams.model import build_free_phase
    from impactbeams.modes import contact_frequencies

    if p.contact_law == "tied":
        return contact_frequencies(p, n).tolist()
    free = build_free_phase(p, max(n, recommended_modes(p)))
    spring = spring_contact(free, p.tip_compliance, 0.0, p.contact_stiffness)
    return spring.frequencies[:n].tolist()


def _modes(args: argparse.Namespace) -> None:
    from impactbeams.modes import free_modes

    p = params_from_args(args)
    result = {
        "free": {"beam1": free_modes(p.EI1, p.rhoA1, p.l1, args.n).omega.tolist(),
                 "beam2": free_modes(p.EI2, p.rhoA2, p.l2, args.n).omega.tolist()},
        "contact_law": p.contact_law,
        "contact": _contact_frequencies(p, args.n),
    }
    if args.json:
        print(json.dumps(result))
        return
    print(f"natural frequencies (rad/s); contact phase of the {p.contact_law} law")
    print(f"{'mode':>4} {'beam 1 free':>16} {'beam 2 free':>16} {'contact':>16}")
    for i in range(args.n):
        row = (result["free"]["beam1"][i], result["free"]["beam2"][i], result["contact"][i])
        print(f"{i + 1:>4} " + " ".join(f"{w:16.6f}" for w in row))


def _run(args: argparse.Namespace) -> None:
    from impactbeams.sweep import load_sweep, write_sweep  # writes netCDF without xarray

    sweep = load_sweep(args.sweep)
    output = args.output or str(Path("results") / (Path(args.sweep).stem + ".nc"))
    print(f"{sweep.source}: {' x '.join(map(str, sweep.shape))} = {sweep.size} cells over "
          f"{', '.join(a.name for a in sweep.axes)}; t_max = {sweep.t_max} s, "
          f"{sweep.n_modes} modes per beam -> {output}\n(the first chunk also compiles the "
          "kernels, about 10 s on a fresh install; they are cached after that)", file=sys.stderr)
    try:
        with _cluster_runner(args) as runner:
            write_sweep(sweep, output, threads=None if runner else args.threads,
                        progress=not args.quiet, chunk_cells=args.chunk_cells, runner=runner,
                        discard_corrupt=args.discard_corrupt)
    except KeyboardInterrupt:
        print(f"\nimpactbeams: interrupted; finished chunks are kept in {output}.partial/ "
              "and the same command resumes from them", file=sys.stderr)
        raise
    print(f"wrote {output}", file=sys.stderr)


@contextlib.contextmanager
def _cluster_runner(args: argparse.Namespace) -> Iterator[ChunkRunner | None]:
    """A Dask chunk runner for --scheduler / --local-cluster (closed on exit), else None."""
    if args.scheduler is None and args.local_cluster is None:
        yield None
        return
    from impactbeams.sweep.dask_runner import dask_client, dask_runner, require_dask

    try:
        require_dask()
    except ImportError as error:
        raise ParameterError(str(error)) from None
    with dask_client(args.scheduler, args.local_cluster) as client:
        yield dask_runner(client, threads_per_task=args.threads)


def _plot(args: argparse.Namespace) -> None:
    import xarray as xr

    from impactbeams.plotting import parse_assignments, parse_levels, plot_dataset

    if not Path(args.dataset).is_file():
        problem = "is a folder" if Path(args.dataset).is_dir() else "does not exist"
        raise ParameterError(f"file {args.dataset!r} {problem}: give a netCDF file")
    try:
        dataset = xr.open_dataset(args.dataset).load()
    except (OSError, ValueError) as error:
        raise ParameterError(f"{args.dataset!r} is not a netCDF file of impactbeams: "
                             f"{str(error).splitlines()[0]}") from None
    with dataset:
        notes = plot_dataset(dataset, args.output, args.var,
                             values=parse_assignments(args.slice, "--slice"),
                             indices=parse_assignments(args.slice_index, "--slice-index"),
                             scale=args.scale, contours=parse_levels(args.contours),
                             title=args.title, dpi=args.dpi)
    for note in notes:
        print(f"impactbeams: {note}", file=sys.stderr)
    print(f"wrote {args.output}", file=sys.stderr)


def _simulate(args: argparse.Namespace) -> None:
    from impactbeams.io import write_netcdf
    from impactbeams.trajectory import simulate

    output = Path(args.output)
    if output.suffix != ".nc":
        raise ParameterError(f"--output {args.output!r} is not allowed: must end in .nc")
    dataset = simulate(params_from_args(args), args.t_max, n_modes=args.n_modes,
                       dt_output=args.dt_output, fields=args.fields,
                       energy_balance=args.energy_balance)
    write_netcdf(dataset, output)
    print(f"wrote {output}: {dataset.impact.size} impacts, status {dataset.attrs['status']}",
          file=sys.stderr)


def _positive_float(text: str) -> float:
    value = float(text)
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text} is not allowed: must be a finite number > 0")
    return value


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not allowed: must be an integer >= 1")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The ``impactbeams`` argument parser with all subcommands."""
    parser = argparse.ArgumentParser(prog="impactbeams", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    modes = commands.add_parser("modes", help="print natural frequencies of both phases (rad/s)")
    modes.add_argument("--n", type=_positive_int, default=5, help="number of modes (default 5)")
    modes.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_parameter_options(modes)
    modes.set_defaults(handler=_modes)

    simulate = commands.add_parser("simulate", help="simulate one trajectory, write netCDF")
    simulate.add_argument("--t-max", type=_positive_float, required=True, metavar="SECONDS",
                          help="end time (s)")
    simulate.add_argument("--n-modes", type=_positive_int, default=None,
                          help="free modes per beam (default: 5 for the tied law; for the "
                               "spring law the number that resolves the contact, 4 n*)")
    simulate.add_argument("--dt-output", type=_positive_float, default=1e-4, metavar="SECONDS",
                          help="output time step (s, default 1e-4)")
    simulate.add_argument("--energy-balance", action="store_true",
                          help="also store the work of F and the dissipation (costly with many "
                               "modes)")
    simulate.add_argument("--fields", action="store_true",
                          help="also store the deflection fields y_i(x, t)")
    simulate.add_argument("-o", "--output", required=True, metavar="RUN.nc")
    add_parameter_options(simulate)
    simulate.set_defaults(handler=_simulate)

    run = commands.add_parser("run", help="run a sweep defined in a TOML file (see sweeps/)")
    run.add_argument("sweep", metavar="SWEEP.toml")
    run.add_argument("-o", "--output", metavar="OUT.nc",
                     help="netCDF result (default results/<sweep name>.nc)")
    run.add_argument("--threads", type=_positive_int,
                     help="Numba threads (default: all cores); on a cluster, per task "
                     "(default: cores per host / Dask threads per host)")
    run.add_argument("--chunk-cells", type=_positive_int,
                     help="cells per saved chunk (default: about 1%% of the grid, 4096..65536)")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--discard-corrupt", action="store_true",
                     help="on a resume, delete damaged saved chunks and compute them again "
                     "(default: stop with an error naming the file)")
    cluster = run.add_mutually_exclusive_group()
    cluster.add_argument("--scheduler", metavar="ADDRESS",
                         help="run the chunks on the Dask cluster at ADDRESS, e.g. "
                         "tcp://host:8786 (needs impactbeams[distributed])")
    cluster.add_argument("--local-cluster", type=_positive_int, metavar="N",
                         help="run the chunks on a Dask LocalCluster of N worker processes")
    run.set_defaults(handler=_run)

    plot = commands.add_parser("plot", help="draw a saved sweep map or simulated run")
    plot.add_argument("dataset", metavar="IN.nc")
    plot.add_argument("-o", "--output", required=True, metavar="OUT.png")
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
    plot.set_defaults(handler=_plot)
    return parser


def _show_warning(message: Warning | str, category: type[Warning], *_: object,
                  **__: object) -> None:
    """Warnings as one line, like the errors."""
    print(f"impactbeams: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``impactbeams`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            args.handler(args)
    except ParameterError as error:
        print(f"impactbeams: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("impactbeams: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
