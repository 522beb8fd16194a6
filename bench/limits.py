"""Size limits stated up front: the memory (and disk) a request needs, estimated before any of
it is allocated, against what the machine has.

A request that cannot fit is refused with both numbers ("--count 100000000: this run needs
15 GiB; the machine has 22.6 GiB available, of which a run may use 11.3 GiB") instead of
ending in a ``MemoryError`` traceback or the kernel's OOM killer. A request that fits starts.

The estimates are *measured* peaks, not element counts: peak resident memory of the command
(``ru_maxrss``) at two sizes, the difference divided by the size difference, rounded up
(measured on Linux x86-64, numpy 2, MuJoCo 3; the constants below say what was run). The
fixed cost of the interpreter, numpy, scipy and MuJoCo (≈ 200 MiB) is :data:`BASE_BYTES`.

Only stdlib here (``os``): the commands call it before importing the domain.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

GIB = 2**30

MEMORY_SHARE = 0.5
"""Share of the available memory one request may plan to use: the estimates are peaks of one
process measured on one machine, and the machine runs other work (other processes, the page
cache of the files being written)."""

BASE_BYTES = 200 * 2**20
"""Interpreter, numpy, scipy and MuJoCo loaded: ≈ 192 MiB measured for a 1000-sample run."""

STATIC_SAMPLE_BYTES = 160
"""``generate calibration`` (static): 130 B per sample measured (10⁶ distinct poses: 316 MiB
against 192 MiB at 10³); held poses share their physics, 66 B per sample."""

SWEEP_STEP_BYTES = 200
"""``generate calibration --mode sweep``: per *physics step* (``duration / timestep``): the
rollout's state and sensor rows of every step; 81 MiB measured for 1000 s at 1 ms steps
(10⁶ steps: 85 B per step with the sample rows), rounded up for longer states."""

VEHICLE_SAMPLE_BYTES = 250
"""``generate vehicle`` / ``course``: 206 B per sample measured (10⁶ samples: 389 MiB)."""

SYNTHETIC_SAMPLE_BYTES = 250
"""``nmin`` synthetic calibration of N samples (draw, fit, residuals): 173 B per sample
measured (N = 10⁶: 271 MiB against 106 MiB at N = 10³)."""

DESIGN_SAMPLE_BYTES = 8192
"""``design``, per sample of the largest N in one process: the gap detection of a Monte Carlo
run (its effect candidates and their profiles); 6.1 kB per sample measured (N = 200001:
1.29 GiB against 0.22 GiB at N = 20001), rounded up."""

SEED_STREAM_BYTES = 400
"""One spawned ``numpy.random.SeedSequence`` (378 B measured with tracemalloc): Monte Carlo
loops spawn all their streams up front (``nmin --runs``, ``demo --coverage-runs``)."""

CLASS_STUDENT_BYTES = 4096
"""``generate class``: per student before the first set is written (derived seed, folder
name, the six target paths checked for ``--force``)."""

COURSE_SET_DISK_BYTES = 700_000
"""Disk of one course set at the default 20001 + 6000 samples (644 kB measured), per
student of ``generate class``."""


DESIGN_RUN_SECONDS = 0.05
"""``design`` Monte Carlo: CPU seconds of one run through the gap detection, per simulated
effect and experiment, at small N (45 ms measured at N = 201, one core)."""

DESIGN_RUN_SAMPLE_SECONDS = 5e-5
"""… plus this per sample of the experiment (0.12 s a run measured at N = 2001)."""

WORK_LIMIT_SECONDS = 7 * 86400
"""Longest computation one request may plan: a week of one core. Beyond it a request is a
runaway (``design --runs 1e12`` planned 1,500 years), refused with the estimate instead of
running until killed; a long but finishable study stays allowed."""


class SizeError(ValueError):
    """A request too large for this machine; the message gives the estimate and the limit.

    A ``ValueError``: the command line reports it as one line, exit code 2."""


def available_memory() -> int:
    """Memory a new allocation can get without swapping, bytes — the one home of this
    estimate (the size checks of every command use it): ``MemAvailable`` of
    ``/proc/meminfo`` (Linux), else the free physical pages (``SC_AVPHYS_PAGES``), else all
    physical pages, capped by a cgroup v2 ``memory.max`` (a container's limit); 8 GiB when
    the system says nothing (assume a small machine)."""
    avail = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    for pages in ("SC_AVPHYS_PAGES", "SC_PHYS_PAGES"):
        if avail is not None:
            break
        try:
            avail = int(os.sysconf(pages) * os.sysconf("SC_PAGE_SIZE"))
        except (OSError, ValueError, AttributeError):
            pass
    if avail is None:
        avail = 8 * GIB
    try:
        cap = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if cap.isdigit():
            avail = min(avail, int(cap))
    except OSError:
        pass
    return avail


def gib(n: float) -> str:
    """``n`` bytes as ``'74 GiB'`` (one decimal below 10 GiB; MiB below 1 GiB)."""
    if n < GIB:
        return f"{n / 2**20:.0f} MiB"
    return f"{n / GIB:.1f} GiB" if n < 10 * GIB else f"{n / GIB:,.0f} GiB"


def check_memory(need: float, what: str) -> float:
    """Refuse (:class:`SizeError`) a request whose estimated peak ``need`` (bytes, without
    :data:`BASE_BYTES`) exceeds :data:`MEMORY_SHARE` of the available memory; ``what`` names
    the options that set the size, e.g. ``"--count 100000000"``. Returns ``need``."""
    total = need + BASE_BYTES
    have = available_memory()
    if not total <= MEMORY_SHARE * have:  # `not <=`: an overflowed (inf/nan) estimate refuses
        raise SizeError(f"{what}: this run needs {gib(total)} of memory; the machine has "
                        f"{gib(have)} available, of which one run may use "
                        f"{gib(MEMORY_SHARE * have)} ({MEMORY_SHARE:.0%}); ask for less")
    return need


def check_time(seconds: float, what: str) -> float:
    """Refuse (:class:`SizeError`) a request whose estimated CPU time ``seconds`` (one core)
    exceeds :data:`WORK_LIMIT_SECONDS`; ``what`` names the options that set it."""
    if not seconds <= WORK_LIMIT_SECONDS:  # `not <=`: an overflowed estimate refuses
        raise SizeError(f"{what}: this run needs about {seconds / 3600:,.0f} CPU hours "
                        f"(estimated); one request may plan at most "
                        f"{WORK_LIMIT_SECONDS / 86400:.0f} days of one core; ask for less")
    return seconds


def free_disk(path: str | Path) -> int:
    """Free bytes on the file system that holds ``path`` (or its nearest existing parent)."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return shutil.disk_usage(p).free


def check_disk(need: float, out: str | Path, what: str) -> float:
    """Refuse (:class:`SizeError`) writing an estimated ``need`` bytes under ``out`` when the
    file system has less free space (an existing output being replaced is not counted)."""
    have = free_disk(out)
    if not need <= have:
        raise SizeError(f"{what}: this needs {gib(need)} of disk; {out} has {gib(have)} free; "
                        "ask for less or choose another --out")
    return need


def static_run_bytes(samples: float) -> float:
    """Peak of a static calibration run of ``samples`` samples, bytes."""
    return STATIC_SAMPLE_BYTES * samples


def sweep_run_bytes(duration: float, timestep: float) -> float:
    """Peak of a sweep of ``duration`` s simulated at ``timestep`` s, bytes."""
    return SWEEP_STEP_BYTES * (duration / timestep + 1)


def vehicle_run_bytes(samples: float) -> float:
    """Peak of a vehicle run of ``samples`` samples, bytes."""
    return VEHICLE_SAMPLE_BYTES * samples


def synthetic_runs_bytes(n: float, runs: float) -> float:
    """Peak of ``runs`` synthetic calibrations of ``n`` samples, one at a time, bytes."""
    return SYNTHETIC_SAMPLE_BYTES * n + SEED_STREAM_BYTES * runs
