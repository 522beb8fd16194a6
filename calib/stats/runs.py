"""Runs of a Monte Carlo: one random stream per run, chunks of runs, and the map that executes them.

Reproducibility contract: run ``k`` of a sweep with seed ``s`` always draws from
``SeedSequence(s, spawn_key=key).spawn(runs)[k]``, whatever the chunk size, the number of
processes or the cluster, so a sweep's results depend on ``(s, runs)`` only.

The domain (``calib``) never starts processes: a long sweep takes a ``mapper`` argument, a
callable ``mapper(fn, tasks, progress=None) -> list`` that returns ``[fn(t) for t in tasks]``
in task order. :func:`serial_map` is the in-process default; ``bench.sweep`` provides a local
process pool and a Dask cluster with the same signature. ``fn`` must be a module-level
function and the tasks picklable, so any mapper can ship them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np


class Mapper(Protocol):
    """``mapper(fn, tasks, progress=None) -> [fn(t) for t in tasks]`` (in task order).

    ``progress(done, total)`` is called as tasks finish (counts of tasks, not of runs).
    """

    def __call__(self, fn: Callable[[Any], Any], tasks: Sequence[Any],
                 progress: Callable[[int, int], None] | None = None) -> list: ...


def serial_map(fn: Callable[[Any], Any], tasks: Sequence[Any],
               progress: Callable[[int, int], None] | None = None) -> list:
    """The in-process mapper: ``[fn(t) for t in tasks]``, reporting each finished task."""
    out = []
    total = len(tasks)
    for i, t in enumerate(tasks):
        out.append(fn(t))
        if progress is not None:
            progress(i + 1, total)
    return out


def run_seeds(seed: int, runs: int, spawn_key: tuple[int, ...] = ()
              ) -> list[np.random.SeedSequence]:
    """The per-run streams: ``SeedSequence(seed, spawn_key=spawn_key).spawn(runs)``."""
    return np.random.SeedSequence(int(seed), spawn_key=tuple(spawn_key)).spawn(int(runs))


def chunk_ranges(runs: int, chunk: int) -> list[range]:
    """``range(0, runs)`` cut into consecutive pieces of at most ``chunk`` runs."""
    if chunk < 1:
        raise ValueError(f"chunk must be ≥ 1, got {chunk}")
    return [range(a, min(a + chunk, runs)) for a in range(0, int(runs), int(chunk))]
