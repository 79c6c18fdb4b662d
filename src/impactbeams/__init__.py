"""impactbeams: exact modal dynamics of two impacting cantilevers, and sweeps over it.

The physics follows Dzyubak & Bhaskar (2017) as corrected in docs/model.md. Heavy modules load on
first use, so ``import impactbeams`` stays fast and compiles nothing; so does ``__version__``
(reading the installed metadata costs more than the rest of the import).
"""

from importlib import import_module
from typing import Any

from impactbeams.params import ParameterError, Params

_LAZY = {
    "build_tied_model": "impactbeams.contact",
    "build_free_phase": "impactbeams.contact",
    "LongTime": "impactbeams.longtime",
    "load_sweep": "impactbeams.sweep",
    "run_sweep": "impactbeams.sweep",
    "simulate": "impactbeams.trajectory",
    "InitialFields": "impactbeams.trajectory",
    "PeriodMap": "impactbeams.orbits",
    "ContactsPeriodMap": "impactbeams.orbits",
    "periodic_orbit": "impactbeams.orbits",
    "steady_gap": "impactbeams.orbits",
    "grazing_curve": "impactbeams.orbits",
    "grazing_frequencies": "impactbeams.orbits",
    "basins": "impactbeams.orbits",
    "basin_stability": "impactbeams.orbits",
    "Settling": "impactbeams.orbits",
    "Continuation": "impactbeams.continuation",
    "continue_orbits": "impactbeams.continuation",
    "BifurcationCurve": "impactbeams.continuation",
    "continue_curve": "impactbeams.continuation",
    "plot_dataset": "impactbeams.plotting",
    "Cantilever": "impactbeams.structure",
    "Segment": "impactbeams.structure",
    "PointMass": "impactbeams.structure",
    "Spring": "impactbeams.structure",
    "Contact": "impactbeams.structure",
    "two_sided_stop": "impactbeams.structure",
    "first_contact": "impactbeams.trajectory",
    "contact_sequence": "impactbeams.trajectory",
    "MatrixStructure": "impactbeams.structure.user",
    "ModalStructure": "impactbeams.structure.user",
}

__all__ = ["ParameterError", "Params", "__version__", *_LAZY]
# old names, still loaded on demand but not advertised: build_model warns (build_tied_model)
_DEPRECATED = {"build_model": "impactbeams.contact"}


def _version() -> str:
    """The installed package's version ("0+unknown" in a source tree without installation)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("impactbeams")
    except PackageNotFoundError:
        return "0+unknown"


def __dir__() -> list[str]:
    """The public API (``__all__``), not the helpers this module imports."""
    return sorted(__all__)


def __getattr__(name: str) -> Any:
    if name == "__version__":
        globals()[name] = _version()  # once: later look-ups find the module attribute
        return globals()[name]
    if name in _LAZY or name in _DEPRECATED:
        return getattr(import_module({**_LAZY, **_DEPRECATED}[name]), name)
    raise AttributeError(f"module 'impactbeams' has no attribute {name!r}")
