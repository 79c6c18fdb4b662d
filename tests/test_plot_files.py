"""`impactbeams plot` without xarray (issue 24): a map's file read by netCDF4 alone is what
xarray reads, sliced as xarray slices it, and a regular grid drawn as an image is the picture of
its mesh of cells. The files are the maps of every kind (first impact, dynamics with a
categorical axis, long-time samples, Lyapunov, a stepped sweep), filled with synthetic values
(no kernel runs), as the command line writes them (netCDF4) and as xarray writes them."""

import io

import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import QuadMesh
from matplotlib.figure import Figure
from matplotlib.image import BboxImage

from impactbeams.cli import main
from impactbeams.io import build_netcdf, write_netcdf
from impactbeams.plotting import draw, maps, plot_dataset
from impactbeams.plotting.arrays import (
    PlainArray,
    PlainDataset,
    as_plain,
    read_figure_data,
    read_plain,
)
from impactbeams.sweep import load_sweep
from impactbeams.sweep.definition import FIRST_IMPACT
from impactbeams.sweep.output import cell_values, map_dataset, map_layout, stored_arrays
from impactbeams.variables import attributes
from test_resume import KINDS

SWEEPS = {**KINDS, "stepped": 'stepping = "both"\n' + KINDS["long-time"]}


def _results(sweep, rng):
    """Synthetic values of every cell: NaN in a quarter of the float cells, small integers."""
    cells = int(np.prod(sweep.shape))
    results = {}
    for name, (dtype, shape) in cell_values(sweep).items():
        if dtype.kind == "f":
            values = rng.uniform(1e-3, 1.0, (cells, *shape))
            values[rng.random(cells) < 0.25] = np.nan
        else:
            values = rng.integers(0, 4, (cells, *shape))
        results[name] = values.astype(dtype)
    if FIRST_IMPACT in results:
        results[FIRST_IMPACT] = results[FIRST_IMPACT].astype(float)
    return results


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Each kind's map as the command line writes it (``cli``) and as xarray does (``xarray``)."""
    folder = tmp_path_factory.mktemp("maps")
    rng = np.random.default_rng(24)
    paths = {}
    for kind, text in SWEEPS.items():
        (folder / f"{kind}.toml").write_text(text)
        sweep = load_sweep(folder / f"{kind}.toml")
        results = _results(sweep, rng)
        paths[kind, "xarray"] = folder / f"{kind}-xarray.nc"
        write_netcdf(map_dataset(sweep, results), paths[kind, "xarray"])
        paths[kind, "cli"] = folder / f"{kind}-cli.nc"
        with build_netcdf(paths[kind, "cli"], folder / "building.nc", map_layout(sweep)) as nc:
            for name, values in stored_arrays(sweep, results).items():
                nc[name][...] = values.reshape(nc[name].shape)
    return paths


def assert_same(plain, reference):
    """Equal PlainDatasets: names, coordinates, order, dimensions, dtypes, values, attributes."""
    assert list(plain.data_vars) == list(reference.data_vars)
    assert plain.coords.keys() == reference.coords.keys() and plain.sizes == reference.sizes
    for name, expected in reference.variables.items():
        found = plain.variables[name]
        assert (found.dims, found.dtype) == (expected.dims, expected.dtype), name
        assert np.array_equal(found.values, expected.values,
                              equal_nan=expected.dtype.kind == "f"), name
        assert found.attrs.keys() == expected.attrs.keys(), name
        for key, value in expected.attrs.items():
            assert np.array_equal(found.attrs[key], value), (name, key)
    assert plain.attrs.keys() == reference.attrs.keys()
    assert all(np.array_equal(plain.attrs[k], v) for k, v in reference.attrs.items())


@pytest.mark.parametrize("writer", ["cli", "xarray"])
@pytest.mark.parametrize("kind", SWEEPS)
def test_a_map_file_reads_as_xarray_reads_it(files, kind, writer):
    path = files[kind, writer]
    with xr.open_dataset(path) as dataset:
        assert_same(read_plain(path), as_plain(dataset.load()))


def test_files_xarray_would_decode_are_read_by_xarray(tmp_path):
    """A run's file (time), and variables that CF decoding changes: not read by netCDF4 alone."""
    samples = {"time": xr.Dataset({"x": ("time", [0.0, 1.0])},
                                  coords={"time": ("time", [0.0, 0.1], attributes("time"))}),
               "scaled": xr.Dataset({"x": ("omega", np.array([1, 2], np.int16),
                                           {"scale_factor": 0.5})}),
               "integer fill": xr.Dataset({"x": ("omega", [1.0, np.nan])}),
               "times": xr.Dataset({"x": ("omega", [1.0, 2.0], {"units": "s since 2000-01-01"})})}
    encodings = {"integer fill": {"x": {"dtype": "int16", "_FillValue": -1}}}
    for name, dataset in samples.items():
        path = tmp_path / f"{name}.nc"
        dataset.to_netcdf(path, encoding=encodings.get(name))
        assert read_plain(path) is None, name
        assert isinstance(read_figure_data(path, "input"), xr.Dataset), name


def test_slices_are_xarrays(files):
    """By position, by label (a string coordinate), a dimension without coordinate, transposed."""
    with xr.open_dataset(files["stepped", "cli"]) as dataset:
        dataset.load()
    plain = read_plain(files["stepped", "cli"])
    assert_same(plain.isel({"omega": 3, "period": -1}),
                as_plain(dataset.isel({"omega": 3, "period": -1})))
    assert_same(plain.sel({"sweep_direction": "down"}),
                as_plain(dataset.sel({"sweep_direction": "down"})))
    assert np.array_equal(plain["period"].values, dataset["period"].values)
    field = plain["poincare_deflection1"].transpose("period", ...)
    expected = dataset["poincare_deflection1"].transpose("period", ...)
    assert field.dims == expected.dims
    assert np.array_equal(field.values, expected.values, equal_nan=True)
    sliced = plain.isel({"sweep_direction": 0, "omega": 0})
    assert sliced.coords["sweep_direction"].item() == "up" and sliced.coords["omega"].ndim == 0


@pytest.mark.parametrize("kind", ["first-impact", "dynamics", "stepped"])
def test_the_command_draws_what_plot_dataset_draws_from_xarray(files, kind, tmp_path):
    """`impactbeams plot` (the file read without xarray) against the library given xarray's
    Dataset: the same PNG, byte for byte."""
    path = files[kind, "cli"]
    assert main(["plot", str(path), "-o", str(tmp_path / "cli.png")]) == 0
    with xr.open_dataset(path) as dataset:
        plot_dataset(dataset.load(), tmp_path / "xarray.png")
    assert (tmp_path / "cli.png").read_bytes() == (tmp_path / "xarray.png").read_bytes()


def test_a_plain_dataset_of_a_run_is_refused():
    run = PlainDataset({"x": PlainArray("x", ("time",), np.zeros(3), {})}, frozenset(), {})
    with pytest.raises(TypeError, match="a run's overview is drawn from an xarray.Dataset"):
        plot_dataset(run, "run.png")


# --- a regular grid's image is its mesh's picture -----------------------------------------------

def _grid(x, y, x_scale="linear", y_scale="linear"):
    """first_impact_time on (x, y) grids: smooth, with a NaN corner (no impact)."""
    values = np.add.outer(np.linspace(0.01, 0.5, len(x)), np.linspace(0.0, 0.4, len(y)))
    values[: len(x) // 3, : len(y) // 3] = np.nan
    coords = {"omega": ("omega", x, {"units": "rad/s", "long_name": "forcing frequency",
                                     "scale": x_scale}),
              "force_amplitude": ("force_amplitude", y, {"units": "N", "long_name": "F0",
                                                         "scale": y_scale})}
    return xr.Dataset({"first_impact_time": (("omega", "force_amplitude"), values,
                                             {"units": "s", "long_name": "t"})}, coords=coords)


def _pixels(dataset, mesh=False, monkeypatch=None):
    """The drawn map (RGB pixels at 100 dpi), as an image or, with ``mesh``, as its mesh."""
    if mesh:
        monkeypatch.setattr(maps, "_uniform", lambda *_: False)
    figure = Figure(figsize=(5, 4), layout="constrained")
    FigureCanvasAgg(figure)
    draw(figure.subplots(), dataset, title="")
    kind = [type(a) for a in figure.axes[0].get_children() if isinstance(a, BboxImage | QuadMesh)]
    buffer = io.BytesIO()
    figure.savefig(buffer, format="rgba", dpi=100)
    monkeypatch and monkeypatch.undo()
    return kind, np.frombuffer(buffer.getvalue(), np.uint8).reshape(400, 500, 4)[..., :3]


GRIDS = {
    "linear x log": (np.linspace(10.0, 400.0, 90), np.geomspace(1e-6, 1e-3, 70), "log"),
    "finer than the pixels": (np.linspace(10.0, 400.0, 700), np.geomspace(1e-6, 1e-3, 500),
                              "log"),
    "descending": (np.linspace(400.0, 10.0, 37), np.linspace(1e-4, 2e-4, 23), "linear"),
    "two rows": (np.linspace(10.0, 400.0, 30), np.array([1e-4, 2e-4]), "linear"),
}


@pytest.mark.parametrize("grid", GRIDS)
def test_a_regular_grid_is_drawn_as_an_image_the_picture_of_its_mesh(grid, monkeypatch):
    """Every pixel as the mesh of quadrilaterals colours it, up to 1 of 255 per channel (the
    image's colours are truncated to bytes, the mesh's rounded by Agg)."""
    x, y, y_scale = GRIDS[grid]
    dataset = _grid(x, y, y_scale=y_scale)
    kind, image = _pixels(dataset)
    mesh_kind, mesh = _pixels(dataset, mesh=True, monkeypatch=monkeypatch)
    assert (kind, mesh_kind) == ([BboxImage], [QuadMesh])
    assert np.abs(image.astype(int) - mesh).max() <= 1


def test_named_choices_are_regular_and_unequal_cells_a_mesh(monkeypatch):
    """Named choices sit at 0, 1, 2 (an image, as its mesh); cells of 1, 2, 5 x 10^-4 N on a
    linear axis are unequal (a mesh)."""
    named = _grid(np.linspace(10.0, 400.0, 6), np.array(["tied", "spring", "stop"]))
    kind, image = _pixels(named)
    assert kind == [BboxImage]
    assert np.abs(image.astype(int) - _pixels(named, True, monkeypatch)[1]).max() <= 1
    assert _pixels(_grid(np.linspace(10.0, 400.0, 6), np.array([1e-4, 2e-4, 5e-4])))[0] == [
        QuadMesh]
