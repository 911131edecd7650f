"""A progress bar for one long render on the terminal (`rast5d render`): sim.render calls it with
(bins done, bins); it stays silent for the first `delay` seconds, then redraws one stderr line at
most every 0.2 s with the share done, the time elapsed and an estimate of the time left (one line
every 5 s when stderr is not a terminal)."""
from __future__ import annotations

import sys
import time


class ProgressBar:
    def __init__(self, label: str = "render", delay: float = 2.0, stream=None, width: int = 30):
        self.label, self.delay, self.width = label, delay, width
        self.stream = stream if stream is not None else sys.stderr
        self.t0 = time.perf_counter()
        self.last = 0.0
        self.shown = False
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        elapsed = now - self.t0
        if elapsed < self.delay or (self.shown and now - self.last < (0.2 if self.tty else 5.0)) or total <= 0:
            return
        self.last = now
        self.shown = True
        frac = min(1.0, done / total)
        fill = int(round(frac * self.width))
        left = f"~{_dur(elapsed * (1.0 - frac) / frac)} left" if done > 0 else "estimating"
        self.stream.write(f"{chr(13) if self.tty else ''}{self.label} [{'#' * fill}{'.' * (self.width - fill)}] {100 * frac:3.0f}% "
                          f"{done}/{total} bins, {_dur(elapsed)} elapsed, {left}" + ("   " if self.tty else "\n"))
        self.stream.flush()

    def close(self) -> None:
        if self.shown and self.tty:
            self.stream.write("\n")
            self.stream.flush()
            self.shown = False


def _dur(s: float) -> str:
    s = max(0.0, s)
    if s < 60:
        return f"{s:.0f} s"
    m, s = divmod(int(s), 60)
    return f"{m} min {s:02d} s" if m < 60 else f"{m // 60} h {m % 60:02d} min"
