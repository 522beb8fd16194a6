"""``tiltbench trajectory`` and ``tiltbench nmin``: parse, call ``calib``, print.

``trajectory`` calibrates on the ensayo, corrects and integrates the vehicle run, and decides
the arrival point with its confidence region (:mod:`calib.region`). ``nmin`` analyses how many
calibration samples are needed (:mod:`calib.nmin`). Without ``--datos`` the noise variances are
estimated from the calibration residuals and P0, V0 are the course's (0, 0), (1, 3); a note
says so on stderr. ``--json`` prints exactly one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

from bench.record import trajectory_tree
from calib.calibration import calibrate
from calib.io import (
    DataError,
    check_positive,
    dumps,
    parse_pair,
    read_acel,
    read_datos,
    read_ensayo,
    read_puntos,
    refuse_overwrite,
)
from calib.nmin import COURSE_STEPS, analyze_nmin
from calib.region import arrival_region
from calib.trajectory import COURSE_P0, COURSE_V0, INTEGRATORS, compute_trajectory


def _check_level(level: float) -> float:
    if not 0.0 < level < 1.0:
        raise DataError(f"--level must be in (0, 1), e.g. 0.997, got {level}")
    return level


def _inputs(args: argparse.Namespace):
    """Read files; return ensayo, acel, candidates, p0, v0, noise_var (None = estimate)."""
    check_positive(args.g, "--g")
    ensayo = read_ensayo(args.ensayo)
    acel = read_acel(args.acel)
    candidates = read_puntos(args.puntos)
    p0, v0, nv = np.array(COURSE_P0), np.array(COURSE_V0), None
    if args.datos:
        d = read_datos(args.datos)
        p0, v0, nv = d.p0, d.v0, d.noise_var
    if args.p0:
        p0 = parse_pair(args.p0, "--p0")
    if args.v0:
        v0 = parse_pair(args.v0, "--v0")
    if not args.datos:
        p0_src, v0_src = ("given" if opt else "course value" for opt in (args.p0, args.v0))
        print("note: no --datos: noise variances estimated from the calibration residuals; "
              f"P0 = {p0.tolist()} m ({p0_src}), V0 = {v0.tolist()} m/s ({v0_src})",
              file=sys.stderr)
    return ensayo, acel, candidates, p0, v0, nv


def _add_inputs(p: argparse.ArgumentParser) -> None:
    p.add_argument("--ensayo", required=True, help="calibration run ensayo.mat (tita, datos)")
    p.add_argument("--acel", required=True, help="vehicle run acel.mat (t, Aerr)")
    p.add_argument("--puntos", required=True, help="candidate points puntos.mat (A, B, …)")
    p.add_argument("--datos", help="course datos.txt (P0, V0, noise variances)")
    p.add_argument("--p0", help="initial position x,y in m (overrides datos.txt)")
    p.add_argument("--v0", help="initial velocity x,y in m/s (overrides datos.txt)")
    p.add_argument("--level", type=float, default=0.997,
                   help="confidence level of the region (χ², 2 dof)")
    p.add_argument("--method", choices=["ols", "wls"], default="ols",
                   help="calibration: per-axis OLS (course) or joint WLS")
    p.add_argument("--integrator", choices=list(INTEGRATORS), default="trapezoid",
                   help="double integration rule")
    p.add_argument("--g", type=float, default=9.8, help="gravity, m/s²")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def _calibrate(ensayo, nv, method, g):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = calibrate(ensayo, nv, method, g)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    return cal


def _cmd_trajectory(args: argparse.Namespace) -> int:
    level = _check_level(args.level)
    refuse_overwrite([args.plot, args.rrd], args.force)
    ensayo, acel, candidates, p0, v0, nv = _inputs(args)
    cal = _calibrate(ensayo, nv, args.method, args.g)
    traj = compute_trajectory(acel, cal, p0, v0, args.integrator)
    region = arrival_region(traj, cal, candidates, nv, level)
    if args.plot:
        from bench.figures_trajectory import save_trajectory_plot

        save_trajectory_plot(args.plot, traj, region, force=args.force)
    out = trajectory_tree(traj, region, cal, args.method,
                          "given" if nv is not None else "estimated")
    if args.rrd:
        from bench.record import record_trajectory

        record_trajectory(traj, region, cal, args.rrd, force=args.force, tree=out)
    if args.json:
        print(dumps(out), end="")
        return 0
    print(traj.summary())
    print(region.summary())
    return 0


def _progress():
    """Progress lines on stderr with the elapsed time (stdout stays clean for --json)."""
    import time

    t0 = time.perf_counter()

    def say(msg: str) -> None:
        print(f"[nmin {time.perf_counter() - t0:5.1f} s] {msg}", file=sys.stderr, flush=True)

    return say


def _cmd_nmin(args: argparse.Namespace) -> int:
    level = _check_level(args.level)
    ensayo, acel, candidates, p0, v0, nv = _inputs(args)
    try:
        steps = [int(s) for s in args.steps.split(",")] if args.steps else []
        mc_n = [int(s) for s in args.mc_n.split(",")] if args.mc_n else []
    except ValueError:
        raise DataError("--steps / --mc-n: expected comma-separated integers") from None
    if any(s < 1 for s in steps) or any(n < 3 for n in mc_n):
        raise DataError("--steps must be >= 1 and --mc-n values >= 3")
    if args.runs < 0:
        raise DataError(f"--runs must be >= 0, got {args.runs}")
    res = analyze_nmin(ensayo, acel, candidates, p0, v0, nv, level, args.method,
                       args.integrator, args.g, steps, mc_n, args.runs, args.seed,
                       progress=_progress())
    if args.json:
        print(dumps(res.to_dict()), end="")
    else:
        print(res.summary())
    return 0


def register(sub) -> None:
    p = sub.add_parser("trajectory", help="correct, integrate and decide the arrival point")
    _add_inputs(p)
    p.add_argument("--plot", help="write a figure (.png or .svg)")
    p.add_argument("--rrd", help="write a rerun recording of the run to this file")
    p.add_argument("--force", action="store_true",
                   help="overwrite an existing --plot / --rrd file")
    p.set_defaults(handler=_cmd_trajectory)

    q = sub.add_parser("nmin", help="calibration samples needed to decide the arrival point")
    _add_inputs(q)
    q.add_argument("--steps", default=",".join(map(str, COURSE_STEPS)),
                   help="subsampling steps of the course experiment (every k-th sample)")
    q.add_argument("--mc-n", default="20001,1539,1429",
                   help="calibration sizes N for fresh synthetic runs (the design N is added)")
    q.add_argument("--runs", type=int, default=100, help="synthetic runs per N (0: none)")
    q.add_argument("--seed", type=int, default=0, help="seed of the synthetic runs")
    q.set_defaults(handler=_cmd_nmin)
