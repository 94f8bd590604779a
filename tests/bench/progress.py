"""Textual progress indicator for benchmark runs, on stderr so stdout keeps only the results.

On a terminal one line is redrawn in place (bar, step count, elapsed time, current task); in a
log (not a terminal) each step prints its own line."""

from __future__ import annotations

import sys
import time


class Progress:
    def __init__(self, total: int, stream=sys.stderr, width: int = 24):
        self.total, self.done = max(total, 1), 0
        self.stream, self.width = stream, width
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self.t0 = time.perf_counter()

    def _line(self, label: str) -> str:
        frac = min(self.done / self.total, 1.0)
        fill = int(round(frac * self.width))
        return (f"[{'#' * fill}{'.' * (self.width - fill)}] {self.done:>3}/{self.total} "
                f"{time.perf_counter() - self.t0:6.1f}s  {label}")

    def show(self, label: str) -> None:
        """Announce the step now starting."""
        if self.tty:
            self.stream.write("\r\x1b[K" + self._line(label)[:160])
        else:
            self.stream.write(self._line(label) + "\n")
        self.stream.flush()

    def step(self, label: str = "") -> None:
        """Mark one step finished (and show the next label, if any); in a log, a step with a
        label prints its line (a benchmark that only steps shows its progress there too)."""
        self.done += 1
        if label:
            self.show(label)

    def close(self) -> None:
        if self.tty:
            self.stream.write("\r\x1b[K")
            self.stream.flush()
