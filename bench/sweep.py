"""Where the runs of a long sweep execute: this process, a local process pool, or a Dask cluster.

Each returns a mapper with the signature of :class:`calib.stats.runs.Mapper`
(``mapper(fn, tasks, progress=None) -> [fn(t) for t in tasks]``, in task order), so the domain
functions that take a ``mapper`` run unchanged on any of them. Results do not depend on where
they ran: every run draws from its own ``SeedSequence`` stream (:mod:`calib.stats.runs`).

* ``workers=1`` — in this process (:func:`calib.stats.runs.serial_map`).
* ``workers=k > 1`` — a local ``concurrent.futures.ProcessPoolExecutor`` with k processes
  (the default for long sweeps: ``os.cpu_count()``), started by a fork server; BLAS is kept at
  one thread per process so the processes do not fight over the cores.
* ``scheduler="tcp://host:port"`` — a running ``dask.distributed`` scheduler (``pip install
  "tiltbench[cluster]"``); tasks are submitted with ``Client.map`` and gathered in order.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

from calib.stats.runs import Mapper, serial_map

CONNECT_TIMEOUT = "10s"
"""How long a sweep waits for the dask scheduler before it gives up with an OSError."""


def default_workers() -> int:
    """The local pool's size when none is given: the machine's cores."""
    return max(1, os.cpu_count() or 1)


POOL_PRELOAD = ("numpy", "scipy.linalg", "calib.calibration.montecarlo", "bench.classset")
"""Modules the fork server imports once, so the pool's processes start with them loaded."""


def _context():
    """The ``forkserver`` start method: workers are forked from a small server process started
    once (with :data:`POOL_PRELOAD` imported), not from this process, which may run threads
    (a Dask client, rerun's writers) that a plain ``fork`` would copy mid-operation. Costs
    ≈ 0.7 s on the first pool of a process, ≈ 0.03 s on later ones (measured here)."""
    import multiprocessing

    # One BLAS thread per worker. The variables are read when numpy loads, which happens in
    # the fork server (preload) before any worker exists, so they must be in the environment
    # the server starts with: this process's (its own BLAS is already loaded, unaffected).
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(POOL_PRELOAD))
    return ctx


def process_map(workers: int) -> Mapper:
    """A mapper over a local pool of ``workers`` processes (results in task order)."""
    def run(fn: Callable[[Any], Any], tasks: Sequence[Any],
            progress: Callable[[int, int], None] | None = None) -> list:
        from concurrent.futures import ProcessPoolExecutor, as_completed

        tasks = list(tasks)
        if workers <= 1 or len(tasks) <= 1:
            return serial_map(fn, tasks, progress)
        out: list[Any] = [None] * len(tasks)
        with ProcessPoolExecutor(max_workers=min(workers, len(tasks)),
                                 mp_context=_context()) as pool:
            futures = {pool.submit(fn, t): i for i, t in enumerate(tasks)}
            for done, fut in enumerate(as_completed(futures), start=1):
                out[futures[fut]] = fut.result()
                if progress is not None:
                    progress(done, len(tasks))
        return out

    return run


def dask_map(scheduler: str) -> Mapper:
    """A mapper over the ``dask.distributed`` cluster whose scheduler listens at ``scheduler``."""
    try:
        from dask.distributed import Client, as_completed
    except ImportError as exc:  # the optional extra is missing
        raise ModuleNotFoundError('--scheduler needs dask.distributed: pip install '
                                  '"tiltbench[cluster]"') from exc

    def run(fn: Callable[[Any], Any], tasks: Sequence[Any],
            progress: Callable[[int, int], None] | None = None) -> list:
        tasks = list(tasks)
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except OSError as exc:  # nothing listening, wrong host, a firewall
            raise OSError(f"cannot reach the dask scheduler at {scheduler} within "
                          f"{CONNECT_TIMEOUT} ({exc}); start it with `dask scheduler` and "
                          "check the address") from None
        with client:
            futures = client.map(fn, tasks, pure=False)
            index = {f.key: i for i, f in enumerate(futures)}
            out: list[Any] = [None] * len(tasks)
            for done, fut in enumerate(as_completed(futures), start=1):
                out[index[fut.key]] = fut.result()
                if progress is not None:
                    progress(done, len(tasks))
        return out

    return run


def make_mapper(workers: int | None = None, scheduler: str | None = None) -> Mapper:
    """The mapper for ``--workers`` / ``--scheduler`` (module docstring)."""
    if scheduler:
        return dask_map(scheduler)
    w = default_workers() if workers is None else int(workers)
    return serial_map if w <= 1 else process_map(w)
