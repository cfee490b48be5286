"""Progress of runs and sweeps: a tqdm bar when tqdm is installed, else a
line on stderr every 10 s; or the caller's own callable."""

from __future__ import annotations

import sys
import time
from typing import Callable, Optional, Union

Progress = Union[bool, Callable[[int, int], None]]


class _Lines:
    def __init__(self, what: str, unit: str):
        self.what, self.unit = what, unit
        self.last = time.monotonic()

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        if now - self.last >= 10.0:
            self.last = now
            share = 100.0 * done / max(total, 1)
            print(f"slipfront: {self.what} {done}/{total} {self.unit} ({share:.0f} %)",
                  file=sys.stderr)

    def close(self) -> None:
        pass


class _Bar:
    def __init__(self, tqdm, what: str, unit: str):
        self.bar = tqdm(desc=what, unit=unit, unit_scale=True, leave=False)

    def __call__(self, done: int, total: int) -> None:
        if self.bar.total != total:
            self.bar.total = total
            self.bar.refresh()
        if done > self.bar.n:
            self.bar.update(done - self.bar.n)

    def close(self) -> None:
        self.bar.close()


def reporter(progress: Progress, what: str, unit: str):
    """(callback for the core, close) for a ``progress=`` argument."""
    if progress is False or progress is None:
        return None, lambda: None
    if callable(progress):
        return progress, lambda: None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        lines = _Lines(what, unit)
        return lines, lines.close
    bar = _Bar(tqdm, what, unit)
    return bar, bar.close
