"""The one timer of the benchmarks: the best of ``repeat`` wall-clock calls.

The best (not the mean) is the run least disturbed by the rest of the machine; every
benchmark compares it with a baseline timed the same way in the same run.
"""

from __future__ import annotations

import time
from collections.abc import Callable


def best_of(fn: Callable[[], object], repeat: int = 5) -> float:
    """Shortest of ``repeat`` calls of ``fn``, s (``time.perf_counter``)."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
