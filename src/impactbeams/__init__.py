"""impactbeams: exact modal dynamics of two impacting cantilevers, and sweeps over it.

The physics follows Dzyubak & Bhaskar (2017) as corrected in MODEL.md. Heavy modules load on
first use, so ``import impactbeams`` stays fast and compiles nothing.
"""

from importlib.metadata import PackageNotFoundError, version

from impactbeams.params import ParameterError, Params

try:
    __version__ = version("impactbeams")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"

__all__ = ["ParameterError", "Params", "__version__"]
