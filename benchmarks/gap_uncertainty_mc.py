"""Monte Carlo check of the uncertainties that ``calib.gap`` prints for its nonlinear effects.

    OPENBLAS_NUM_THREADS=1 python benchmarks/gap_uncertainty_mc.py walk --reps 400
    OPENBLAS_NUM_THREADS=1 python benchmarks/gap_uncertainty_mc.py walk --candidates
    OPENBLAS_NUM_THREADS=1 python benchmarks/gap_uncertainty_mc.py saturation --reps 200

Each replicate is a synthetic calibration run generated here in numpy straight from
``docs/effects.md`` (never through ``calib`` or the bench), with random bias and scale on both
axes, the white noise of the course (σ² = 0.25, 0.64) and ONE effect on one axis:

* ``walk``: static full-turn design (θ uniform over a turn, sorted, no timing), a bias random
  walk on x with ``q_per_sample = size·σ_x/√N`` (``--size``, the walk's spread over the run in
  units of the white noise σ);
* ``saturation``: the same design, x clipped to ±``limit`` (9.0 m/s²);
* ``lowpass``: an up-then-down sweep (100 Hz, timed), low-pass τ = 0.05 s on x;
* ``quantization``: the same static design, x rounded to multiples of lsb = 0.5 m/s².

``calib.gap.analyze_gap`` runs end to end; over the replicates that name the effect on x it
reports ``z = (estimate - truth)/std``: mean(z), sd(z), the coverage of ``estimate ± 1.96 std``
and, where the effect has one, the coverage of the reported 95 % ``interval``. The binomial
tolerance ``4·sqrt(0.95·0.05/R)`` (≈ 4 standard errors of a coverage estimated from R runs)
says whether a coverage differs from 95 % beyond Monte Carlo noise; sd(z) has a standard error
≈ ``1/sqrt(2R)``.

``--candidates`` (walk only): on the final model of every replicate it also evaluates the
alternatives considered for the std of q (the measurements that chose the implementation):

* ``curv``: the curvature of the REML ``-2 log L`` in q at q̂ (the former ``_q_std``);
* ``fisher``: the expected Fisher information of the REML likelihood on log q, exact in the
  spectral form (per-sample units: Δt = 1, ``Σ_Δ = σ²T + q²I`` is diagonal in the DST-I basis,
  ``I(log q²) = ½ q⁴ tr(P²)``, ``P = Σ⁻¹ - Σ⁻¹X(XᵀΣ⁻¹X)⁻¹XᵀΣ⁻¹``);
* ``logwald``: ``q̂·exp(±1.96 s)`` with ``s = curv/q̂`` (Wald on log q);
* ``profile``: the REML profile-likelihood interval (what calib reports now).

Seeds: ``np.random.default_rng([SEED, effect index, replicate])``; the same arguments give the
same numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

G = 9.8
TWO_PI = 2.0 * np.pi
STATED = (0.25, 0.64)
SEED = 20240611
EFFECTS = ("walk", "saturation", "lowpass", "quantization")
Z95 = 1.959963984540054


def synth(effect: str, n: int, size: float, rng: np.random.Generator, design: str = "uniform",
          value: float | None = None):
    """(θ (N,) rad, readings (N, 2) m/s², t (N,) s or None, catalog key, true value).

    ``design`` (static effects): "uniform" (θ uniform over a full turn, sorted) or "held"
    (24 positions over a full turn, N/24 samples each, in order). ``value``: the true limit,
    τ or lsb instead of the default (9.0 m/s², 0.05 s, 0.5 m/s²).
    """
    if effect == "lowpass":
        t = np.arange(n) / 100.0
        u = t / t[-1]
        th = TWO_PI * (1 - np.abs(2 * u - 1))  # up then down
    elif design == "held":
        t = None
        pos = np.linspace(0, TWO_PI, 24, endpoint=False) + rng.uniform(0, TWO_PI / 24)
        th = np.repeat(pos, int(np.ceil(n / 24)))[:n]
    else:
        t = None
        th = np.sort(rng.uniform(0, TWO_PI, n))
    bias = rng.uniform(-0.3, 0.3, 2)
    scale = rng.uniform(-0.03, 0.03, 2)
    a = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    key, truth = "", 0.0
    if effect == "saturation":
        key, truth = "limit", value or 9.0
        a[:, 0] = np.clip(a[:, 0], -truth, truth)
    if effect == "lowpass":  # τ dy/dt + y = u, exact for u linear between samples, y_0 = u_0
        key, truth = "tau", value or 0.05
        x = a[:, 0].copy()
        for k in range(1, n):
            h = t[k] - t[k - 1]
            e = np.exp(-h / truth)
            c = (a[k, 0] - a[k - 1, 0]) / h
            x[k] = a[k, 0] - truth * c + e * (x[k - 1] - a[k - 1, 0] + truth * c)
        a[:, 0] = x
    y = (1 + scale) * a + bias + np.sqrt(STATED) * rng.standard_normal((n, 2))
    if effect == "walk":
        key, truth = "q_per_sample", size * np.sqrt(STATED[0]) / np.sqrt(n)
        y[1:, 0] += np.cumsum(truth * rng.standard_normal(n - 1))
    if effect == "quantization":
        key, truth = "lsb", value or 0.5
        y[:, 0] = truth * np.floor(y[:, 0] / truth + 0.5)
    return th, y, t, key, truth


def _fisher_std_logq(ext, state, k: int) -> float:
    """sd(log q̂) from the exact expected REML information (Δt = 1 only; see module doc)."""
    from scipy import fft

    st = state.axes[k]
    q, s2 = st.q, st.sigma2_eff
    r = ext.reference(k, st.tau, st.limit)
    _, cols = ext.columns(k, st)
    x = np.diff(np.column_stack([r, *cols]), axis=0)  # differenced design (bias removed)
    m = x.shape[0]
    j = np.arange(1, m + 1)
    lam = 2.0 - 2.0 * np.cos(j * np.pi / (m + 1))  # eigenvalues of T (m × m)
    s = s2 * lam + q * q
    xs = fft.dst(x, type=1, axis=0, norm="ortho")  # Vᵀ X in the DST-I basis
    xw = xs / s[:, None]
    mm = np.linalg.inv(xs.T @ xw)
    # tr(P²) = Σ 1/s² - 2 tr(M Xᵀ S⁻³ X) + tr((M Xᵀ S⁻² X)²)
    a2 = xs.T @ (xs / s[:, None] ** 2)
    a3 = xs.T @ (xs / s[:, None] ** 3)
    tr_p2 = np.sum(1.0 / s**2) - 2.0 * np.trace(mm @ a3) + np.trace(mm @ a2 @ mm @ a2)
    info_log_q2 = 0.5 * q**4 * tr_p2
    return float(0.5 / np.sqrt(info_log_q2))  # sd(log q) = ½ sd(log q²)


def replicate(job: tuple[str, int, int, float, str, float | None, bool]) -> dict:
    from calib.effects import Extensions, RunData
    from calib.files.course import Ensayo
    from calib.gap import analyze_gap

    effect, i, n, size, design, value, candidates = job
    rng = np.random.default_rng([SEED, EFFECTS.index(effect), i])
    th, y, t, key, truth = synth(effect, n, size, rng, design, value)
    res = analyze_gap(Ensayo(th, y, t), STATED)
    name = {"walk": "bias_random_walk", "saturation": "saturation", "lowpass": "lowpass_lag",
            "quantization": "quantization"}[effect]
    out = {"i": i, "truth": truth, "named": [list(e) for e in res.named], "found": False}
    try:
        e = res.effect(name, "x")
    except KeyError:
        return out
    out.update(found=True, est=float(e.params[key]), std=float(e.std[key]))
    if key in e.interval:
        out["interval"] = [float(v) for v in e.interval[key]]
    if candidates and effect == "walk":
        from calib.gap import q_curvature_std, q_profile_interval

        run = RunData.build(th, y, G)
        ext = Extensions(run, np.asarray(res.final.gains))
        state = res.final.state
        q = state.axes[0].q
        curv = q_curvature_std(ext, state, 0)
        lo, hi = q_profile_interval(ext, state, 0)
        sf = _fisher_std_logq(ext, state, 0)
        sc = curv / q
        out["cand"] = {
            "curv": [q - Z95 * curv, q + Z95 * curv, curv],
            "logwald": [q * np.exp(-Z95 * sc), q * np.exp(Z95 * sc), curv],
            "fisher": [q * np.exp(-Z95 * sf), q * np.exp(Z95 * sf), q * sf],
            "profile": [lo, hi, (hi - lo) / (2 * Z95)],
            "profile_log": [lo, hi, q * np.log(hi / lo) / (2 * Z95)],
        }
    return out


def summarise(rows: list[dict], label: str) -> dict:
    found = [r for r in rows if r["found"]]
    r_all, r = len(rows), len(found)
    tol = 4.0 * np.sqrt(0.95 * 0.05 / max(r, 1))
    est = np.array([f["est"] for f in found])
    std = np.array([f["std"] for f in found])
    truth = np.array([f["truth"] for f in found])
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (est - truth) / std
    out = {"label": label, "R": r_all, "named_on_x": r,
           "mean_z": float(np.mean(z)), "sd_z": float(np.std(z, ddof=1)),
           "sd_z_se": float(1 / np.sqrt(2 * r)),
           "cover_1.96std": float(np.mean(np.abs(z) <= Z95)),
           "cover_4std": float(np.mean(np.abs(z) <= 4)),
           "binomial_tol_95": float(tol),
           "rel_sd_estimate": float(np.std(est / truth, ddof=1))}
    if found and "interval" in found[0]:
        iv = np.array([f["interval"] for f in found])
        out["cover_interval"] = float(np.mean((iv[:, 0] <= truth) & (truth <= iv[:, 1])))
        out["miss_low_high"] = [float(np.mean(truth < iv[:, 0])),
                                float(np.mean(truth > iv[:, 1]))]
    if found and "cand" in found[0]:
        cands = {}
        for c in found[0]["cand"]:
            v = np.array([f["cand"][c] for f in found])
            cands[c] = {"cover_interval": float(np.mean((v[:, 0] <= truth) & (truth <= v[:, 1]))),
                        "miss_low_high": [float(np.mean(truth < v[:, 0])),
                                          float(np.mean(truth > v[:, 1]))],
                        "sd_z": float(np.std((est - truth) / v[:, 2], ddof=1)),
                        "cover_1.96std": float(np.mean(np.abs(est - truth) <= Z95 * v[:, 2]))}
        out["candidates"] = cands
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("effect", choices=EFFECTS)
    p.add_argument("--reps", type=int, default=None, help="R (default 400 walk, 200 others)")
    p.add_argument("--n", type=int, default=3000, help="samples per run")
    p.add_argument("--size", type=float, default=2.0,
                   help="walk: q√N in units of σ_x (2-4 in the brief)")
    p.add_argument("--design", choices=("uniform", "held"), default="uniform",
                   help="static θ design (walk, saturation, quantization)")
    p.add_argument("--value", type=float, default=None,
                   help="true limit / tau / lsb (default 9.0 m/s², 0.05 s, 0.5 m/s²)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--candidates", action="store_true", help="walk: compare std methods")
    args = p.parse_args()
    reps = args.reps or (400 if args.effect == "walk" else 200)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # inherited by the spawned workers
    jobs = [(args.effect, i, args.n, args.size, args.design, args.value, args.candidates)
            for i in range(reps)]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, mp_context=get_context("spawn")) as ex:
        rows = list(ex.map(replicate, jobs, chunksize=4))
    label = f"{args.effect} N={args.n}" + (f" q√N={args.size}σ" if args.effect == "walk" else "")
    if args.effect != "lowpass":
        label += f" {args.design}"
    if args.value is not None:
        label += f" value={args.value:g}"
    out = summarise(rows, label)
    out["seconds"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
