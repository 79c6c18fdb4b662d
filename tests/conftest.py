"""Shared fixtures: models are built once per session (SciPy work), kernels compile once."""

import os

# Small dense eigenproblems (the FE reference) run ~15x faster on one BLAS thread than on two
# competing with Numba's; set before NumPy loads its BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from impactbeams.kernels import source_digest  # noqa: E402  (imports no Numba)

# Numba's cache checks a kernel only against its own file, not the kernels it calls: key the
# cache by all kernel sources, so that tests never run stale code (CI sets its own clean dir).
# Set before Numba loads; subprocesses (CLI, Dask workers) inherit it.
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(
    os.path.dirname(os.path.dirname(__file__)), ".numba-cache", source_digest()))

import pytest  # noqa: E402

from impactbeams.model import build_tied_model  # noqa: E402
from impactbeams.params import Params  # noqa: E402


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """On the plain path (kernels/jit.py), skip the checks of how the fast path compiles."""
    from impactbeams.kernels.jit import plain_numba

    if not plain_numba():
        return
    skip = pytest.mark.skip(reason="kernels compile as plain Numba kernels (kernels/jit.py)")
    for item in items:
        if "fast_path" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def default_params() -> Params:
    return Params()


@pytest.fixture(scope="session")
def model50(default_params):
    """Default geometry, 50 free modes per beam, 100 contact modes."""
    return build_tied_model(default_params, 50)


@pytest.fixture
def captured(monkeypatch):
    """The figures the plotting functions would save, laid out on the Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    figures = []

    def keep(figure, path, dpi=150):
        FigureCanvasAgg(figure)
        figure.canvas.draw()
        figures.append(figure)

    for module in ("impactbeams.plotting.trajectories", "impactbeams.plotting"):
        monkeypatch.setattr(f"{module}.save_figure", keep)
    return figures
