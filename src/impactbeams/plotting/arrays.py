"""A saved Dataset as NumPy arrays: what a figure of a sweep reads, without xarray.

Importing xarray (and pandas with it) takes about half a second, a third of what `impactbeams
plot` of a map used to take; a map file needs no decoding beyond what netCDF4 does, so
[`read_figure_data`][] reads it with netCDF4 alone into a [`PlainDataset`][]. Such a dataset
has the few parts of xarray's Dataset and DataArray the figures of sweeps use (names,
dimensions, attributes, values, coordinates, slicing by position and label), with xarray's
meaning; [`as_plain`][] turns a user's xarray Dataset into one, so that both are drawn by the
same code. A simulated run's and a continuation's figures are drawn from xarray Datasets.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Hashable, Mapping
from pathlib import Path
from types import EllipsisType
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.preflight import read_netcdf, registered, require_netcdf

if TYPE_CHECKING:
    import xarray as xr

# dimensions of the files whose figures are drawn from xarray Datasets: a simulated run's
# (its overview), a continuation's (its branches) and a basin map's (its attractors)
XARRAY_DIMENSIONS = frozenset({"time", "branch_point", "attractor"})
# attributes of a variable that xarray's CF decoding acts on (beyond a NaN fill, which reads
# as it is): a file that has any is read by xarray, so that it means what xarray reads
_DECODED = frozenset({"scale_factor", "add_offset", "missing_value", "_Unsigned", "dtype",
                      "calendar", "_Encoding"})


@dataclasses.dataclass(frozen=True)
class PlainArray:
    """One variable (or coordinate): as xarray's DataArray, without its coordinates."""

    name: str
    dims: tuple[str, ...]
    values: np.ndarray
    attrs: Mapping[str, Any]

    @property
    def ndim(self) -> int:
        """The number of dimensions."""
        return self.values.ndim

    @property
    def size(self) -> int:
        """The number of values."""
        return self.values.size

    @property
    def dtype(self) -> np.dtype:
        """The values' dtype."""
        return self.values.dtype

    @property
    def sizes(self) -> dict[str, int]:
        """Each dimension's length."""
        return dict(zip(self.dims, self.values.shape, strict=True))

    def item(self) -> Any:
        """The one value, as a Python scalar."""
        return self.values.item()

    def transpose(self, *dims: str | EllipsisType) -> PlainArray:
        """The array with its dimensions in the order ``dims`` (``...``: the others, in order)."""
        named = [d for d in dims if d is not Ellipsis]
        rest = [d for d in self.dims if d not in named]
        at = dims.index(Ellipsis) if Ellipsis in dims else len(named)
        order = [*named[:at], *rest, *named[at:]]
        return dataclasses.replace(self, dims=tuple(order), values=self.values.transpose(
            [self.dims.index(d) for d in order]))

    def isel(self, positions: Mapping[str, int]) -> PlainArray:
        """The array at the integer ``positions`` of its dimensions (others ignored), which go."""
        index = tuple(positions.get(d, slice(None)) for d in self.dims)
        values = np.array(self.values[index], dtype=self.dtype, copy=None)  # 0-d: an array
        return dataclasses.replace(self, dims=tuple(d for d in self.dims if d not in positions),
                                   values=values)


class PlainDataset:
    """Named [`PlainArray`][]s, coordinates (``coord_names``) and data variables, and ``attrs``.

    As xarray's Dataset: ``dataset[name]``, ``name in dataset``, `coords`, `data_vars`,
    ``variables``, `dims` and ``sizes`` (the dimensions' lengths), `isel` and `sel`.
    """

    def __init__(self, variables: Mapping[str, PlainArray], coord_names: frozenset[str],
                 attrs: Mapping[str, Any]) -> None:
        self.variables = dict(variables)
        self.attrs = dict(attrs)
        self._coord_names = coord_names & self.variables.keys()
        self.sizes = {d: n for v in self.variables.values() for d, n in v.sizes.items()}

    @property
    def dims(self) -> dict[str, int]:
        """Each dimension's length (``name in dataset.dims`` as with xarray)."""
        return self.sizes

    @property
    def coords(self) -> dict[str, PlainArray]:
        """The coordinates, by name."""
        return {name: v for name, v in self.variables.items() if name in self._coord_names}

    @property
    def data_vars(self) -> dict[str, PlainArray]:
        """The data variables (all but the coordinates), by name, in the file's order."""
        return {name: v for name, v in self.variables.items() if name not in self._coord_names}

    def __contains__(self, name: Hashable) -> bool:
        return name in self.variables

    def __getitem__(self, name: str) -> PlainArray:
        """A variable, or a dimension without a coordinate as its positions (as xarray)."""
        if name in self.variables:
            return self.variables[name]
        return PlainArray(name, (name,), np.arange(self.sizes[name]), {})

    def isel(self, positions: Mapping[str, int]) -> PlainDataset:
        """The dataset at integer ``positions`` along dimensions, which go.

        A sliced dimension's coordinate stays, as a scalar coordinate.
        """
        return PlainDataset({name: v.isel(positions) for name, v in self.variables.items()},
                            self._coord_names, self.attrs)

    def sel(self, labels: Mapping[str, Any]) -> PlainDataset:
        """The dataset at the coordinate values ``labels`` (each must be on its coordinate)."""
        return self.isel({name: int(np.flatnonzero(self[name].values == label)[0])
                          for name, label in labels.items()})


def as_plain(dataset: xr.Dataset | PlainDataset) -> PlainDataset:
    """``dataset`` as a [`PlainDataset`][] (its values computed if lazy)."""
    if isinstance(dataset, PlainDataset):
        return dataset
    variables = {**dataset.coords, **dataset.data_vars}
    return PlainDataset({str(name): PlainArray(str(name), tuple(map(str, v.dims)),
                                               np.asarray(v.values), dict(v.attrs))
                         for name, v in variables.items()},
                        frozenset(map(str, dataset.coords)), dataset.attrs)


def is_dataset(value: object) -> bool:
    """Whether ``value`` is an xarray Dataset or a [`PlainDataset`][].

    Without importing xarray: if it has not been imported, nothing is one of its Datasets.
    """
    xr = sys.modules.get("xarray")
    return isinstance(value, PlainDataset) or (xr is not None and isinstance(value, xr.Dataset))


def read_figure_data(path: str | Path, what: str) -> xr.Dataset | PlainDataset:
    """The netCDF file ``path`` to draw, read by netCDF4 alone where xarray is not needed.

    A [`PlainDataset`][] (`read_plain`), or an xarray Dataset for a run's or a continuation's
    file and for any file whose variables xarray would decode (`preflight.read_netcdf`).

    A missing, unreadable or non-netCDF file, or one whose registered names are not as
    registered, is a ParameterError naming it as ``what``.
    """
    path = require_netcdf(path, what)
    plain = read_plain(path)
    if plain is None:
        return read_netcdf(path, what)
    return registered(plain, f"{what} file {str(path)!r}")


def read_plain(path: Path) -> PlainDataset | None:
    """The netCDF file ``path`` as xarray would read it, or None if that needs xarray.

    None for a run's or a continuation's dimensions (`XARRAY_DIMENSIONS`), or variables that
    CF decoding changes (`_plain`).
    """
    import netCDF4

    with netCDF4.Dataset(path) as nc:
        variables = nc.variables
        if any(not _plain(v) or XARRAY_DIMENSIONS & set(v.dimensions)
               for v in variables.values()):
            return None
        nc.set_auto_mask(False)  # a NaN fill reads as NaN; nothing else is filled
        attrs = {key: nc.getncattr(key) for key in nc.ncattrs()}
        named = {*nc.dimensions, *str(attrs.pop("coordinates", "")).split()}
        arrays = {}
        for name, variable in variables.items():
            kept = {key: variable.getncattr(key) for key in variable.ncattrs()}
            kept.pop("_FillValue", None)  # xarray's encoding, not an attribute
            named.update(str(kept.pop("coordinates", "")).split())
            values = np.asarray(variable[...])
            if variable.dimensions == (name,) and values.dtype == object:
                values = values.astype(str)  # an index of strings: NumPy's, as xarray's
            arrays[name] = PlainArray(name, variable.dimensions, values, kept)
    return PlainDataset(arrays, frozenset(named), attrs)


def _plain(variable: Any) -> bool:
    """Whether xarray reads the netCDF4 ``variable`` as netCDF4 does (without masking).

    So it does for numbers or strings with no attribute that CF decoding acts on, no time
    units, and a fill value only as NaN (masked, it reads as NaN).
    """
    names = set(variable.ncattrs())
    if names & _DECODED or " since " in str(getattr(variable, "units", "")):
        return False
    kind = "U" if variable.dtype is str else np.dtype(variable.dtype).kind
    if kind not in "fiuU":
        return False
    return "_FillValue" not in names or (kind == "f" and np.isnan(variable.getncattr(
        "_FillValue")))
