"""A basin map's initial states and given attractors read from files (the CLI, a basins file).

`read_states`: rows of section states z = (q, q') from a ``.npy`` file, a ``.npz`` archive
(its one array, or its array ``states``) or a basin map's ``.nc`` (its ``start_displacement``
and ``start_velocity``: the same states again, e.g. at other parameters).

`continued_orbits`: the orbits of a continuation's output (`impactbeams continue`) at the
map's value of the continued parameter, as `impactbeams.basins` takes them (``attractors``):
wherever a branch crosses that value, the branch point nearer to it is the guess of
`periodic_orbit` at the map's parameters, with the branch's period (docs/basins.md). The
continuation's other parameters and modes must be the map's. Every problem is one line
(`ParameterError`) naming the file.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.params import ParameterError, Params, element_field, parameter_value
from impactbeams.variables import parameter_text

if TYPE_CHECKING:
    import xarray as xr

    from impactbeams.orbits.shooting import PeriodicOrbit

STATES_SUFFIXES = (".npy", ".npz", ".nc")


def section_dimension(params: Params, n_modes: int) -> int:
    """2 N: the numbers of a section state z = (q, q') of ``n_modes`` per moving beam."""
    return 2 * n_modes * params.partner.beams


def read_states(path: str | Path, where: str, dimension: int) -> np.ndarray:
    """The initial states (cells, ``dimension``) in the file ``path``; ``where`` names it."""
    path = Path(path)
    if path.suffix not in STATES_SUFFIXES:
        raise ParameterError(f"{where} = '{path}' is not allowed: must be a .npy, .npz or .nc "
                             "file")
    if not path.is_file():
        raise ParameterError(f"{where} = '{path}': no such file")
    try:
        array = _basin_states(path) if path.suffix == ".nc" else _array(path, where)
    except (OSError, ValueError, EOFError) as error:
        raise ParameterError(f"{where} = '{path}' cannot be read ({error})") from None
    if not (array.ndim == 2 and array.shape[0] >= 1 and array.shape[1] == dimension
            and np.issubdtype(array.dtype, np.number)):
        raise ParameterError(f"{where} = '{path}' holds an array of shape {array.shape}: must be "
                             f"rows of {dimension} numbers, section states z = (q, q') of "
                             "this model (n_modes per beam, q then q')")
    return np.asarray(array, dtype=float)


def _array(path: Path, where: str) -> np.ndarray:
    """The array of a ``.npy`` file, or the one (or ``states``) array of a ``.npz``."""
    if path.suffix == ".npy":
        return np.load(path, allow_pickle=False)
    with np.load(path, allow_pickle=False) as loaded:
        names = list(loaded.files)
        if "states" in names or len(names) == 1:
            return loaded["states" if "states" in names else names[0]]
    raise ParameterError(f"{where} = '{path}' holds arrays {', '.join(names)}: name the "
                         "initial states 'states' (or keep one array)")


def _basin_states(path: Path) -> np.ndarray:
    """The initial states of a basin map's file, one row per cell."""
    import xarray as xr

    with xr.open_dataset(path) as dataset:
        if "start_displacement" not in dataset or "start_velocity" not in dataset:
            raise ValueError("not a basin map: no start_displacement, start_velocity")
        q, v = dataset.start_displacement.values, dataset.start_velocity.values
    return np.concatenate([q.reshape(-1, q.shape[-1]), v.reshape(-1, v.shape[-1])], axis=1)


def continued_orbits(path: str | Path, params: Params, n_modes: int,
                     where: str) -> list[PeriodicOrbit]:
    """The orbits of the continuation file ``path`` at ``params`` (module doc)."""
    from impactbeams.orbits.shooting import OrbitNotConverged, periodic_orbit

    branches = _continuation(Path(path), where)
    parameter = str(branches.attrs["continued_parameter"])
    _require_same_model(branches, params, n_modes, parameter, f"{where} = '{path}'")
    value = float(parameter_value(params, parameter))
    guesses = _crossings(branches, parameter, value)
    if not guesses:
        values = branches[parameter].values
        raise ParameterError(f"{where} = '{path}': its branches do not reach {parameter} = "
                             f"{value:g} (they cover {values.min():g} to {values.max():g})")
    orbits = []
    for point in guesses:
        try:
            orbits.append(periodic_orbit(params, n_modes, int(branches.orbit_period[point]),
                                         guess=branches.section_state.values[point],
                                         measures=False))
        except OrbitNotConverged as error:
            raise ParameterError(f"{where} = '{path}': the orbit near its branch point {point} "
                                 f"did not converge at {parameter} = {value:g} ({error})"
                                 ) from None
    return orbits


def _continuation(path: Path, where: str) -> xr.Dataset:
    """The continuation's Dataset (loaded), or one line saying why not."""
    import xarray as xr

    if path.suffix != ".nc":
        raise ParameterError(f"{where} = '{path}' is not allowed: must be a continuation's .nc "
                             "file (impactbeams continue)")
    if not path.is_file():
        raise ParameterError(f"{where} = '{path}': no such file")
    try:
        with xr.open_dataset(path) as dataset:
            branches = dataset.load()
    except (OSError, ValueError) as error:
        raise ParameterError(f"{where} = '{path}' cannot be read ({error})") from None
    needed = ("section_state", "orbit_period", "branch")
    if ("continued_parameter" not in branches.attrs
            or any(name not in branches for name in needed)):
        raise ParameterError(f"{where} = '{path}' is not a continuation's output (impactbeams "
                             "continue): no continued_parameter, section_state, orbit_period")
    return branches


def _require_same_model(branches: xr.Dataset, params: Params, n_modes: int, parameter: str,
                        where: str) -> None:
    """The continuation's modes and fixed parameters are the map's (one line if not).

    Several contacts are compared as their attribute's text, unless the continued parameter
    is one contact's field (``contacts.INDEX.FIELD``, whose value the text holds): then each
    orbit's Newton solve on the map's contacts is the check.
    """
    if int(branches.attrs.get("n_modes", -1)) != n_modes:
        raise ParameterError(f"{where}: its orbits have n_modes = {branches.attrs.get('n_modes')}"
                             f", the map's {n_modes}: give the map the same n_modes")
    field = element_field(parameter)  # a contact's or a part's: its tuple is continued
    continued = parameter if field is None else field[0]
    for key, value in params.as_dict().items():
        if key == continued or key not in branches.attrs or isinstance(value, (list, dict)):
            continue
        saved, value = branches.attrs[key], parameter_text(value)
        if (saved != value if isinstance(value, str)
                else not np.isclose(float(saved), float(value), rtol=1e-12, atol=0.0)):
            raise ParameterError(f"{where}: its orbits are of {key} = {saved}, the map's "
                                 f"{key} is {value}: continue the same model")


def _crossings(branches: xr.Dataset, parameter: str, value: float) -> list[int]:
    """Per branch, the point nearer to ``value`` wherever the branch crosses or reaches it."""
    values, branch = branches[parameter].values - value, branches.branch.values
    points = []
    for k in range(values.size):
        last = k + 1 == values.size or branch[k + 1] != branch[k]
        if values[k] == 0.0:
            points.append(k)
        elif not last and values[k] * values[k + 1] < 0.0:
            points.append(k if abs(values[k]) <= abs(values[k + 1]) else k + 1)
    return points
