"""An interrupted curve in two parameters resumes from its last step, bit for bit (issue 34).

As a one-parameter continuation (`test_continuation_resume`): `continue_curve` with an output,
interrupted (Ctrl-C from a progress callback, three times, the log's last record then cut by
hand) and called again, writes the file an uninterrupted call writes (every variable bitwise,
`test_resume.assert_same_map`); `impactbeams continue` with a ``[curve]`` table, killed while
it follows the curve, resumes from the branch it saved and the curve's last step. The model is
`test_two_parameter`'s soft stop (3 modes): its upper fold at 0.1 mN followed down through the
cusp and back up as the lower fold, about 100 points in 2 s.
"""

import signal
import warnings

import pytest

from impactbeams.cli import main
from impactbeams.continuation import Continuation, ContinuationInterrupted, continue_orbits
from impactbeams.continuation.checkpoint import saved_points
from impactbeams.continuation.twoparameter import BifurcationCurve, continue_curve
from impactbeams.params import ParameterError
from test_continuation_resume import _stop_after
from test_resume import _interrupt, assert_same_map
from test_two_parameter import STOP, STOP_CURVE_FILE

# test_two_parameter's command file, the curve followed as `curve` below
FILE = STOP_CURVE_FILE.replace("min = 1e-4\nmax = 1.2e-4\n", "min = 1e-6\nmax = 2e-4\n"
                               'direction = "down"\nmax_points = 400\n')
# the command line with every checkpoint of the curve 50 ms longer: the signal finds it going
SLOW_CLI = ("import sys, time\n"
            "from impactbeams.continuation import checkpoint\n"
            "save = checkpoint.CourseLog.__call__\n"
            "def slow(self, course):\n"
            "    save(self, course)\n"
            "    if 'run.json' in {p.name for p in self.directory.iterdir()}:\n"
            "        time.sleep(0.05)\n"
            "checkpoint.CourseLog.__call__ = slow\n"
            "from impactbeams.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
SAVED_BEFORE_THE_SIGNAL = 30  # curve points, of the uninterrupted run's ~100


@pytest.fixture(scope="module")
def curve():
    continuation = Continuation(STOP, "omega", 195.0, 330.0, n_modes=3, subspace=4,
                                max_branches=1)
    return BifurcationCurve.from_branch(continuation, continue_orbits(continuation), "fold",
                                        "force_amplitude", 1e-6, 2e-4, direction="down",
                                        max_points=400)


@pytest.fixture(scope="module")
def uninterrupted(curve, tmp_path_factory):
    """The uninterrupted call's file and its number of points."""
    out = tmp_path_factory.mktemp("uninterrupted") / "curve.nc"
    dataset = continue_curve(curve, None, out)
    assert dataset.attrs["curve_ending"] == "bound"
    assert dataset.branch_point.size > 2 * SAVED_BEFORE_THE_SIGNAL
    return out, dataset.branch_point.size


def test_an_interrupted_curve_resumes_to_the_uninterrupted_file(curve, uninterrupted,
                                                                tmp_path):
    """Interrupted three times (the cusp among them), the log's last record cut short by a
    kill in the middle of a write: the same call still ends with the same file."""
    reference, points = uninterrupted
    out = tmp_path / "out.nc"
    partial = tmp_path / "out.nc.partial"
    sizes = []
    for count in (5, 40, 20):
        with pytest.raises(ContinuationInterrupted) as interrupted:
            continue_curve(curve, _stop_after(count), out)
        sizes.append(interrupted.value.dataset.branch_point.size)
        assert interrupted.value.dataset.attrs["curve_ending"] == "interrupted"
        assert (partial / "out.nc").exists() and not out.exists()
    assert sizes[0] == 5 and sizes[0] < sizes[1] < sizes[2] < points  # resumed each time
    (log,) = partial.glob("course_*.log")  # a resume drops the older
    assert log.name == "course_0002.log"
    kept = saved_points(out)
    log.write_bytes(log.read_bytes()[:-100])  # the last record cut
    assert saved_points(out) < kept
    dataset = continue_curve(curve, None, out)
    assert dataset.branch_point.size == points and not partial.exists()
    assert_same_map(out, reference)


def test_another_curves_partial_run_is_refused(curve, tmp_path):
    out = tmp_path / "out.nc"
    with pytest.raises(ContinuationInterrupted):
        continue_curve(curve, _stop_after(5), out)
    other = BifurcationCurve(**{**curve.__dict__, "max_points": 300})
    with pytest.raises(ParameterError) as error:
        continue_curve(other, None, out)
    assert str(error.value) == (f"{tmp_path / 'out.nc.partial'} holds a partial run of a "
                                "different continuation: delete it or choose another output")


@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGINT])
def test_a_stopped_curve_command_resumes_to_the_uninterrupted_file(uninterrupted, tmp_path,
                                                                   capsys, how):
    """Stopped while it follows the curve: the same command reads the branch it saved,
    resumes the curve from its last step and writes the Python call's file."""
    reference, points = uninterrupted
    path, out = tmp_path / "fold.toml", tmp_path / "out.nc"
    path.write_text(FILE)
    partial = tmp_path / "out.nc.partial"
    command = ["continue", str(path), "-o", str(out), "--quiet"]
    kept = _interrupt(command, partial, how, lambda _: saved_points(out), SLOW_CLI,
                      SAVED_BEFORE_THE_SIGNAL)
    assert not out.exists() and SAVED_BEFORE_THE_SIGNAL <= kept < points
    (branch,) = partial.glob("branch_*.nc")  # the branch, finished, and nothing else of it
    stderr = (tmp_path / "stderr.txt").read_text()
    if how == signal.SIGINT:
        assert stderr.splitlines()[-2].endswith(
            f"curve points computed are in {partial / 'out.nc'}; the curve's steps are kept "
            f"in {partial}/ and the same command resumes from them")
    capsys.readouterr()
    with warnings.catch_warnings():  # the CLI prints its warnings as one line each
        warnings.simplefilter("always")
        assert main(command[:-1]) == 0
    err = capsys.readouterr().err
    assert f"branch: read from {branch}: " in err
    assert f"resuming the curve from the {kept} points saved in {partial}/" in err
    assert not partial.exists() and not out.with_name("out.nc.lock").exists()
    assert_same_map(out, reference)
