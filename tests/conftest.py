"""Shared fixtures: models are built once per session (SciPy work), kernels compile once."""

import pytest

from impactbeams.model import build_model
from impactbeams.params import Params


@pytest.fixture(scope="session")
def default_params() -> Params:
    return Params()


@pytest.fixture(scope="session")
def model50(default_params):
    """Default geometry, 50 free modes per beam, 100 contact modes."""
    return build_model(default_params, 50)
