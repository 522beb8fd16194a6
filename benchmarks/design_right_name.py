"""design's right-name probability against an independent full-analysis Monte Carlo.

    python benchmarks/design_right_name.py            # R = 300 runs each (≈ 5 min on 2 cores)
    python benchmarks/design_right_name.py --runs 100

For two effects near their 80 % first-step size on the course design (uniform static full
turn, N = 801, stated σ² = 0.25, 0.64 (m/s²)², sensor gain 1 + scale = 0.97):

* ``design``: ``calib.design.analyze_design(..., runs=R, gain=0.97)`` → ``right_name`` (its
  own Monte Carlo of ``calib.gap.analyze_gap`` on ``calib.design.signals.readings``) and the
  first-step analytic power beside it;
* ``independent``: R runs made by the validation generator's sensor chain
  (``validation.effects.readings``, code that shares nothing with ``calib.design.signals``),
  analysed by ``analyze_gap`` and judged by the same rule
  (``calib.design.montecarlo.right_name``).

Agreement: ``|p̂₁ − p̂₂| ≤ 4·sqrt(p(1 − p)(1/R₁ + 1/R₂))`` (p pooled), the binomial band of a
difference. ``tests/test_design.py`` asserts the same on a smaller run (slow).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

SIZES = {"misalignment": 0.012, "nonlinearity_k2": 0.0024}
GAIN = 0.97


def independent(task) -> bool:
    from calib.design import Experiment
    from calib.design.montecarlo import right_name
    from calib.files.course import Ensayo
    from calib.gap import analyze_gap
    from validation.effects import AxisSpec, Draws, Run, Spec, readings

    name, size, seed, i = task
    th = Experiment("uniform", 801, 0.314).theta()
    run = Run.build("uniform", th, None)
    field = {"misalignment": "delta", "nonlinearity_k2": "k2"}[name]
    spec = Spec(x=AxisSpec(scale=GAIN - 1.0, **{field: size}), y=AxisSpec())
    y = readings(run, spec, Draws.draw(np.random.default_rng([seed, i]), run.n), (0.25, 0.64))
    a = analyze_gap(Ensayo(th, y, None, source="mc"), (0.25, 0.64))
    return right_name(a.named, [d["names"] for d in a.not_identifiable], a.verdict, name, "x")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=300)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    from bench.sweep import make_mapper
    from calib.design import Experiment, analyze_design

    mapper = make_mapper(args.workers, None)
    t0 = time.perf_counter()
    res = analyze_design([Experiment("uniform", 801, 0.314)], list(SIZES), SIZES,
                         runs=args.runs, seed=3, mapper=mapper, gain=GAIN)
    ok = True
    for name, size in SIZES.items():
        row = res.effects[name]["per_experiment"][0]
        p1 = row["right_name"]
        hits = mapper(independent, [(name, size, 7, i) for i in range(args.runs)], None)
        p2 = sum(hits) / args.runs
        p = (p1 + p2) / 2
        band = 4.0 * np.sqrt(max(p * (1 - p), 1.0 / args.runs) * 2.0 / args.runs)
        ok &= abs(p1 - p2) <= band
        print(f"{name} {size:g}: first-step power {row['power']:.3f}; right name: design "
              f"{p1:.3f} {row['right_name_ci95']}, independent {p2:.3f} (R = {args.runs} each);"
              f" |Δ| = {abs(p1 - p2):.3f} ≤ band {band:.3f}: {abs(p1 - p2) <= band}")
    print(f"total {time.perf_counter() - t0:.0f} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
