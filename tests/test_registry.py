"""The naming pass (issue 21): one list of contact laws, the package's public names and their
docs, status variables as CF flags, and the registry's check on every Dataset written or read."""

import re
import tomllib
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

import impactbeams
from impactbeams.cli import main
from impactbeams.io import write_netcdf
from impactbeams.kernels import layout
from impactbeams.params import CONTACT_LAWS, DEFAULT_CONTACT_LAW, ParameterError, Params
from impactbeams.plotting import draw, plot_dataset
from impactbeams.sweep import map_dataset, run_sweep, sweep_from_mapping
from impactbeams.variables import (
    DYNAMICS_STATUSES,
    VARIABLES,
    attributes,
    check_variables,
    validate,
)

ROOT = Path(__file__).resolve().parents[1]

# a map of the run status over one axis (values filled in, nothing computed)
STATUS_TOML = ('t_max = 0.3\nn_modes = 4\nobservables = ["impact_count"]\n[params]\n'
               'contact_law = "tied"\n[axes.omega]\nmin = 50.0\nmax = 200.0\nnum = 5\n')
STATUS_SWEEP = tomllib.loads(STATUS_TOML)
STATUS = np.array([0, 1, 2, 1, 3])

def status_map():
    sweep = sweep_from_mapping(STATUS_SWEEP, source="status.toml")
    return map_dataset(sweep, {"impact_count": np.arange(5.0), "dynamics_status": STATUS})


# --- names ----------------------------------------------------------------------------------


def test_one_list_of_contact_laws():
    # the kernels' integer codes (packing writes them into every settings record and geometry;
    # the kernels branch on them): pinned, so that no reordering goes unnoticed
    assert layout.CONTACT_LAWS == ("tied", "spring") and (layout.TIED, layout.SPRING) == (0, 1)
    # users see the same laws, the default first
    assert sorted(CONTACT_LAWS) == sorted(layout.CONTACT_LAWS)
    assert CONTACT_LAWS[0] == DEFAULT_CONTACT_LAW == Params().contact_law == "spring"


def test_params_compose_the_configuration_objects():
    """The flat keys name the objects (issue 33); the objects say what the strings did."""
    from impactbeams import configuration as c

    stop = Params(counterpart="stop", contact_law="tied", shaker="beam2")
    assert (stop.law, stop.partner, stop.mount) == (c.TIED_LAW, c.STOP, c.BEAM2)
    assert (Params().law, Params().partner, Params().mount) == (c.SPRING_LAW, c.BEAM, c.BOTH)
    assert [law.index for law in (c.TIED_LAW, c.SPRING_LAW)] == [layout.TIED, layout.SPRING]
    assert [(law.compliant, law.tangent_flow) for law in c.LAWS.values()] == [(True, True),
                                                                             (False, False)]
    assert [(p.beams, p.has_beam2) for p in c.COUNTERPARTS.values()] == [(2, True), (1, False)]
    # the clamps moved and the words of each (shaker, counterpart), as the tables before
    assert [m.clamps for m in c.MOUNTS.values()] == [(1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]
    assert {(m.name, p.name): m.place(p) for m in c.MOUNTS.values()
            for p in c.COUNTERPARTS.values()} == {
        ("both", "beam"): "on both clamps", ("beam1", "beam"): "on beam 1's clamp",
        ("beam2", "beam"): "on beam 2's clamp", ("both", "stop"): "on beam 1's clamp and the stop",
        ("beam1", "stop"): "on beam 1's clamp", ("beam2", "stop"): "on the stop"}
    assert [m.moves_stop(c.STOP) for m in c.MOUNTS.values()] == [True, False, True]
    assert not any(m.moves_stop(c.BEAM) for m in c.MOUNTS.values())
    assert [m.shaken_beams(c.BEAM) for m in c.MOUNTS.values()] == [("1", "2"), ("1",), ("2",)]
    assert {m.shaken_beams(c.STOP) for m in c.MOUNTS.values()} == {("1",)}


def test_dir_shows_the_public_api():
    names = dir(impactbeams)
    assert names == sorted(impactbeams.__all__)
    assert {"simulate", "run_sweep", "load_sweep", "Params", "plot_dataset"} <= set(names)
    assert not {"Any", "import_module"} & set(names)
    for name in names:  # each one is there (the lazy ones load on access)
        assert getattr(impactbeams, name) is not None


def _documented_root_names():
    """The names in the first column of docs/api.md's table: `impactbeams.NAME`."""
    text = (ROOT / "docs" / "api.md").read_text()
    cells = re.findall(r"^\| ([^|]*) \|", text, flags=re.MULTILINE)
    return {name for cell in cells for name in re.findall(r"`impactbeams\.(\w+)`", cell)}


def test_every_public_name_has_its_api_entry():
    """A name added to the package's API without a line in docs/api.md fails here."""
    public = set(impactbeams.__all__) - {"__version__"}
    documented = _documented_root_names()
    assert public - documented == set(), "public names missing from docs/api.md"
    assert documented - public == set(), "docs/api.md names what the package does not export"


# --- the status as CF flags -----------------------------------------------------------------


def test_statuses_are_the_kernels_codes():
    from impactbeams.kernels import dynamics

    assert DYNAMICS_STATUSES == dynamics.STATUS_NAMES
    codes = (dynamics.COMPLETE, dynamics.EVENT_LIMIT, dynamics.STUCK, dynamics.SEARCH_LIMIT)
    assert [DYNAMICS_STATUSES[code] for code in codes] == list(dynamics.STATUS_NAMES)


def test_dynamics_status_is_stored_with_cf_flags_and_read_back(tmp_path):
    flags = attributes("dynamics_status")
    assert flags["flag_values"].dtype == np.int8  # CF 3.5: the variable's own type
    assert flags["flag_values"].tolist() == [0, 1, 2, 3]
    assert flags["flag_meanings"] == "complete event_limit stuck search_limit"
    path = tmp_path / "status.nc"
    write_netcdf(status_map(), path)
    with netCDF4.Dataset(path) as nc:  # as stored: a byte attribute of the byte variable
        stored = nc["dynamics_status"]
        assert stored.dtype == np.int8 and stored.getncattr("flag_values").dtype == np.int8
        assert stored.getncattr("flag_values").tolist() == [0, 1, 2, 3]
        assert stored.getncattr("flag_meanings") == flags["flag_meanings"]
    with xr.open_dataset(path) as read:
        validate(read)
        assert read.dynamics_status.values.tolist() == STATUS.tolist()


@pytest.fixture
def figure():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    figure = Figure(layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _strip_flags(dataset):
    for key in ("flag_values", "flag_meanings"):
        del dataset.dynamics_status.attrs[key]
    return dataset


@pytest.mark.parametrize("flags", ["stored", "earlier version"])
def test_status_plots_are_labelled_with_the_meanings(figure, flags):
    """By the file's flags; a file of an earlier version has none: by the registry's."""
    dataset = status_map() if flags == "stored" else _strip_flags(status_map())
    axes = figure.subplots()
    draw(axes, dataset, "dynamics_status")
    figure.canvas.draw()
    assert [t.get_text() for t in axes.get_yticklabels()] == [
        "complete", "event limit", "stuck", "search limit"]


# --- the registry's check -------------------------------------------------------------------


def _described(dataset):
    return {str(name): (v.dims, v.dtype, v.attrs) for name, v in dataset.variables.items()}


def test_validate_names_what_is_wrong():
    good = status_map()
    validate(good)
    cases = {
        "units": ("impact_count", {"units": "s"}, "variable 'impact_count' has units = 's', "
                                                  "expected '1'"),
        "flags": ("dynamics_status", {"flag_meanings": "ok late stuck slow"},
                  "variable 'dynamics_status' has flag_meanings = 'ok late stuck slow', "
                  "expected 'complete event_limit stuck search_limit'"),
        "parameter": ("omega", {"units": "Hz"}, "variable 'omega' has units = 'Hz', "
                                                "expected 'rad/s'"),
    }
    for name, changes, message in cases.values():
        bad = good.copy(deep=True)
        bad[name].attrs.update(changes)
        with pytest.raises(ValueError, match=re.escape(message)):
            validate(bad)
    with pytest.raises(ValueError, match="'dynamics_status' has dtype float64, expected int8"):
        validate(good.assign(dynamics_status=good.dynamics_status.astype(float)))
    period = VARIABLES["poincare_deflection1"]
    with pytest.raises(ValueError, match=r"dimensions \('omega',\), expected \(the swept axes, "
                                         r"period\)"):
        check_variables({"poincare_deflection1": (("omega",), np.dtype(period.dtype),
                                                  attributes("poincare_deflection1"))})
    # "*" stands for any swept axes, none included (a single run's exponent)
    for dims in [(), ("omega",), ("omega", "clearance")]:
        check_variables({"lyapunov_exponent": (dims, np.dtype("float64"),
                                               attributes("lyapunov_exponent"))})


def test_missing_flags_are_a_bug_on_write_and_an_earlier_version_on_read():
    old = _strip_flags(status_map())
    with pytest.raises(ValueError, match="flag_values = None, expected"):
        validate(old)
    validate(old, strict=False)


def test_a_map_not_as_registered_is_a_package_bug(monkeypatch):
    import impactbeams.sweep.output as output

    def wrong(name):
        return {**attributes(name), "units": "ms"}

    monkeypatch.setattr(output, "attributes", wrong)
    with pytest.raises(ValueError, match="has units = 'ms', expected"):
        status_map()


def _bad_file(path):
    bad = status_map()
    bad.impact_count.attrs["units"] = "s"
    write_netcdf(bad, path)


def test_cli_refuses_a_file_not_as_registered_in_one_line(tmp_path, capsys):
    _bad_file(tmp_path / "bad.nc")
    assert main(["plot", str(tmp_path / "bad.nc"), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err == (f"impactbeams: error: input file {str(tmp_path / 'bad.nc')!r} is not as "
                   "impactbeams writes it: variable 'impact_count' has units = 's', expected "
                   "'1'\n")
    assert not (tmp_path / "x.png").exists()


def test_files_of_earlier_versions_are_plotted_and_reused(tmp_path, capsys):
    """Without flags: drawn, and a finished run (its stopped cells: exit 3) is reused."""
    path = tmp_path / "old.nc"
    write_netcdf(_strip_flags(status_map()), path)
    before = path.read_bytes()
    assert main(["plot", str(path), "-o", str(tmp_path / "old.png"), "--var",
                 "dynamics_status"]) == 0
    assert capsys.readouterr().err == f"wrote {tmp_path / 'old.png'}\n"
    (tmp_path / "status.toml").write_text(STATUS_TOML)
    assert main(["run", str(tmp_path / "status.toml"), "-o", str(path)]) == 3
    assert capsys.readouterr().err.startswith(f"reused {path}: it already holds the result")
    assert path.read_bytes() == before


def test_plot_dataset_refuses_a_dataset_not_as_registered(tmp_path):
    bad = status_map()
    bad.impact_count.attrs["long_name"] = "impacts"
    with pytest.raises(ParameterError, match="dataset is not as impactbeams writes it: variable "
                                             "'impact_count' has long_name = 'impacts'"):
        plot_dataset(bad, tmp_path / "x.png")


def test_an_existing_output_not_as_registered_is_not_reused(tmp_path, capsys):
    """This sweep's map by this code, edited since: refused by the library and the command."""
    path = tmp_path / "bad.nc"
    _bad_file(path)
    before = path.read_bytes()
    message = (f"{path} records this sweep and code but does not hold its map: variable "
               "'impact_count' has units = 's', expected '1'; delete it or choose another output")
    sweep = sweep_from_mapping(STATUS_SWEEP, source="status.toml")
    with pytest.raises(ParameterError, match=re.escape(message)):
        run_sweep(sweep, output=path, progress=False)
    (tmp_path / "status.toml").write_text(STATUS_TOML)
    assert main(["run", str(tmp_path / "status.toml"), "-o", str(path), "--quiet"]) == 2
    assert capsys.readouterr().err == f"impactbeams: error: {message}\n"
    assert path.read_bytes() == before
