"""Checks made before any compute or file: a run's limits, its expected cost, and the paths.

``simulate``, a sweep's validation and the command line call these first, so that a bad input
is refused with one clear message (naming the parameter or file, its value and what is
allowed) before any work starts or any file appears. The limits are explained in
docs/limits.md ("Allowed values").
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.checks import require
from impactbeams.params import (
    MAX_FREQUENCY,
    ParameterError,
    PointName,
    no_point,
    require_all,
    value_at,
)
from impactbeams.variables import validate

if TYPE_CHECKING:
    import xarray as xr

    from impactbeams.structure.user import MatrixStructure, ModalStructure

# rad: the largest phase omega t of any oscillation over a run (the fastest mode's or the
# forcing's). A phase is rounded to ~0.1 eps omega t per evaluation (docs/limits.md), 2e-7 rad
# at 1e10 rad; beyond, results lose their digits, and the run would take hours per cell.
MAX_PHASE = 1e10


def highest_frequency(values: Mapping[str, Any], n_modes: int, springs: int = 0,
                      structure1: MatrixStructure | ModalStructure | None = None,
                      steps: tuple[float, float] = (1.0, 1.0)) -> np.ndarray:
    """The highest free-mode frequency (rad/s) of both beams with ``n_modes`` modes each.

    ``values``: resolved parameters (floats or arrays that broadcast, as in `check_run`);
    ``springs``: the springs to ground a beam carries (`Params.grounded_springs`). Each is a
    rank-one stiffening, which raises the n-th frequency at most to the (n+1)-th: a bound is
    the uniform beam's mode ``n_modes + springs`` (point masses and a compliant clamp only
    lower the frequencies). A stepped beam's frequencies lie at most ``steps`` (one factor
    per beam, `Params.step_factors`) above those of its l, EI, rhoA. A user structure as beam 1
    (``structure1``) gives its own ``n_modes``-th frequency (of the modes it has).
    """
    from impactbeams.modes import cantilever_roots  # SciPy: only when a run is checked

    root = cantilever_roots(n_modes + springs)[-1]
    highest = [step * np.sqrt(np.asarray(values[f"EI{i}"]) / values[f"rhoA{i}"])
               * (root / np.asarray(values[f"l{i}"])) ** 2
               for i, step in zip(("1", "2"), steps, strict=True)]
    if structure1 is not None:
        highest[0] = structure1.modes(min(n_modes, structure1.mode_limit)).frequencies[-1]
    return np.maximum(*highest)


def check_run(values: Mapping[str, Any], t_max: float, n_modes: int,
              point: PointName = no_point, springs: int = 0,
              structure1: MatrixStructure | ModalStructure | None = None,
              steps: tuple[float, float] = (1.0, 1.0)) -> None:
    """Refuse a run whose modes or horizon leave the model's or double precision's range.

    ``values``: the resolved numeric parameters (floats, or arrays broadcasting over a
    sweep's corner grid); ``t_max`` in s; ``n_modes`` free modes per beam (already checked to
    be an integer within the package's limit); ``springs``, ``structure1``, ``steps``: see
    `highest_frequency`. Raises ParameterError.
    """
    if structure1 is not None:
        limit = structure1.mode_limit
        require("n_modes", n_modes, n_modes <= limit,
                f"{structure1.name} has {limit} modes: n_modes must be at most {limit}")
    highest = highest_frequency(values, n_modes, springs, structure1, steps)
    require_all("n_modes", np.asarray(n_modes), highest <= MAX_FREQUENCY, point, lambda j: (
        f"the highest mode would have the frequency {value_at(highest, j):.3g} rad/s, above "
        f"{MAX_FREQUENCY:g} rad/s where a continuum beam model does not hold: use fewer modes"))
    fastest = np.maximum(highest, np.asarray(values["omega"], dtype=float))
    phase = fastest * t_max
    require_all("t_max", np.asarray(t_max), phase <= MAX_PHASE, point, lambda j: (
        f"the fastest oscillation of the run (highest mode or forcing, "
        f"{value_at(fastest, j):.3g} rad/s) turns through {value_at(phase, j):.3g} rad by "
        f"t_max, more than {MAX_PHASE:g} rad (double precision keeps a phase to ~0.1 eps "
        "omega t; beyond, results lose their digits and a run takes hours): t_max <= "
        f"{MAX_PHASE / value_at(fastest, j):.3g} s here, or fewer modes"))


@dataclasses.dataclass(frozen=True)
class Cost:
    """Expected cost of a run: peak ``memory`` (bytes) and its compute time (``seconds``).

    The time comes from the cost model of `impactbeams.costs`.
    """

    memory: float
    seconds: float

    def describe(self) -> str:
        """E.g. ``"about 1.2 GiB of memory for its arrays and roughly 3 min"``."""
        duration = (f"roughly {format_time(self.seconds)}" if self.seconds >= 1
                    else "under a second")
        return f"about {format_bytes(self.memory)} of memory for its arrays and {duration}"


# The share of the physical memory a run may plan to use: the rest is left to the operating
# system, the interpreter and its libraries, and other programs.
MEMORY_FRACTION = 0.8


def machine_memory() -> int:
    """Physical memory of this machine (bytes), from ``os.sysconf``."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def require_memory(what: str, memory: float, advice: str) -> None:
    """Raise ParameterError if ``memory`` (bytes) exceeds MEMORY_FRACTION of this machine's.

    ``what`` names the input and its value; ``advice`` says what to change.
    """
    physical = machine_memory()
    if memory > MEMORY_FRACTION * physical:
        raise ParameterError(f"{what} is not allowed: it needs about "
                             f"{format_bytes(memory)} of memory, more than "
                             f"{MEMORY_FRACTION:.0%} of this machine's {format_bytes(physical)}: "
                             f"{advice}")


def format_bytes(size: float) -> str:
    """``size`` bytes in binary units, 3 significant digits (``"72.8 TiB"``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if size < 1024 or unit == "PiB":
            return f"{size:.3g} {unit}"
        size /= 1024
    raise AssertionError("unreachable")


def format_time(seconds: float) -> str:
    """A duration in the largest fitting unit (``"3 min"``, ``"2.1 days"``)."""
    for unit, length in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= length:
            return f"{seconds / length:.2g} {unit}"
    return f"{seconds:.2g} s"


# --- paths -------------------------------------------------------------------------------------


def require_input_file(path: str | Path, what: str) -> Path:
    """``path`` as a Path if it is an existing, readable regular file; else ParameterError.

    ``what`` names the input (an option or argument) in the message.
    """
    path = Path(path)
    if not path.exists():
        raise ParameterError(f"{what} file {str(path)!r} does not exist")
    if path.is_dir():
        raise ParameterError(f"{what} file {str(path)!r} is a folder: give a file")
    if not path.is_file():
        raise ParameterError(f"{what} file {str(path)!r} is not a regular file")
    try:
        with path.open("rb"):
            pass
    except OSError as error:
        raise ParameterError(f"{what} file {str(path)!r} cannot be read: {error.strerror}"
                             ) from None
    return path


def require_output_file(path: str | Path, what: str, suffixes: Collection[str],
                        kind: str) -> Path:
    """``path`` as a Path if a ``kind`` file (one of ``suffixes``) can be written there.

    The file may exist (it is replaced) but not as a folder; missing folders above it will be
    created, so the nearest existing one must accept new files (probed with an anonymous
    temporary file: nothing is left behind). Raises ParameterError naming ``what``.
    """
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise ParameterError(f"{what} {str(path)!r} is not allowed: a {kind} file must end in "
                             f"{', '.join(sorted(suffixes))}")
    if path.is_dir():
        raise ParameterError(f"{what} {str(path)!r} is an existing folder: give a file name")
    folder = _existing_folder(path)
    if not folder.is_dir():
        raise ParameterError(f"{what} {str(path)!r} cannot be written: {str(folder)!r} is a "
                             "file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise ParameterError(f"{what} {str(path)!r} cannot be written: the folder "
                             f"{str(folder)!r} does not accept new files ({error.strerror})"
                             ) from None
    return path


def require_disk(path: Path, size: float, what: str) -> None:
    """Raise ParameterError if the disk to hold ``path`` has less than ``size`` bytes free."""
    folder = _existing_folder(path)
    free = shutil.disk_usage(folder).free
    if size > free:
        raise ParameterError(f"{what} {str(path)!r} is not allowed: the run needs about "
                             f"{format_bytes(size)} of disk space there, and {str(folder)!r} has "
                             f"{format_bytes(free)} free: free some space or write elsewhere")


def _existing_folder(path: Path) -> Path:
    """The nearest existing folder above ``path`` (where its missing folders would be made)."""
    folder = path.parent
    while not folder.exists():
        folder = folder.parent
    return folder


def image_suffixes() -> dict[str, str]:
    """Image formats matplotlib writes, by file suffix (``".png"``: ``"Portable Network ..."``)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return {f".{name}": description
            for name, description in FigureCanvasBase.get_supported_filetypes().items()}


def image_path(path: str | Path) -> Path:
    """The file a figure saved at ``path`` goes to.

    Without a suffix, matplotlib appends its default format's (``savefig.format``, png).
    """
    import matplotlib

    path = Path(path)
    if not path.suffix:
        path = path.with_name(f"{path.name.rstrip('.')}.{matplotlib.rcParams['savefig.format']}")
    return path


def image_output(path: str | Path, what: str) -> Path:
    """`image_path` of ``path``, checked like `require_output_file`.

    Missing folders are made when the figure is saved, as for every output.
    """
    return require_output_file(image_path(path), what, image_suffixes(), "figure")


def read_netcdf(path: str | Path, what: str, check: bool = True) -> xr.Dataset:
    """Load a netCDF file; a missing, unreadable or non-netCDF file is a ParameterError.

    ``check``: so is a file whose registered names are not as registered (`registered`).
    """
    import xarray as xr

    path = require_input_file(path, what)
    try:
        with xr.open_dataset(path) as dataset:
            loaded = dataset.load()
    except (OSError, ValueError, RuntimeError) as error:
        raise _unreadable(path, what, error) from None
    return registered(loaded, f"{what} file {str(path)!r}") if check else loaded


def require_netcdf(path: str | Path, what: str) -> Path:
    """``path`` if it is a readable netCDF file, as `read_netcdf` checks, without xarray.

    For ``run``'s existing output, which is then read with netCDF4 alone: xarray and pandas
    would add a second to the start-up.
    """
    import netCDF4

    path = require_input_file(path, what)
    try:
        netCDF4.Dataset(path).close()
    except (OSError, ValueError, RuntimeError) as error:
        raise _unreadable(path, what, error) from None
    return path


def _unreadable(path: Path, what: str, error: Exception) -> ParameterError:
    """The error of a ``what`` file at ``path`` that could not be read as netCDF."""
    # xarray's ValueError when no backend recognises the file is long: say it shortly
    detail = "an unknown format" if "did not find a match" in str(error) else _first_line(error)
    return ParameterError(f"{what} file {str(path)!r} is not a readable netCDF file "
                          f"({detail}): give a file written by impactbeams")


def registered(dataset: xr.Dataset, source: str) -> xr.Dataset:
    """``dataset`` (read from ``source``) if its registered names are as the registry says.

    Else a ParameterError names ``source`` and what is wrong (a file written by other software
    or edited by hand); files of earlier versions pass (`impactbeams.variables.validate`).
    """
    try:
        validate(dataset, strict=False)
    except ValueError as error:
        raise ParameterError(f"{source} is not as impactbeams writes it: {error}") from None
    return dataset


def _first_line(error: Exception) -> str:
    return (str(error).strip().splitlines() or [type(error).__name__])[0]
