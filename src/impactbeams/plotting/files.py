"""Figures into image files: atomically, missing folders made, the format from the suffix."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from impactbeams.io import atomic_write
from impactbeams.preflight import image_path


def save_figure(figure: Figure, path: str | Path, dpi: float = 150) -> Path:
    """Save ``figure`` to ``path`` (matplotlib's default format if it has no suffix).

    Written as a temporary file renamed into place (`impactbeams.io.atomic_write`): an
    error leaves no partial image, and a failed write is a
    [`WriteError`][impactbeams.io.WriteError].
    Returns the file written.
    """
    path = image_path(path)
    atomic_write(path, lambda temporary: figure.savefig(
        temporary, format=path.suffix[1:].lower(), dpi=dpi))
    return path
