"""Progress reporting for long work: on a terminal only, silent with ``quiet``."""
from __future__ import annotations

import sys
import time


class Progress:
    """A one-line progress meter: items done, items per second and time left.

    Writes to ``stream`` (stderr by default) only when it is a terminal and
    ``quiet`` is false, so logs and pipes stay clean.

    Parameters
    ----------
    total : int or None
        Number of items expected, ``None`` when unknown.
    label : str
        Word shown before the counts ("frames", "particles", ...).
    """

    def __init__(self, total: int | None, label: str = "items", quiet: bool = False, stream=None):
        self.total = total
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = (not quiet) and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.done = 0
        self.start = time.perf_counter()
        self._last_draw = 0.0

    @property
    def rate(self) -> float:
        """Items per second so far."""
        elapsed = time.perf_counter() - self.start
        return self.done / elapsed if elapsed > 0 else 0.0

    def update(self, n: int = 1, note: str = "") -> None:
        self.done += n
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last_draw < 0.1 and (self.total is None or self.done < self.total):
            return
        self._last_draw = now
        rate = self.rate
        if self.total:
            left = (self.total - self.done) / rate if rate > 0 else float("nan")
            text = f"\r{self.label} {self.done}/{self.total}  {rate:.1f}/s  {left:.0f} s left"
        else:
            text = f"\r{self.label} {self.done}  {rate:.1f}/s"
        if note:
            text += f"  {note}"
        self.stream.write(text + "\033[K")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
