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

    python -m validation.switching.score --analysis            # 400 walks, 160 telegraphs
    python -m validation.switching.score --analysis --walks 0 --telegraphs 0 --staircases 150

``--analysis`` runs the whole analysis (:func:`calib.gap.analyze_gap`) on calibration runs
built around such paths (:func:`validation.switching.paths.make_run`: the path on x, a
constant-rate or stop-and-go table, N ≤ 6001; longer paths are skipped) and counts, for
walks and telegraphs, the verdicts, whether the walk on x is named, and the decision of the
steps or switching against it (``--staircases K`` adds K staircases of 2–6 steps of one
sign and size, 0.25–0.6 σ; ``"describes"``: the pair listed, the walk named; ``"leans"``:
beyond :data:`calib.gap.walk.LEAN_MARGIN`, the walk not named; ``"steps"``: beyond the
margin) with the largest gain of each kind, and on the stop-and-go runs how often a bias tied
to the drive ties with, describes or leans against the walk on x
(:func:`calib.gap.drive_bias.walk_or_drive_bias`; ``"leans"``: the walk not named). Two
processes by default (``--jobs``).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from calib.gap.switching import SWITCH_CHARGE, block_size, fit_switching
from calib.gap.walk import SWITCH_MARGIN, path_walk_lr
from validation.switching.paths import make_path, make_run

LEVELS = (0.0, 6.0, SWITCH_MARGIN, 20.0, 30.0)


def gain(e: np.ndarray, sigma2: float, dt: float) -> float:
    """D of the module docstring."""
    fit = fit_switching(e, sigma2)
    walk = path_walk_lr(e, sigma2, np.full(e.size - 1, dt), block_size(e.size))
    return (fit.lr - 2.0 * SWITCH_CHARGE) - (walk - 2.0)


def _row(name: str, d: np.ndarray) -> str:
    cells = " ".join(f"{int(np.sum(d > v)):>5d}" for v in LEVELS)
    return f"{name:<28s} {d.size:>5d} {cells}   largest {np.max(d):+.1f}"


def analysed(job: tuple[int, str, bool]) -> dict | None:
    """The whole analysis of one run of :func:`make_run` (seed, kind, faint): verdict, walk
    on x named, and the decision and gain of the steps or switching against that walk."""
    from calib.files.course import Ensayo
    from calib.gap import analyze_gap

    seed, kind, faint = job
    run = make_run(np.random.default_rng(seed), kind, faint)
    if run is None:
        return None
    res = analyze_gap(Ensayo(run["tita"], run["datos"], run["t"]), run["noise_var"])
    walk = [w for w in res.adequacy.get("walk", []) if w["axis"] == "x"]
    steps = walk[0]["steps"] if walk else None
    drive = [f["decision"] for f in res.adequacy.get("drive_bias", [])
             if f["names"] == ["bias_random_walk"] and f["axis"] == "x"]
    return {"kind": kind, "verdict": res.verdict,
            "walk_named": ("bias_random_walk", "x") in res.named,
            "decision": None if steps is None else steps["decision"],
            "gain": None if steps is None else float(steps["gain"]),
            "drive_bias": drive[0] if drive else None, **run["info"]}


def analysis_study(walks: int, telegraphs: int, seed: int, jobs: int, staircases: int = 0
                   ) -> int:
    """``--analysis`` of the module docstring: the table on stdout."""
    from multiprocessing import get_context

    work = [(seed + i, "walk", i % 2 == 0) for i in range(walks)]
    work += [(seed + walks + i, "telegraph", True) for i in range(telegraphs)]
    work += [(seed + walks + telegraphs + i, "staircase", True) for i in range(staircases)]
    rows = []
    with get_context("spawn").Pool(max(1, jobs)) as pool:
        for i, r in enumerate(pool.imap(analysed, work, chunksize=4)):
            if r is not None:
                rows.append(r)
            print(f"\rrun {i + 1}/{len(work)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    print(f"whole analysis (seed {seed}, N ≤ 6001): runs | verdict explained / unexplained / "
          "nothing | walk on x named | steps or switching against it: describes (pair, walk "
          "named) / leans (walk not named) / steps (replaced) | largest gain of each | a bias "
          "tied to the drive against the walk (calib.gap.drive_bias.walk_or_drive_bias): ties / "
          "describes / leans, stop-and-go runs")
    for kind in ("walk", "telegraph", "staircase"):
        rs = [r for r in rows if r["kind"] == kind]
        if not rs:
            continue
        verdicts = "/".join(str(sum(r["verdict"] == v for r in rs))
                            for v in ("explained", "unexplained", "nothing_detected"))
        tiers = "/".join(str(sum(r["decision"] == d for r in rs))
                         for d in ("describes", "leans", "steps"))
        top = ", ".join(f"{d} {max((r['gain'] for r in rs if r['decision'] == d), default=0):.1f}"
                        for d in ("describes", "leans", "steps"))
        drive = "/".join(str(sum(r["drive_bias"] == d for r in rs))
                         for d in ("ties", "describes", "leans"))
        stop_go = sum(r["design"] == "stop_and_go" for r in rs)
        print(f"{kind + 's':<11s} {len(rs):>5d} | {verdicts:>11s} | "
              f"{sum(r['walk_named'] for r in rs):>5d} | {tiers:>9s} | {top} | {drive} "
              f"of {stop_go}")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--walks", type=int, default=400)
    p.add_argument("--telegraphs", type=int, default=None,
                   help="telegraphs (default 150 paths, 160 runs with --analysis)")
    p.add_argument("--seed", type=int, default=2033)
    p.add_argument("--analysis", action="store_true",
                   help="run the whole analysis on runs built around the paths")
    p.add_argument("--staircases", type=int, default=0,
                   help="--analysis: also this many staircases (2–6 steps of 0.25–0.6 σ)")
    p.add_argument("--jobs", type=int, default=2, help="processes of --analysis")
    a = p.parse_args(argv)
    if a.analysis:
        return analysis_study(a.walks, 160 if a.telegraphs is None else a.telegraphs,
                              a.seed, a.jobs, a.staircases)
    a.telegraphs = 150 if a.telegraphs is None else a.telegraphs
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
