"""Progress bars with an ETA (shown by the CLI; the library prints nothing by default)."""

from __future__ import annotations

import sys
import time
from typing import Any


class Progress:
    """Progress bar with ETA on stderr; one line per 10% when stderr is not a terminal.

    Counts ``total`` units (cells of a sweep, seconds of a simulated run, ...). The rate behind
    the ETA is measured from the end of the first computed update, which also pays for
    compiling the kernels (until then the ETA shows as unknown). The work may come in
    ``weights``: the expected cost of each part (in any unit), an update naming its ``part``;
    the ETA then assumes that the rest runs at the same cost per unit of weight, for work whose
    parts differ in cost.
    """

    def __init__(self, total: float, enabled: bool = True, stream: Any = None,
                 unit: str = "cells", weights: list[float] | None = None) -> None:
        self.total, self.done, self.enabled, self.unit = total, 0, enabled, unit
        self.weights = weights
        self.total_weight = total if weights is None else sum(weights)
        self.weighed = 0.0  # weight of the finished work
        self.stream = stream or sys.stderr
        self.interactive = self.stream.isatty()
        self.start = time.perf_counter()
        self.reported_decile = -1
        self.warm: tuple[float, float] | None = None  # (time, weight done) after the first

    def update(self, amount: float, computed: bool = True, part: int | None = None) -> None:
        """Record ``amount`` more finished units (``computed=False``: loaded from a resume).

        ``part``: the index of the part of ``weights`` finished (with weights only).
        """
        self.done += amount
        self.weighed += amount if self.weights is None or part is None else self.weights[part]
        now = time.perf_counter()
        eta = 0.0 if self.done >= self.total else float("nan")
        if computed and self.warm is None:
            self.warm = (now, self.weighed)
        elif computed and now > self.warm[0] and self.weighed > self.warm[1]:
            rate = (self.weighed - self.warm[1]) / (now - self.warm[0])
            eta = max(self.total_weight - self.weighed, 0.0) / rate
        if self.enabled:
            self._draw(now, eta)

    def reach(self, done: float) -> None:
        """Record the work finished so far as ``done`` units in all (e.g. simulated time)."""
        self.update(done - self.done)

    def stop(self, done: float, reason: str) -> None:
        """End the bar at ``done`` units, short of its total, saying why (a last line)."""
        self.done = done
        if self.enabled:
            self._draw(time.perf_counter(), float("nan"), f"stopped: {reason}")

    def _draw(self, now: float, eta: float, stopped: str = "") -> None:
        fraction = min(self.done / self.total, 1.0) if self.total else 1.0
        bar = "#" * int(30 * fraction)
        eta_text = "   ?  " if eta != eta else f"{eta:6.1f}"
        amounts = (f"{self.done}/{self.total}" if isinstance(self.total, int)
                   else f"{self.done:.4g}/{self.total:.4g}")
        line = (f"[{bar:<30}] {100 * fraction:5.1f}% {amounts} {self.unit} "
                f"{now - self.start:6.1f} s elapsed, " + (stopped or f"ETA {eta_text} s"))
        if stopped:
            self.stream.write(("\r" if self.interactive else "") + line + "\n")
        elif self.interactive:
            self.stream.write("\r" + line + ("\n" if fraction >= 1 else ""))
        elif int(10 * fraction) > self.reported_decile:
            self.reported_decile = int(10 * fraction)
            self.stream.write(line + "\n")
        self.stream.flush()
