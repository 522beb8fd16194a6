"""The process pool of the Monte Carlo tests: workers forked from one fork server per pytest
worker, with the analysis already imported.

Why not ``spawn``: a spawned worker starts a fresh interpreter and imports numpy, scipy, the
analysis and the test module before its first run (≈ 2 s of CPU each, 2026-11-30); the suite
started ≈ 27 of them. A fork server imports :data:`PRELOAD` once (the first pool of a pytest
worker, ≈ 2.5 s) and forks every later worker from that clean, single-threaded process in
≈ 0.05 s (a plain ``fork`` of the pytest worker would copy its threads mid-operation). The
runs do not change: each draws from its own seeded generator and sees one BLAS thread, as
before.

:func:`bench.sweep.process_map` uses the same ``forkserver`` context; whichever pool comes
first in a pytest worker starts the server with its preload list, and a worker imports any
module the server lacks on first use.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor

PRELOAD = ("numpy", "scipy.stats", "scipy.optimize", "pytest", "calib.gap", "bench.gap.run",
           "validation.score", "tests.gap_synthetic")
"""What the Monte Carlo tests' runs import (the analysis, the bench's gap run, the validation
set's scorer, the synthetic runs)."""


def process_pool(workers: int = 2) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes (at most the machine's cores), one BLAS thread each."""
    # The fork server reads the environment once, when it starts (numpy loads there).
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(PRELOAD))
    return ProcessPoolExecutor(max(1, min(workers, os.cpu_count() or 1)), mp_context=ctx)
