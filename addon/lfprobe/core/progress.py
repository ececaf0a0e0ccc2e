"""Progress on a terminal: one line per stage, updated in place when stderr is a terminal."""

from __future__ import annotations

import sys
import time


class TerminalProgress:
    """A callback for native jobs: ``job.run(TerminalProgress())``."""

    def __init__(self, stream=None, min_interval: float = 5.0):
        self.stream = stream or sys.stderr
        self.interactive = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.min_interval = min_interval
        self._stage = None
        self._last = 0.0

    def __call__(self, fraction: float, stage: str) -> bool:
        now = time.monotonic()
        if stage == "done":
            if self.interactive and self._stage is not None:
                self.stream.write("\n")
            self._stage = None
            return True
        if stage != self._stage:
            if self.interactive and self._stage is not None:
                self.stream.write("\n")
            self._stage = stage
            if self.interactive:
                self._last = 0.0
        # On a terminal the line updates in place; in a log, a line every min_interval seconds.
        if now - self._last >= (0.1 if self.interactive else self.min_interval):
            self._last = now
            line = f"  {stage}: {100.0 * fraction:5.1f}%"
            self.stream.write(("\r" + line) if self.interactive else (line + "\n"))
            self.stream.flush()
        return True
