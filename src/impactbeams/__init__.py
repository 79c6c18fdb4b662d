"""impactbeams: exact modal dynamics of two impacting cantilevers, and sweeps over it.

The physics follows Dzyubak & Bhaskar (2017) as corrected in docs/model.md. Heavy modules load on
first use, so ``import impactbeams`` stays fast and compiles nothing.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from impactbeams.params import ParameterError, Params

try:
    __version__ = version("impactbeams")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"

_LAZY = {
    "build_model": "impactbeams.model",
    "build_free_phase": "impactbeams.model",
    "LongTime": "impactbeams.longtime",
    "load_sweep": "impactbeams.sweep",
    "run_sweep": "impactbeams.sweep",
    "simulate": "impactbeams.trajectory",
    "plot_dataset": "impactbeams.plotting",
}

__all__ = ["ParameterError", "Params", "__version__", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'impactbeams' has no attribute {name!r}")
