"""Shared fixtures: models are built once per session (SciPy work), kernels compile once."""

import os

# Small dense eigenproblems (the FE reference) run ~15x faster on one BLAS thread than on two
# competing with Numba's; set before NumPy loads its BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest  # noqa: E402

from impactbeams.model import build_model  # noqa: E402
from impactbeams.params import Params  # noqa: E402


@pytest.fixture(scope="session")
def default_params() -> Params:
    return Params()


@pytest.fixture(scope="session")
def model50(default_params):
    """Default geometry, 50 free modes per beam, 100 contact modes."""
    return build_model(default_params, 50)
