"""Start-up time of the command line, as ratios against ``python -c "import numpy"``.

    python benchmarks/cli_startup.py [--runs 7] [--course-data DIR]     # or: make bench

Each command runs in a fresh process (``subprocess``), ``--runs`` times; the median wall time
is reported next to the baseline measured in the same run, on the same machine:

* ``tiltbench --help``: must import no domain module (no numpy, scipy, mujoco, matplotlib,
  rerun); the exit code is 1 if it costs 3× the numpy import or more;
* ``tiltbench calibrate ensayo.mat --datos datos.txt --json`` on the course files: the
  smallest real job (numpy, scipy.io, the fit), for information.

The command line runs as ``python -m bench.cli`` with this checkout first on ``PYTHONPATH``
(the ``tiltbench`` console script does the same import).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
COURSE_DATA = REPO.parent / "shared" / "course-data"
HELP_LIMIT = 3.0
"""``tiltbench --help`` must cost less than this many numpy imports."""


def median_time(argv: list[str], runs: int, env: dict[str, str]) -> float:
    """Median wall time of ``argv`` in a fresh process, s (output discarded; must exit 0)."""
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(argv, env=env, cwd=REPO, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    p.add_argument("--runs", type=int, default=7, help="runs per command (median; >= 5)")
    p.add_argument("--course-data", type=Path, default=COURSE_DATA,
                   help="folder with the course ensayo.mat and datos.txt")
    args = p.parse_args(argv)
    runs = max(5, args.runs)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join(filter(None, (str(REPO),
                                                        os.environ.get("PYTHONPATH")))))
    cli = [sys.executable, "-m", "bench.cli"]
    ensayo, datos = args.course_data / "ensayo.mat", args.course_data / "datos.txt"
    base = median_time([sys.executable, "-c", "import numpy"], runs, env)
    rows = [("tiltbench --help", median_time([*cli, "--help"], runs, env))]
    if ensayo.exists() and datos.exists():
        rows.append(("tiltbench calibrate ensayo.mat --datos datos.txt --json",
                     median_time([*cli, "calibrate", str(ensayo), "--datos", str(datos),
                                  "--json"], runs, env)))
    else:
        print(f"(no course files in {args.course_data}: calibrate not timed)")
    print(f"median of {runs} runs; baseline python -c 'import numpy': {1e3 * base:.0f} ms")
    print(f"{'command':<58}{'ms':>8}{'× numpy':>10}")
    for label, t in rows:
        print(f"{label:<58}{1e3 * t:>8.0f}{t / base:>9.2f}×")
    ratio = rows[0][1] / base
    if ratio >= HELP_LIMIT:
        print(f"FAIL: tiltbench --help costs {ratio:.2f}× the numpy import "
              f"(limit {HELP_LIMIT:g}×)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
