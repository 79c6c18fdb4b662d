"""The progress bar of a sweep: :class:`impactbeams.progress.Progress` (shared with simulate)."""

from impactbeams.progress import Progress

__all__ = ["Progress"]
