"""A killed or interrupted continuation resumes from its last step, bit for bit (issue 32).

`impactbeams continue` in a child process, stopped mid-branch by SIGKILL, SIGTERM or SIGINT
(Ctrl-C); the same command again ends with the file an uninterrupted run writes: every
variable and coordinate bitwise, with its dtype and attributes, every global attribute but the
time-stamped ``history`` (`test_resume.assert_same_map`, as for the sweeps). The model is
`test_continuation_events`'s (two beams, 3 modes each) over 248.8 to 250.5 rad/s: ``POINTS``
points on two branches (a period doubling switched to), about 3 s; the Newton-Picard variant
carries its basis from step to step, which the checkpoints must carry too. A continuation of
several contacts (a two-sided stop, ``[[params.contacts]]``) resumes the same way, from Python
and from the command line.
"""

import functools
import json
import signal
import warnings

import pytest

import impactbeams as ib
from impactbeams.cli import EXIT_INTERRUPTED, main
from impactbeams.continuation import (
    Continuation,
    ContinuationInterrupted,
    continue_orbits,
    load_continuation,
)
from impactbeams.continuation.checkpoint import saved_points
from impactbeams.params import ParameterError
from test_resume import _interrupt, assert_same_map, uninterrupted_runs

FILE = ("n_modes = 3\n[params]\ncontact_stiffness = 1e4\ndamping_ratio = 0.02\n"
        "force_amplitude = 3e-5\nclearance = 1.1e-5\n[continuation]\nparameter = 'omega'\n"
        "min = 248.8\nmax = 250.5\nstart = 248.9\nmax_branches = 2\nmethod = '{method}'\n")
METHODS = ("newton", "newton-picard")
POINTS = 79  # on both branches, uninterrupted
SAVED_BEFORE_THE_SIGNAL = 15  # of POINTS: mid-branch

# the command line with every checkpoint 50 ms longer: the signal finds the run going
SLOW_CLI = ("import sys, time\n"
            "from impactbeams.continuation import checkpoint\n"
            "save = checkpoint.CourseLog.__call__\n"
            "def slow(self, course):\n"
            "    save(self, course)\n"
            "    time.sleep(0.05)\n"
            "checkpoint.CourseLog.__call__ = slow\n"
            "from impactbeams.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("continuations")
    for method in METHODS:
        (folder / f"{method}.toml").write_text(FILE.format(method=method))
    return folder


def _command(files, method, out):
    return ["continue", str(files / f"{method}.toml"), "-o", str(out), "--quiet"]


@pytest.fixture(scope="module")
def uninterrupted(files, tmp_path_factory):
    """The file of an uninterrupted run of each method (computed once, when first asked)."""
    return uninterrupted_runs(tmp_path_factory.mktemp("uninterrupted"),
                              functools.partial(_command, files))


@pytest.mark.parametrize(("how", "method"), [(signal.SIGKILL, "newton"),
                                             (signal.SIGTERM, "newton-picard"),
                                             (signal.SIGINT, "newton")])
def test_a_stopped_continuation_resumes_to_the_uninterrupted_file(files, uninterrupted,
                                                                  tmp_path, capsys, how,
                                                                  method):
    reference = uninterrupted(method)  # first: compiled here, the CLI process loads the kernels
    out = tmp_path / "out.nc"
    command = _command(files, method, out)
    partial = tmp_path / "out.nc.partial"
    kept = _interrupt(command, partial, how, lambda _: saved_points(out), SLOW_CLI,
                      SAVED_BEFORE_THE_SIGNAL)
    stderr = (tmp_path / "stderr.txt").read_text()
    assert not out.exists() and SAVED_BEFORE_THE_SIGNAL <= kept < POINTS
    if how == signal.SIGINT:  # what was computed, to look at, and the way on
        assert stderr.splitlines()[-2].endswith(
            f"are in {partial / 'out.nc'}; the continuation's steps are kept in {partial}/ and "
            "the same command resumes from them")
        assert (partial / "out.nc").exists()
    capsys.readouterr()
    with warnings.catch_warnings():  # the CLI prints its warnings as one line each
        warnings.simplefilter("always")
        assert main([argument for argument in command if argument != "--quiet"]) == 0
    err = capsys.readouterr().err
    assert f"-> {out} (resuming from the {kept} branch points saved in {partial}/)" in err
    # a killed run cannot release its output's lock: the same command takes it over, warning
    assert ("warning: took over the lock file" in err) == (how != signal.SIGINT)
    assert not partial.exists() and not out.with_name("out.nc.lock").exists()
    assert_same_map(out, reference)


PARAMS = ib.Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5,
                   clearance=1.1e-5)


def _continuation(**changes):
    return Continuation(PARAMS, "omega", 248.8, 250.5, start=248.9, n_modes=3, max_branches=2,
                        **changes)


def _stop_after(count):
    seen = []

    def progress(branch, point):
        seen.append(point)
        if len(seen) == count:
            raise KeyboardInterrupt

    return progress


def test_from_python_resumed_after_each_of_several_interrupts_and_a_cut_log(uninterrupted,
                                                                           tmp_path):
    """Interrupted three times (the branch switched to among them), the log's last record cut
    short by a kill in the middle of a write: the same call still ends with the same file."""
    out = tmp_path / "out.nc"
    for count in (5, 40, 20):
        with pytest.raises(ContinuationInterrupted):
            continue_orbits(_continuation(method="newton"), _stop_after(count), out)
    (log,) = (tmp_path / "out.nc.partial").glob("course_*.log")  # a resume drops the older
    assert log.name == "course_0002.log"
    kept = saved_points(out)
    log.write_bytes(log.read_bytes()[:-100])  # the last record cut
    assert saved_points(out) == kept - 1
    dataset = continue_orbits(_continuation(method="newton"), None, out)
    assert dataset.branch_point.size == POINTS
    assert_same_map(out, uninterrupted("newton"))


def test_another_continuation_or_other_code_is_refused_in_one_line_before_the_header(
        files, tmp_path, capsys):
    """As a sweep's partial run: refused (exit 2, one line, nothing printed before), the
    partial folder left as it was."""
    out = tmp_path / "out.nc"
    with pytest.raises(ContinuationInterrupted):
        continue_orbits(_continuation(method="newton"), _stop_after(5), out)
    partial = tmp_path / "out.nc.partial"
    before = {path.name: path.read_bytes() for path in partial.iterdir()}
    changed = tmp_path / "changed.toml"
    changed.write_text(FILE.format(method="newton").replace("max = 250.5", "max = 250.6"))
    capsys.readouterr()
    assert main(["continue", str(changed), "-o", str(out)]) == 2
    assert capsys.readouterr().err == (
        f"impactbeams: error: {partial} holds a partial run of a different continuation: "
        "delete it or choose another output\n")
    with pytest.raises(ParameterError, match="a different continuation"):
        continue_orbits(_continuation(method="newton", max_step=0.05), None, out)
    record = json.loads((partial / "run.json").read_text())
    (partial / "run.json").write_text(json.dumps({**record, "code": "0123456789abcdef"}))
    assert main(_command(files, "newton", out)) == 2
    assert capsys.readouterr().err.startswith(
        f"impactbeams: error: {partial} holds a partial continuation computed by other "
        "impactbeams code (code digest 0123456789abcdef, this code ")
    (partial / "run.json").write_text(json.dumps(record))
    assert {path.name: path.read_bytes() for path in partial.iterdir()} == before


def test_a_full_disk_is_refused_before_the_header(files, tmp_path, capsys, monkeypatch):
    """16 kB free: refused in one line before any work (it computed the whole branch, then
    lost it at the write); the room asked for is the first branch's fewest points' log."""
    import shutil

    from impactbeams.continuation import load_continuation
    from impactbeams.continuation.checkpoint import expected_log_size

    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage._replace(free=16 * 1024))
    out = tmp_path / "out.nc"
    assert main(_command(files, "newton", out)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"impactbeams: error: -o/--output '{out}' is not allowed: the run needs "
                          "about ") and "16 KiB free" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []
    # 21 points at max_step (1.7 / 20 rad/s), 2 N = 12: each a 1.2 kB monodromy and the rest
    assert expected_log_size(load_continuation(files / "newton.toml")) == 2 * 21 * (
        8 * 144 + 64 * 12 + 2048)


# --- several contacts: a two-sided stop (issue 33) ---------------------------------------------

# 3 um below and 6 um above mid-span, with dashpots, 8 modes: along F0 from 0.3 to 0.38 mN the
# orbit grazes the stop below (as tests/test_orbits_several.py's branch): 26 points, 2-3 s
SEVERAL_FILE = (
    "n_modes = 8\n[params]\ncounterpart = 'stop'\ncontact_stiffness = 1e4\n"
    "damping_ratio = 0.05\nomega = 400.0\n"
    "[[params.contacts]]\nposition1 = 0.05\nside = 'below'\nclearance = 3e-6\ndamping = 0.5\n"
    "[[params.contacts]]\nposition1 = 0.05\nside = 'above'\nclearance = 6e-6\ndamping = 0.5\n"
    "[continuation]\nparameter = 'force_amplitude'\nmin = 3e-4\nmax = 3.8e-4\n"
    "method = '{method}'\n")


def test_a_continuation_of_several_contacts_resumes_to_the_uninterrupted_one(tmp_path):
    """Interrupted after 5 points, from Python, resumed across the grazing: the resumed run's
    file and Dataset are the uninterrupted run's, bit for bit (the Dataset but its
    ``history``)."""
    (tmp_path / "c.toml").write_text(SEVERAL_FILE.format(method="newton"))
    continuation = load_continuation(tmp_path / "c.toml")
    assert len(continuation.params.contacts) == 2
    reference = continue_orbits(continuation, None, tmp_path / "reference.nc")
    out = tmp_path / "out.nc"
    with pytest.raises(ContinuationInterrupted):
        continue_orbits(continuation, _stop_after(5), out)
    assert 0 < saved_points(out) < reference.branch_point.size
    resumed = continue_orbits(continuation, None, out)
    assert_same_map(out, tmp_path / "reference.nc")
    assert resumed.attrs.pop("history") and reference.attrs.pop("history")
    assert resumed.identical(reference)


def test_a_continuation_of_several_contacts_from_its_file_resumes_from_the_cli(
        tmp_path, capsys, monkeypatch):
    """`impactbeams continue` of ``[[params.contacts]]``, interrupted (Ctrl-C) after 4 saved
    points and run again: the uninterrupted run's file."""
    from impactbeams.continuation import checkpoint

    (tmp_path / "c.toml").write_text(SEVERAL_FILE.format(method="newton-picard"))
    command = ["continue", str(tmp_path / "c.toml"), "--quiet", "-o"]
    assert main([*command, str(tmp_path / "reference.nc")]) == 0
    save, saved = checkpoint.CourseLog.__call__, []

    def interrupted(self, course):
        save(self, course)
        saved.append(course)
        if len(saved) == 4:
            raise KeyboardInterrupt

    out = tmp_path / "out.nc"
    with monkeypatch.context() as patch:
        patch.setattr(checkpoint.CourseLog, "__call__", interrupted)
        assert main([*command, str(out)]) == EXIT_INTERRUPTED
    assert saved_points(out) == 4
    capsys.readouterr()
    assert main([*command, str(out)]) == 0
    assert_same_map(out, tmp_path / "reference.nc")
