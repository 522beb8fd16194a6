"""Probe ``calib.gap`` with mechanisms outside both validation sets (issue 20).

    python tools/mechanism_probe.py [MECHANISM,...] [--z 10]

**Not independent**: written by the detector's author (2026-11-26) to look for sponges the
two validation sets do not have; it shows what the detector does on them and is not a score to
report beside the independent set's. Each run is a *clean* run of the independent generator
(``validation.independent``: its designs, sampling and sensor chain; seeds 500, 501, noise
sets 0, 1) with one mechanism added here from its physics, sized ``z`` σ beyond the catalog's
linear signatures (bias, scale and ``validation.independent.effects.catalog_columns``
projected out):

==============  ==============================================================================
scale_drift     ``A_r·u``, u = time on [-½, ½] (a gain drifting with temperature)
backlash        ``dA_r/dθ·d``, d the direction of the last motion (the table stops short)
gain_step       ``A_r·[u > u₀]``, u₀ uniform in [-0.3, 0.3]
tilt_drift      ``dA_r/dθ·u`` (a creeping tilt of the mount)
warmup          ``exp(-(t - t₀)/T)``, T = 15 % of the run
heating         travel so far ``∫|ω|dt`` normalised (nothing while holding; moving runs)
ar_noise        AR(1) noise φ = 0.9 of σ added (sized in its own terms)
corr_noise      one white series × 0.8 σ added to both axes (common-mode noise)
signal_noise    white noise × 0.6 σ·|A_r|/g added (noise that follows the load)
==============  ==============================================================================

Seven designs (back-and-forth with dwells, slow/fast turns, stop-and-go, growing rock, partial
sweep with jittered t, random poses, repeated poses) × 2 seeds, the axis alternating. A run is
"ok" when the verdict is ``unexplained``. Measured at the session start (d9d19be) and now in
the closing note of stop 26.
"""

from __future__ import annotations

import argparse
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

DESIGNS = [("backforth_dwell", "rate"), ("slow_fast_turns", "rate"), ("stop_and_go", "rate"),
           ("growing_rock", "rate"), ("partial_sweep", "t"), ("random_poses", "none"),
           ("repeated_poses", "none")]
MECHANISMS = ("scale_drift", "backlash", "gain_step", "tilt_drift", "warmup", "heating",
              "ar_noise", "corr_noise", "signal_noise")


def _shape(mech: str, motion, a: np.ndarray, k: int, u: np.ndarray,
           rng: np.random.Generator) -> np.ndarray | None:
    slope = a[:, 1] if k == 0 else -a[:, 0]  # dA_r/dθ, course signs
    if mech == "scale_drift":
        return a[:, k] * u
    if mech == "backlash":
        both = np.any(motion.last_dir < 0) and np.any(motion.last_dir > 0)
        return slope * motion.last_dir if both else None
    if mech == "gain_step":
        return a[:, k] * (u > -0.3 + 0.6 * rng.uniform())
    if mech == "tilt_drift":
        return slope * u
    if mech == "warmup":
        return np.exp(-(u + 0.5) / 0.15)
    if mech == "heating":
        if motion.omega is None or not np.any(motion.omega):
            return None
        h = np.cumsum(np.abs(motion.omega))
        return h / h[-1]
    raise ValueError(mech)


def probe(arg: tuple[str, int, int, float]) -> tuple | None:
    """(mechanism, design, axis, verdict, named) of one run, or None when the mechanism does
    not apply to the design."""
    from calib.files.course import validate_ensayo
    from calib.gap import analyze_gap
    from validation.independent.cases import CL, CaseDef, build
    from validation.independent.effects import catalog_columns
    from validation.independent.physics import static_force

    mech, di, seed, z = arg
    design, timing = DESIGNS[di]
    case = CaseDef(CL, "clean", "-", design, timing, "jitter" if timing == "t" else "uniform",
                   rate=100, n=4001 + 2 * seed, noise=seed % 4)
    motion, datos, truth = build(case, seed=500 + seed)
    rng = np.random.default_rng([seed, di, 7])
    k = seed % 2
    sd = np.sqrt(truth["noise_var"])
    a = static_force(motion.theta)
    clock = motion.clock
    u = (clock - clock.mean()) / max(float(np.ptp(clock)), 1e-9)
    datos = datos.copy()
    if mech == "corr_noise":
        datos += 0.8 * sd * rng.standard_normal(motion.n)[:, None]
    elif mech == "ar_noise":
        e = rng.standard_normal(motion.n)
        x = np.zeros(motion.n)
        for i in range(1, motion.n):
            x[i] = 0.9 * x[i - 1] + e[i]
        datos[:, k] += sd[k] * x / x.std()
    elif mech == "signal_noise":
        datos[:, k] += 0.6 * sd[k] * np.abs(a[:, k]) / 9.8 * rng.standard_normal(motion.n)
    else:
        s = _shape(mech, motion, a, k, u, rng)
        if s is None:
            return None
        basis = np.column_stack([np.ones(motion.n), a[:, k], catalog_columns(motion)["xy"[k]]])
        q, _ = np.linalg.qr(basis)
        left = s - q @ (q.T @ s)
        datos[:, k] += z * sd[k] / np.linalg.norm(left) * s
    res = analyze_gap(validate_ensayo(motion.theta, datos, motion.t), truth["noise_var"],
                      rate=100.0 if timing == "rate" else None)
    return mech, design, "xy"[k], res.verdict, res.named


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("mechanisms", nargs="?", default=",".join(MECHANISMS))
    p.add_argument("--z", type=float, default=10.0, help="size beyond the catalog, in σ")
    args = p.parse_args(argv)
    mechs = args.mechanisms.split(",")
    unknown = sorted(set(mechs) - set(MECHANISMS))
    if unknown:
        p.error(f"unknown mechanism(s) {unknown}; choose from {', '.join(MECHANISMS)}")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    tasks = [(m, di, s, args.z) for m in mechs for di in range(len(DESIGNS)) for s in range(2)]
    counts: dict[str, list[int]] = {m: [0, 0] for m in mechs}
    with ProcessPoolExecutor(2, mp_context=get_context("spawn")) as ex:
        for r in ex.map(probe, tasks):
            if r is None:
                continue
            ok = r[3] == "unexplained"
            counts[r[0]][0] += ok
            counts[r[0]][1] += 1
            print(("ok  " if ok else "MISS"), *r, flush=True)
    for m, (ok, n) in counts.items():
        print(f"{m:14s} unexplained {ok}/{n}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    raise SystemExit(main())
