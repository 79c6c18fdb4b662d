"""Every sweep resumes, bitwise (issue 20).

The chunk store, the netCDF file and the in-memory map hold every observable a sweep can store
with its registered dtype and shape (a test generated from the variable registry). A run of
each kind of sweep killed (SIGKILL) or interrupted (SIGINT) after some chunks and resumed by the
same command equals an uninterrupted run on every data variable, coordinate and dtype, locally
and on a Dask LocalCluster. Damaged chunks are named; a finished file is reused only if it
holds the sweep's map; two uninterrupted runs differ only in their ``history`` attribute.
"""

import functools
import signal
import subprocess
import sys
import warnings

import netCDF4
import numpy as np
import pytest
import xarray as xr

from impactbeams.cli import EXIT_INTERRUPTED, main
from impactbeams.params import ParameterError
from impactbeams.sweep import Chunking, load_sweep, sweep_from_mapping, write_sweep
from impactbeams.sweep.definition import (
    CONTACT_OBSERVABLES,
    LONG_TIME_OBSERVABLES,
    OBSERVABLES,
    STEPPED_END_STATE,
)
from impactbeams.sweep.output import cell_values, map_dataset, map_file
from impactbeams.sweep.store import NAMED_DAMAGED, ChunkStore
from impactbeams.variables import MAP_VARIABLES, VARIABLES
from test_distributed import local_cluster
from test_sweep import PROCESS_DEADLINE, _wait_for

# --- the store, the file and the in-memory map hold every stored observable as registered ---

# map variables that no chunk stores: derived from a stored one when the file is written, or
# computed by simulate() only
NOT_IN_CHUNKS = {"impacted": "written from first_impact_time",
                 "lyapunov_exponent_error": "simulate() only: maps compute the exponent alone"}
IN_CHUNKS = [name for name in MAP_VARIABLES if name not in NOT_IN_CHUNKS]


def test_every_map_variable_is_stored_in_chunks_or_derived():
    """A new map variable of the registry is a sweep observable (and so tested below) or is
    listed in NOT_IN_CHUNKS with the reason."""
    assert set(IN_CHUNKS) == {*OBSERVABLES, "dynamics_status", *STEPPED_END_STATE,
                              "first_contact"}
    assert set(NOT_IN_CHUNKS) < set(MAP_VARIABLES)


def _storing(name):
    """A three-cell sweep whose chunks store ``name`` (four samples along ``period``, four
    coordinates: 2 modes per beam, four contacts)."""
    observable = "impact_count" if name == "dynamics_status" else name  # comes with dynamics
    long_time = {"sampled_periods": 4} if name in LONG_TIME_OBSERVABLES else {}
    if name in STEPPED_END_STATE:  # a stepped sweep's, with its long-time samples
        observable = "poincare_deflection1"
        long_time = {"sampled_periods": 4, "stepping": "up", "n_modes": 2}
    params = {}
    if name == "first_contact":  # a map of several contacts'
        observable = "first_impact_time"
        params = {"params": {"contacts": [{"side": "below"}, {"side": "above"}]}}
    if name in CONTACT_OBSERVABLES:  # four contacts: four values per cell along "contact"
        params = {"params": {"counterpart": "stop", "contacts": [
            {"side": side, "position1": x} for x in (0.05, 0.1) for side in ("below", "above")]}}
    return sweep_from_mapping({"observables": [observable], **long_time, **params,
                               "axes": {"omega": {"min": 100.0, "max": 300.0, "num": 3}}})


def _values(dtype, shape, rng):
    """Values of ``dtype`` in ``shape`` with the extremes a store could mangle."""
    if dtype.kind == "f":
        special = [np.nan, np.inf, -np.inf, -0.0, 5e-324, np.finfo(dtype).max]
        values = rng.standard_normal(shape)
    else:
        special = [np.iinfo(dtype).min, np.iinfo(dtype).max, 0]
        values = rng.integers(np.iinfo(dtype).min, np.iinfo(dtype).max, shape, endpoint=True)
    values.flat[:len(special)] = special
    return values.astype(dtype)


def _bits(array):
    return np.asarray(array).dtype, np.asarray(array).shape, np.asarray(array).tobytes()


@pytest.mark.parametrize("name", IN_CHUNKS)
def test_every_stored_observable_round_trips_with_its_registered_dtype_and_shape(tmp_path, name):
    """Saved and loaded by the chunk store, written into the map's file, held in memory: the
    same bits, dtype and shape, the registered ones (the kernels' own dtype is cast losslessly
    on saving: dynamics_status comes as float64)."""
    sweep = _storing(name)
    dtype, shape = cell_values(sweep)[name]
    assert dtype == VARIABLES[name].dtype
    assert len(shape) == len(VARIABLES[name].dims) - 1 and shape == (4,) * len(shape)
    rng = np.random.default_rng(20)
    values = {stored: _values(kind, (sweep.size, *cell), rng)
              for stored, (kind, cell) in cell_values(sweep).items()}
    out, chunking = tmp_path / "map.nc", Chunking.at_most(sweep.shape, sweep.size)
    store = ChunkStore(out, sweep, chunking, None)
    store.save(0, values)
    assert {key: _bits(array) for key, array in store.load(0, sweep.size).items()} == {
        key: _bits(array) for key, array in values.items()}
    if dtype.kind == "i":  # as the kernels give it: float64, cast on saving
        store.save(0, {key: array.astype(np.float64) for key, array in values.items()})
        assert _bits(store.load(0, sweep.size)[name]) == _bits(values[name])
    assert not store.damaged
    with map_file(sweep, out, store.building, chunking) as write:
        write(0, sweep.size, values)
    grid_dims = (*(("sweep_direction",) if sweep.stepping else ()),
                 *(axis.name for axis in sweep.axes), *VARIABLES[name].dims[1:])
    expected = _bits(values[name].reshape(sweep.shape + shape))
    with xr.open_dataset(out) as written:
        assert written[name].dims == grid_dims
        assert _bits(written[name].values) == expected
    in_memory = map_dataset(sweep, values)
    assert in_memory[name].dims == grid_dims and _bits(in_memory[name].values) == expected


# --- the kill/resume matrix ---------------------------------------------------------------------

# One small sweep of each kind, in chunks of one cell (--chunk-cells 1): about a second of work
# on one thread (40 to 600 chunks), so that a run is caught after a few chunks and long before
# its end. Spring contacts soft enough for 5 modes (no warning).
KINDS = {
    "first-impact": (  # omega last: no affine column, one cell per chunk; a third impacts
        "t_max = 0.5\nn_modes = 5\n"
        '[axes.force_amplitude]\nmin = 1e-6\nmax = 1e-3\nnum = 15\nscale = "log"\n'
        "[axes.omega]\nmin = 100.0\nmax = 500.0\nnum = 40\n"),
    "several-contacts": (  # a two-sided stop at mid-span: first_contact too
        "t_max = 0.5\nn_modes = 5\n[params]\ncounterpart = \"stop\"\n"
        "[[params.contacts]]\nposition1 = 0.05\n"
        "[[params.contacts]]\nposition1 = 0.05\nside = \"above\"\nclearance = 5e-6\n"
        '[axes.force_amplitude]\nmin = 1e-6\nmax = 1e-3\nnum = 15\nscale = "log"\n'
        "[axes.omega]\nmin = 100.0\nmax = 500.0\nnum = 40\n"),
    "several-dynamics": (  # stops at mid-span and tip: each contact's share along "contact"
        't_max = 0.1\nn_modes = 5\nobservables = ["contact_impact_count", "contact_max_force"]\n'
        "[params]\ncounterpart = \"stop\"\nforce_amplitude = 1e-3\ncontact_stiffness = 1e3\n"
        "[[params.contacts]]\nposition1 = 0.05\nclearance = 1e-6\n"
        "[[params.contacts]]\nclearance = 2e-6\n"
        "[axes.omega]\nmin = 100.0\nmax = 1000.0\nnum = 40\n"),
    "dynamics": (  # and a categorical axis
        't_max = 2.0\nn_modes = 5\nobservables = ["first_impact_time", "impact_count", '
        '"max_contact_force", "mean_restitution", "contact_fraction"]\n'
        "[params]\nforce_amplitude = 1e-2\ncontact_stiffness = 100.0\n"
        '[axes.contact_law]\nvalues = ["tied", "spring"]\n'
        "[axes.omega]\nmin = 100.0\nmax = 1000.0\nnum = 20\n"),
    "long-time": (  # response_period (int32) and samples along period
        'n_modes = 5\nobservables = ["poincare_deflection1", "poincare_deflection2", '
        '"poincare_velocity1", "poincare_velocity2", "response_period", '
        '"steady_impact_rate", "steady_episode_rate"]\n'
        "transient_periods = 1500\nsampled_periods = 8\nmax_period = 4\n"
        "[params]\nforce_amplitude = 1e-2\ndamping_ratio = 0.03\ncontact_stiffness = 100.0\n"
        "[axes.omega]\nmin = 100.0\nmax = 1000.0\nnum = 40\n"),
    "lyapunov": (
        't_max = 8.0\nn_modes = 5\nobservables = ["lyapunov_exponent"]\ntransient_periods = 10\n'
        "[params]\nforce_amplitude = 1e-2\ncontact_stiffness = 100.0\n"
        "[axes.omega]\nmin = 100.0\nmax = 1000.0\nnum = 40\n"),
}
SAVED_BEFORE_THE_SIGNAL = 3


def test_the_matrix_covers_every_observable(tmp_path):
    stored = set()
    for kind, text in KINDS.items():
        (tmp_path / f"{kind}.toml").write_text(text)
        stored |= set(load_sweep(tmp_path / f"{kind}.toml").stored)
    # a stepped sweep's end states: resumed in tests/test_stepped.py
    assert stored | set(STEPPED_END_STATE) == set(IN_CHUNKS)


@pytest.fixture(scope="module")
def sweep_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweeps")
    for kind, text in KINDS.items():
        (folder / f"{kind}.toml").write_text(text)
    return folder


def _command(sweep_files, kind, out, *options):
    return ["run", str(sweep_files / f"{kind}.toml"), "-o", str(out), "--chunk-cells", "1",
            "--quiet", *(options or ("--threads", "1"))]


def uninterrupted_runs(folder, command):
    """``run(name)``: the file ``folder/name.nc`` of ``main(command(name, out))``, run once."""
    @functools.cache
    def run(name):
        out = folder / f"{name}.nc"
        assert main(command(name, out)) == 0
        return out

    return run


@pytest.fixture(scope="module")
def uninterrupted(sweep_files, tmp_path_factory):
    """The file of an uninterrupted run of each kind (computed once, when first asked for)."""
    return uninterrupted_runs(tmp_path_factory.mktemp("uninterrupted"),
                              functools.partial(_command, sweep_files))


def _contents(path):
    """Every variable's dtype, dimensions, bytes and attributes, and the global attributes."""
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        variables = {}
        for name, variable in nc.variables.items():
            values = variable[:]
            data = values.tolist() if values.dtype == object else values.tobytes()  # strings
            attrs = {key: repr(variable.getncattr(key)) for key in variable.ncattrs()}
            variables[name] = (str(values.dtype), variable.dimensions, data, attrs)
        return variables, {key: nc.getncattr(key) for key in nc.ncattrs()}


def assert_same_map(path, reference):
    """Bitwise equal data variables and coordinates, the same dtypes, dimensions and
    attributes; the global attributes but ``history`` equal."""
    (variables, attrs), (expected, expected_attrs) = _contents(path), _contents(reference)
    assert variables.keys() == expected.keys()
    for name in expected:
        assert variables[name] == expected[name], name
    assert attrs.pop("history") and expected_attrs.pop("history")
    assert attrs == expected_attrs


# the command line with every locally computed chunk 0.1 s longer: the signal always finds the
# run going, however loaded the machine (a poll starved for a second could miss a fast run)
SLOW_CLI = ("import sys, time\n"
            "from impactbeams.sweep import run\n"
            "compute = run.compute_chunk\n"
            "def slow(*args, **kwargs):\n"
            "    time.sleep(0.1)\n"
            "    return compute(*args, **kwargs)\n"
            "run.compute_chunk = slow\n"
            "from impactbeams.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")


# Ctrl-C's handler in the child whatever the parent's: a shell without job control starts its
# background jobs (and their children) with SIGINT ignored, and Python then installs none
DEFAULT_SIGINT = "import signal\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"


def _saved_chunks(partial):
    return len(list(partial.glob("chunk_*.npz")))


def _interrupt(command, partial, how, saved=_saved_chunks, script=SLOW_CLI,
               before=SAVED_BEFORE_THE_SIGNAL):
    """Run ``command`` in a CLI process (``script``); send it ``how`` once ``saved(partial)``
    (the chunks saved, by default) reaches ``before``. Returns what it reached in the end;
    the process's stderr is in ``partial``'s folder, ``stderr.txt``."""
    log = partial.with_name("stderr.txt")
    with open(log, "w") as stderr:
        process = subprocess.Popen([sys.executable, "-c", DEFAULT_SIGINT + script, *command],
                                   stderr=stderr)
        try:
            _wait_for(lambda: saved(partial) >= before, f"{before} saved", process, log)
            process.send_signal(how)
            process.wait(timeout=PROCESS_DEADLINE)
        finally:
            process.kill()  # no-op when it has ended; never leave it running
            process.wait()
    expected = EXIT_INTERRUPTED if how == signal.SIGINT else -how
    assert process.returncode == expected, (
        f"code {process.returncode}, not {expected}: it ended by itself before the signal?\n"
        f"{log.read_text()}")
    return saved(partial)


def _kill_and_resume(sweep_files, uninterrupted, tmp_path, capsys, kind, how, *options):
    reference = uninterrupted(kind)  # first: compiled here, the CLI process loads the kernels
    out = tmp_path / f"{kind}.nc"
    command = _command(sweep_files, kind, out, *options)
    saved = _interrupt(command, tmp_path / f"{kind}.nc.partial", how)
    count = Chunking.at_most(load_sweep(sweep_files / f"{kind}.toml").shape, 1).count
    assert not out.exists() and SAVED_BEFORE_THE_SIGNAL <= saved < count - 1
    capsys.readouterr()
    with warnings.catch_warnings():  # the CLI prints its warnings as one line each
        warnings.simplefilter("always")
        assert main(command) == 0  # the same command
    # a killed run cannot release its output's lock: the same command takes it over, warning
    taken_over = "warning: took over the lock file" in capsys.readouterr().err
    assert taken_over == (how == signal.SIGKILL)
    assert not (tmp_path / f"{kind}.nc.partial").exists()
    assert not (tmp_path / f"{kind}.nc.lock").exists()
    assert_same_map(out, reference)


SIGNALS = {"SIGKILL": signal.SIGKILL, "SIGINT": signal.SIGINT}
# the fast subset: each kind once, each signal at least twice; the rest is slow
FAST = {("long-time", "SIGKILL"), ("lyapunov", "SIGINT"), ("dynamics", "SIGKILL"),
        ("first-impact", "SIGINT"), ("several-dynamics", "SIGKILL")}


@pytest.mark.parametrize(("kind", "how"), [
    pytest.param(kind, how, marks=() if (kind, how) in FAST else pytest.mark.slow)
    for kind in KINDS for how in SIGNALS])
def test_a_killed_run_resumes_to_the_uninterrupted_map(sweep_files, uninterrupted, tmp_path,
                                                       capsys, kind, how):
    _kill_and_resume(sweep_files, uninterrupted, tmp_path, capsys, kind, SIGNALS[how])


@pytest.mark.parametrize("kind", KINDS)
def test_two_uninterrupted_runs_differ_only_in_their_history(sweep_files, uninterrupted,
                                                             tmp_path, kind):
    """What docs/sweep-files.md promises: every data variable and coordinate bitwise (with
    its dtype and attributes), every global attribute but the time-stamped ``history``."""
    with xr.open_dataset(uninterrupted(kind)) as reference:  # no constant map: a real test
        for name in load_sweep(sweep_files / f"{kind}.toml").observables:
            assert np.unique(reference[name].values).size > 1, name
    again = tmp_path / "again.nc"
    assert main(_command(sweep_files, kind, again)) == 0
    assert_same_map(again, uninterrupted(kind))
    history = [_contents(path)[1]["history"] for path in (again, uninterrupted(kind))]
    assert len({line.split(": ", 1)[1] for line in history}) == 1  # but the time


@pytest.fixture(scope="module")
def scheduler():
    """The address of a LocalCluster of two loopback workers (all gone at the module's end)."""
    with local_cluster() as client:
        yield client.scheduler.address


@pytest.mark.parametrize(("kind", "how"), [
    ("long-time", "SIGKILL"),
    pytest.param("dynamics", "SIGINT", marks=pytest.mark.slow),
    pytest.param("lyapunov", "SIGKILL", marks=pytest.mark.slow),
    pytest.param("first-impact", "SIGINT", marks=pytest.mark.slow)])
def test_a_killed_client_of_a_cluster_resumes_to_the_uninterrupted_map(
        sweep_files, uninterrupted, scheduler, tmp_path, capsys, kind, how):
    """The CLI's client killed while the cluster computes; the same command resumes on it. The
    map equals the local uninterrupted run's (the same bits on workers and here)."""
    _kill_and_resume(sweep_files, uninterrupted, tmp_path, capsys, kind, SIGNALS[how],
                     "--scheduler", scheduler)


# --- damaged chunks, finished files -------------------------------------------------------------


def test_damaged_chunks_are_named_and_only_they_are_recomputed(sweep_files, uninterrupted,
                                                               tmp_path, capsys):
    """Not the first chunk checked but the damaged ones: one named with its fault and the others
    named up to NAMED_DAMAGED, then counted; --discard-corrupt recomputes exactly those."""
    sweep, out = load_sweep(sweep_files / "long-time.toml"), tmp_path / "long-time.nc"

    def stop(chunk):
        if chunk == 7:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_sweep(sweep, out, chunk_cells=1, threads=1, on_chunk=stop)
    saved = sorted((tmp_path / "long-time.nc.partial").glob("chunk_*.npz"))
    assert [path.name for path in saved] == [f"chunk_{k:06d}.npz" for k in range(8)]
    saved[2].write_bytes(b"")
    saved[4].write_bytes(saved[4].read_bytes()[:200])
    command = _command(sweep_files, "long-time", out)
    assert main(command) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"impactbeams: error: 2 saved chunks are damaged: {saved[2]} (EOFError: No data left "
        "in file), chunk_000004.npz: run again with --discard-corrupt (discard_corrupt=True) to "
        f"recompute their cells, or delete {saved[0].parent}")
    for path in (saved[0], saved[1], saved[3], saved[5], saved[6]):
        path.write_bytes(b"")
    assert main(command) == 2
    assert capsys.readouterr().err.splitlines()[-1].startswith(
        f"impactbeams: error: 7 saved chunks are damaged: {saved[0]} (EOFError: No data left in "
        "file), chunk_000001.npz, chunk_000002.npz, chunk_000003.npz, chunk_000004.npz and "
        "2 more: run again with --discard-corrupt")
    assert NAMED_DAMAGED == 5 and all(path.exists() for path in saved) and not out.exists()
    computed = []
    with pytest.warns(RuntimeWarning, match="discarded the damaged chunk") as discarded:
        write_sweep(sweep, out, chunk_cells=1, threads=1, discard_corrupt=True,
                    on_chunk=computed.append)
    assert len(discarded) == 7
    assert sorted(computed) == [k for k in range(sweep.size) if k != 7]  # chunk 7 was loaded
    assert_same_map(out, uninterrupted("long-time"))


def _zero_omega(reference, out):
    out.write_bytes(reference.read_bytes())
    with netCDF4.Dataset(out, "a") as nc:
        nc["omega"][:] = 0.0  # as a second writer once left it


def _rewritten(change):
    def rewrite(reference, out):
        with xr.open_dataset(reference) as dataset:
            change(dataset.load()).to_netcdf(out)
    return rewrite


FILE_CHANGES = {  # kind, change, what the error says
    "omega all 0.0": ("long-time", _zero_omega,
                      "40 of the 40 values of its coordinate omega differ from the sweep's (first "
                      "at index 0: 0.0, the sweep's 100.0)"),
    "another law": ("dynamics", _rewritten(lambda d: d.assign_coords(
                        contact_law=["tied", "tied"])),
                    "1 of the 2 values of its coordinate contact_law differ from the sweep's "
                    "(first at index 1: 'tied', the sweep's 'spring')"),
    "float64 periods": ("long-time", _rewritten(lambda d: d.assign(
                            response_period=d.response_period.astype(np.float64))),
                        "its variable response_period has float64 values along ('omega',), the "
                        "sweep's map int32 along ('omega',)"),
    "a variable missing": ("lyapunov", _rewritten(lambda d: d.drop_vars("dynamics_status")),
                           "it has the variables lyapunov_exponent, omega, the sweep's map "
                           "dynamics_status, lyapunov_exponent, omega"),
}


@pytest.mark.parametrize("change", FILE_CHANGES)
def test_a_finished_file_is_reused_only_if_it_holds_the_sweeps_map(
        sweep_files, uninterrupted, tmp_path, capsys, change):
    """Its fingerprint and code digest match, but its coordinates or variables do not: one line,
    exit 2, the file left as it was. Unchanged, it is reused."""
    kind, edit, difference = FILE_CHANGES[change]
    out = tmp_path / "out.nc"
    edit(uninterrupted(kind), out)
    before = out.read_bytes()
    assert main(_command(sweep_files, kind, out)) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"impactbeams: error: {out} records this sweep and code but does not hold its map: "
        f"{difference}; delete it or choose another output")
    assert out.read_bytes() == before
    with pytest.raises(ParameterError, match="does not hold its map"):
        write_sweep(load_sweep(sweep_files / f"{kind}.toml"), out)
    intact = uninterrupted(kind).read_bytes()
    out.write_bytes(intact)
    reuse = [argument for argument in _command(sweep_files, kind, out) if argument != "--quiet"]
    assert main(reuse) == 0
    assert "reused" in capsys.readouterr().err and out.read_bytes() == intact
