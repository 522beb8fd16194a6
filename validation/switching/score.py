"""Two-level switching against a random walk on paths made here: the study behind
:data:`calib.gap.walk.SWITCH_MARGIN`.

    python -m validation.switching.score                    # 400 walks, 150 telegraphs
    python -m validation.switching.score --walks 100 --telegraphs 50 --seed 7

Each path is made with numpy alone (:mod:`validation.switching.paths`, not the detector's
code): white noise of std σ (0.05–1 m/s²), N of 2001, 4001, 6001 or 12001 samples at 50, 100
or 200 Hz, plus

* a **random walk** of q√T = 0.3–1.2 σ (half the walks: the faint ones a telegraph is
  confused with) or 0.3–4 σ (the other half);
* a **telegraph**: levels h = 0.2–0.6 σ apart, 4–30 switches at uniform random times.

On each path the two-level Markov fit (:func:`calib.gap.switching.fit_switching`) and the walk
(:func:`calib.gap.walk.path_walk_lr`) give the AIC gain ``D = (LR_s − 6) − (LR_w − 2)``; the
table gives how often D passes 0, 6, 12 (the margin), 20 and 30, the telegraphs also by h.
A walk above the margin would be a walk the review stops naming (with the walk-beyond check
of :func:`calib.gap.walk.switching_drift` as a second guard, not counted here).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from calib.gap.switching import SWITCH_CHARGE, block_size, fit_switching
from calib.gap.walk import SWITCH_MARGIN, path_walk_lr
from validation.switching.paths import make_path

LEVELS = (0.0, 6.0, SWITCH_MARGIN, 20.0, 30.0)


def gain(e: np.ndarray, sigma2: float, dt: float) -> float:
    """D of the module docstring."""
    fit = fit_switching(e, sigma2)
    walk = path_walk_lr(e, sigma2, np.full(e.size - 1, dt), block_size(e.size))
    return (fit.lr - 2.0 * SWITCH_CHARGE) - (walk - 2.0)


def _row(name: str, d: np.ndarray) -> str:
    cells = " ".join(f"{int(np.sum(d > v)):>5d}" for v in LEVELS)
    return f"{name:<28s} {d.size:>5d} {cells}   largest {np.max(d):+.1f}"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--walks", type=int, default=400)
    p.add_argument("--telegraphs", type=int, default=150)
    p.add_argument("--seed", type=int, default=2033)
    a = p.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    walks, tele, sizes = [], [], []
    for i in range(a.walks):
        e, s2, dt, _ = make_path(rng, "walk", faint=i % 2 == 0)
        walks.append(gain(e, s2, dt))
        print(f"\rwalk {i + 1}/{a.walks}", end="", file=sys.stderr, flush=True)
    for i in range(a.telegraphs):
        e, s2, dt, info = make_path(rng, "telegraph", faint=True)
        tele.append(gain(e, s2, dt))
        sizes.append(info["h_over_sigma"])
        print(f"\rtelegraph {i + 1}/{a.telegraphs}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    tele_d, sizes = np.array(tele), np.array(sizes)
    head = " ".join(f"{'>' + format(v, 'g'):>5s}" for v in LEVELS)
    print(f"{'paths (seed ' + str(a.seed) + ')':<28s} {'runs':>5s} {head}   (AIC gain D)")
    print(_row("random walks", np.array(walks)))
    print(_row("telegraphs", tele_d))
    for lo, hi in ((0.2, 0.35), (0.35, 0.5), (0.5, 0.6)):
        sel = (sizes >= lo) & (sizes < hi)
        if sel.any():
            print(_row(f"  levels {lo:g}–{hi:g} σ apart", tele_d[sel]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
