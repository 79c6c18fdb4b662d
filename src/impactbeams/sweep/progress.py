"""The progress bar of a sweep (shown by the CLI; the library prints nothing by default)."""

from __future__ import annotations

import sys
import time
from typing import Any


class Progress:
    """Progress bar with ETA on stderr; one line per 10% when stderr is not a terminal.

    The rate behind the ETA is measured from the end of the first computed chunk, which also
    pays for compiling the kernels (until then the ETA shows as unknown).
    """

    def __init__(self, total: int, enabled: bool = True, stream: Any = None) -> None:
        self.total, self.done, self.enabled = total, 0, enabled
        self.stream = stream or sys.stderr
        self.interactive = self.stream.isatty()
        self.start = time.perf_counter()
        self.reported_decile = -1
        self.warm: tuple[float, int] | None = None  # (time, cells done) after the first chunk

    def update(self, cells: int, computed: bool = True) -> None:
        """Record ``cells`` more finished cells (``computed=False``: loaded from a resume)."""
        self.done += cells
        now = time.perf_counter()
        eta = 0.0 if self.done == self.total else float("nan")
        if computed and self.warm is None:
            self.warm = (now, self.done)
        elif computed and now > self.warm[0]:
            rate = (self.done - self.warm[1]) / (now - self.warm[0])
            eta = (self.total - self.done) / rate
        if self.enabled:
            self._draw(now, eta)

    def _draw(self, now: float, eta: float) -> None:
        fraction = self.done / self.total
        bar = "#" * int(30 * fraction)
        eta_text = "   ?  " if eta != eta else f"{eta:6.1f}"
        line = (f"[{bar:<30}] {100 * fraction:5.1f}% {self.done}/{self.total} cells "
                f"{now - self.start:6.1f} s elapsed, ETA {eta_text} s")
        if self.interactive:
            self.stream.write("\r" + line + ("\n" if self.done == self.total else ""))
        elif int(10 * fraction) > self.reported_decile:
            self.reported_decile = int(10 * fraction)
            self.stream.write(line + "\n")
        self.stream.flush()
