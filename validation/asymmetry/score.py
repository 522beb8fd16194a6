"""K2 or a scale asymmetry, through the whole analysis: the study behind the asymmetry tier of
:mod:`calib.gap.asymmetry`.

    python -m validation.asymmetry.score             # 200 K2, 100 asymmetries, 100 K3 runs
    python -m validation.asymmetry.score --k2 40 --asymmetry 20 --k3 0 --seed 7 --jobs 1
    python -m validation.asymmetry.score --k2 0 --asymmetry 0 --k3 0 --lever 200 --speed 100 \
        --seed 2036                                  # the lever arm or a drive-state bias

Each run is made with numpy alone (:mod:`validation.asymmetry.runs`): a true K2 (half of the
runs sized z = 3–15, faint ones near detection; half z = 10–60), a true scale asymmetry or a
true third-order term K3 (z = 10–60), on one axis of a stop-and-go, constant-rate or
back-and-forth run; with ``--lever`` / ``--speed``, a true lever arm (half faint) or a bias
that grows with |ω| (z = 10–60) on a stop-and-go or back-and-forth run.
:func:`calib.gap.analyze_gap` is run on each (σ² stated as made), and the table gives per
kind: the runs, the verdicts, how often K2 (the lever arm for the drive kinds) is named on
the effect's axis, and the decisions of the asymmetry against K2 there
(:mod:`calib.gap.asymmetry`), of K3 against the named set (:mod:`calib.gap.cubic`) and of a
drive-state bias against the lever arm (:mod:`calib.gap.drive_bias`) — ``"ties"`` (since
stop 47) and ``"describes"``: the catalog's effects named, the pair listed; ``"leans"``: beyond
:data:`calib.gap.walk.LEAN_MARGIN`, not named — with the largest gain of each. A catalog
effect named on a true asymmetry, K3 or speed bias with the verdict "explained" is the answer
the tiers exist to avoid; a "leans" on a true K2 or lever arm is their cost.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from validation.asymmetry.runs import make_run

Z_RANGES = {"k2": ((3.0, 15.0), (10.0, 60.0)), "asymmetry": ((10.0, 60.0), (10.0, 60.0)),
            "k3": ((10.0, 60.0), (10.0, 60.0)), "lever": ((3.0, 15.0), (10.0, 60.0)),
            "speed": ((10.0, 60.0), (10.0, 60.0))}
NAMED = {"k2": "nonlinearity_k2", "asymmetry": "nonlinearity_k2", "k3": "nonlinearity_k2",
         "lever": "lever_arm", "speed": "lever_arm"}
"""The catalog effect each kind is read against: K2, or the lever arm for the drive kinds."""
"""z ranges of the even and the odd runs of each kind."""


def analysed(job: tuple[int, str]) -> dict:
    """The whole analysis of one run (seed, kind): verdict, K2 named on the effect's axis,
    and the asymmetry's decision and gain against K2 there."""
    from calib.files.course import Ensayo
    from calib.gap import analyze_gap

    seed, kind = job
    run = make_run(np.random.default_rng(seed), kind, Z_RANGES[kind][seed % 2])
    axis = run["info"]["axis"]
    try:
        res = analyze_gap(Ensayo(run["tita"], run["datos"], run["t"]), run["noise_var"])
    except ValueError as exc:  # the front door refuses the run (said, counted apart)
        return {**run["info"], "verdict": "refused", "k2_named": False, "decision": None,
                "gain": None, "k3_decision": None, "k3_gain": None, "drive_decision": None,
                "drive_gain": None, "error": str(exc)[:120]}
    out = {**run["info"], "verdict": res.verdict, "k2_named": (NAMED[kind], axis) in res.named}
    for key, entry in (("", "asymmetry"), ("k3_", "cubic"), ("drive_", "drive_bias")):
        found = [f for f in res.adequacy.get(entry, []) if f["axis"] == axis]
        out[key + "decision"] = found[0]["decision"] if found else None
        out[key + "gain"] = float(found[0]["gain"]) if found else None
    return out


def _largest(rows: list[dict], key: str, decision: str) -> float:
    """The largest gain among ``rows`` whose ``key + "decision"`` is ``decision`` (0 if none)."""
    return max((r[key + "gain"] for r in rows if r[key + "decision"] == decision), default=0.0)


def table(rows: list[dict], seed: int) -> str:
    """The study's table (module docstring)."""
    out = [f"whole analysis (seed {seed}): runs | verdict explained / unexplained / nothing / "
           "refused | K2 (lever arm for lever, speed) named on the effect's axis (of them with "
           "the verdict explained) | asymmetry against K2: ties / describes / leans, largest "
           "gain of the last two | K3 against the named set: the same | a drive-state bias "
           "against the lever arm: the same"]
    for kind in ("k2", "asymmetry", "k3", "lever", "speed"):
        rs = [r for r in rows if r["kind"] == kind]
        if not rs:
            continue
        verdicts = " / ".join(str(sum(r["verdict"] == v for r in rs)) for v in
                              ("explained", "unexplained", "nothing_detected", "refused"))
        named = sum(r["k2_named"] for r in rs)
        named_explained = sum(r["k2_named"] and r["verdict"] == "explained" for r in rs)
        cells = []
        for key in ("", "k3_", "drive_"):
            tiers = " / ".join(str(sum(r[key + "decision"] == d for r in rs))
                               for d in ("ties", "describes", "leans"))
            top = ", ".join(f"{d} {_largest(rs, key, d):.1f}" for d in ("describes", "leans"))
            cells.append(f"{tiers}, {top}")
        out.append(f"{kind:<10s} {len(rs):>4d} | {verdicts} | {named} ({named_explained}) | "
                   f"{' | '.join(cells)}")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--k2", type=int, default=200, help="runs with a true K2")
    p.add_argument("--asymmetry", type=int, default=100, help="runs with a true asymmetry")
    p.add_argument("--k3", type=int, default=100,
                   help="runs with a true third-order term (not in the catalog)")
    p.add_argument("--lever", type=int, default=0,
                   help="runs with a true lever arm (half faint: z = 3–15)")
    p.add_argument("--speed", type=int, default=0,
                   help="runs with a true bias that grows with |ω| (not in the catalog)")
    p.add_argument("--seed", type=int, default=2034)
    p.add_argument("--jobs", type=int, default=2, help="processes")
    a = p.parse_args(argv)
    from multiprocessing import get_context

    work = [(a.seed + i, "k2") for i in range(a.k2)]
    work += [(a.seed + a.k2 + i, "asymmetry") for i in range(a.asymmetry)]
    work += [(a.seed + a.k2 + a.asymmetry + i, "k3") for i in range(a.k3)]
    first = a.seed + a.k2 + a.asymmetry + a.k3
    work += [(first + i, "lever") for i in range(a.lever)]
    work += [(first + a.lever + i, "speed") for i in range(a.speed)]
    rows = []
    with get_context("spawn").Pool(max(1, a.jobs)) as pool:
        for i, r in enumerate(pool.imap(analysed, work, chunksize=4)):
            rows.append(r)
            print(f"\rrun {i + 1}/{len(work)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    print(table(rows, a.seed))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
