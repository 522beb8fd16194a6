"""Scaling of the gap analysis in N, as ratios against the nominal calibration of the same run.

    python benchmarks/gap_scaling.py                  # or: make bench
    python benchmarks/gap_scaling.py --sizes 6001 20001 --repeat 1

For each run shape and size N, ``calib.gap.analyze_gap`` and the nominal least-squares
calibration it starts from (``calib.calibrate(ensayo, noise_var, "ols")``, the baseline) run
on the same data, each in a fresh process (``subprocess``, ``OPENBLAS_NUM_THREADS=1``):

* time: the best of ``--repeat`` calls (wall clock, ``time.perf_counter``);
* memory: the peak of ``tracemalloc`` over one call (numpy registers its buffers with it),
  in a separate fresh process so the timing runs without tracing; the growth of ``ru_maxrss``
  over the same call is shown beside it.

The table gives both, the ratio gap / nominal, and the growth factor of the gap analysis from
N = 20001 to 60001 (three times the samples: ≈ 3 when it is linear in N; the nominal fit is
the same measurement for an O(N) baseline). Nothing is asserted on absolute times.

Run shapes (generated here in numpy, 100 Hz, θ a full turn; stated σ² = 0.25, 0.64 m²/s⁴):

* ``clean``: the nominal model plus white noise (the analysis names nothing);
* ``effects``: the run of issue 10 ("fast enough for real runs"): x with scale 1.01, bias 0.05
  and a bias random walk (0.003 m/s² per sample), y with scale 0.99, bias -0.02 and a
  coupling 0.1·g·sin θ (a misalignment / tilt offset), both with extra white noise.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SIZES = (6001, 20001, 60001)
SHAPES = ("clean", "effects")
NOISE_VAR = (0.25, 0.64)


def make_run(shape: str, n: int):
    """(Ensayo, noise_var) of a run shape (module docstring), seeded by the shape."""
    import numpy as np

    from calib.files.course import Ensayo

    rng = np.random.default_rng(1 if shape == "effects" else 2)  # 1: the script
    g = 9.80665
    t = np.arange(n) / 100.0
    th = np.linspace(0.0, 2.0 * np.pi, n)
    ax, ay = -g * np.sin(th), -g * np.cos(th)
    if shape == "clean":
        datos = np.column_stack([ax + rng.normal(0, 0.5, n), ay + rng.normal(0, 0.8, n)])
    else:
        dx = 1.01 * ax + 0.05 + rng.normal(0, 0.5, n) + np.cumsum(rng.normal(0, 0.003, n))
        dy = 0.99 * ay - 0.02 + rng.normal(0, 0.8, n) + 0.1 * g * np.sin(th)
        datos = np.column_stack([dx, dy])
    return Ensayo(tita=th, datos=datos, t=t), NOISE_VAR


def measure(shape: str, n: int, what: str, mode: str, repeat: int) -> dict:
    """One cell, in this (fresh) process: ``what`` ∈ {gap, nominal}, ``mode`` ∈ {time, mem}."""
    import resource
    import time
    import tracemalloc

    from calib import calibrate
    from calib.gap import analyze_gap

    ensayo, noise_var = make_run(shape, n)
    if what == "gap":
        def call():
            return analyze_gap(ensayo, noise_var)
    else:
        def call():
            return calibrate(ensayo, noise_var, "ols")
    if mode == "time":
        best = float("inf")
        for _ in range(repeat):
            t0 = time.perf_counter()
            call()
            best = min(best, time.perf_counter() - t0)
        return {"time_s": best}
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    tracemalloc.start()
    call()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"peak_mb": peak / 1e6, "maxrss_growth_mb": (rss1 - rss0) / 1e3}  # ru_maxrss: kB


def run_cell(shape: str, n: int, what: str, mode: str, repeat: int) -> dict:
    """:func:`measure` in a fresh interpreter (its caches, arenas and peak RSS its own)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join(filter(None, (str(REPO),
                                                        os.environ.get("PYTHONPATH")))))
    out = subprocess.run([sys.executable, __file__, "--cell", shape, str(n), what, mode,
                          str(repeat)], env=env, cwd=REPO, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    p.add_argument("--sizes", type=int, nargs="+", default=list(SIZES),
                   help="run lengths N (the growth is reported for 20001 → 60001 if both)")
    p.add_argument("--shapes", nargs="+", choices=SHAPES, default=list(SHAPES))
    p.add_argument("--repeat", type=int, default=3, help="timed calls per cell (best)")
    p.add_argument("--cell", nargs=5, metavar=("SHAPE", "N", "WHAT", "MODE", "REPEAT"),
                   help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.cell:
        shape, n, what, mode, repeat = args.cell
        print(json.dumps(measure(shape, int(n), what, mode, int(repeat))))
        return 0

    rows: dict[tuple[str, int], dict] = {}
    for shape in args.shapes:
        for n in args.sizes:
            cell = {}
            for what in ("nominal", "gap"):
                cell[what] = {**run_cell(shape, n, what, "time", args.repeat),
                              **run_cell(shape, n, what, "mem", 1)}
            rows[(shape, n)] = cell
    print("analyze_gap against the nominal calibration (calib.calibrate, OLS) of the same run;")
    print(f"best of {args.repeat} calls, tracemalloc peak of one call, each in a fresh process")
    print(f"{'shape':<9}{'N':>7}{'nominal ms':>12}{'gap ms':>10}{'× nominal':>11}"
          f"{'nominal MB':>12}{'gap MB':>9}{'× nominal':>11}{'gap ΔRSS MB':>13}")
    for (shape, n), c in rows.items():
        nom, gap = c["nominal"], c["gap"]
        print(f"{shape:<9}{n:>7}{1e3 * nom['time_s']:>12.1f}{1e3 * gap['time_s']:>10.0f}"
              f"{gap['time_s'] / nom['time_s']:>10.0f}×{nom['peak_mb']:>12.1f}"
              f"{gap['peak_mb']:>9.1f}{gap['peak_mb'] / nom['peak_mb']:>10.1f}×"
              f"{gap['maxrss_growth_mb']:>13.0f}")
    if 20001 in args.sizes and 60001 in args.sizes:
        print("growth from N = 20001 to 60001 (linear in N ≈ 3):")
        for shape in args.shapes:
            a, b = rows[(shape, 20001)], rows[(shape, 60001)]
            parts = [f"{w} time ×{b[w]['time_s'] / a[w]['time_s']:.2f}, "
                     f"memory ×{b[w]['peak_mb'] / a[w]['peak_mb']:.2f}"
                     for w in ("gap", "nominal")]
            print(f"  {shape:<9}" + "; ".join(parts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
