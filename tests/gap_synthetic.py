"""Synthetic tilt-table runs for the ``calib.gap`` tests, in numpy straight from the equations
of ``docs/effects.md`` (never through ``calib``'s models or the bench), so an error in the
estimator's model cannot cancel in a test: :func:`synth` makes a run with any effects of the
catalog on any of the :func:`design` schedules."""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES

G = 9.8
TWO_PI = 2.0 * np.pi
STATED = (0.25, 0.64)
"""The noise variances stated to the analysis (the course's), (m/s²)²."""
RATE = 100.0
"""Sample rate of the timed designs, Hz."""


def design(kind: str, n: int, rng: np.random.Generator):
    """θ schedule (rad) and sample times (s, or None): the designs calib.gap must handle."""
    if kind == "uniform":  # a full turn sampled uniformly at random, in time order
        return np.sort(rng.uniform(0, TWO_PI, n)), None
    if kind == "held":  # discrete held positions, many samples each
        p = int(rng.choice([6, 12, 24, 36]))
        pos = np.linspace(0, TWO_PI, p, endpoint=False) + rng.uniform(0, TWO_PI / p)
        return np.repeat(pos, int(np.ceil(n / p)))[:n], None
    if kind == "partial":  # non-uniform density over part of a turn
        lo = rng.uniform(0.0, 1.0)
        return np.sort(lo + rng.uniform(1.6, 2.4) * rng.uniform(0, 1, n) ** 2), None
    t = np.arange(n) / RATE
    u = t / t[-1]
    if kind == "constant":
        return TWO_PI * u, t
    if kind == "updown":  # up then down
        return TWO_PI * (1 - np.abs(2 * u - 1)), t
    if kind == "sine":  # oscillating, three cycles
        return np.pi - np.pi * np.cos(TWO_PI * 3 * u), t
    raise ValueError(kind)


def rates(kind: str, t: np.ndarray):
    """Exact ω (rad/s) and α (rad/s²) of the timed designs (for the lever-arm truth)."""
    w = TWO_PI * 3 / t[-1]
    if kind == "sine":
        return np.pi * w * np.sin(w * t), np.pi * w * w * np.cos(w * t)
    raise ValueError(f"lever arm truth needs a smooth design, not {kind}")


def lowpass_loop(u: np.ndarray, t: np.ndarray, tau: float) -> np.ndarray:
    """``τ dy/dt + y = u`` exactly for u linear between samples, y_0 = u_0 (docs/effects.md)."""
    y = np.empty_like(u)
    y[0] = u[0]
    for k in range(1, u.size):
        h = t[k] - t[k - 1]
        a = np.exp(-h / tau)
        c = (u[k] - u[k - 1]) / h
        y[k] = u[k] - tau * c + a * (y[k - 1] - u[k - 1] + tau * c)
    return y


def synth(kind: str, n: int, rng: np.random.Generator, effects=(), g: float = G):
    """A run with the given effects: (θ, readings (N, 2), t or None).

    Readings follow docs/effects.md: the true specific force on each sensitive axis is
    ``-g sin(θ + δ_x)``, ``-g cos(θ + δ_y)`` (misalignment / tilt offset rotate by +δ), plus the
    lever-arm terms (x: -ω² pos_x + α pos_z; y: ω² pos_z + α pos_x), clipped to ±limit; then the
    response terms (low-pass first, then k2·a², k_ip·a·a_p), ``(1 + scale)·… + bias + v``,
    then the additive drift / random walk and the rounding to lsb. Bias and scale are random.
    """
    th, t = design(kind, n, rng)
    bias = rng.uniform(-0.3, 0.3, 2)
    scale = rng.uniform(-0.03, 0.03, 2)
    s2 = np.array(STATED)
    delta, lever, limit = np.zeros(2), np.zeros((2, 2)), np.full(2, np.inf)
    terms: list[dict] = [{}, {}]
    g_true = g
    for name, axis, p in effects:
        for k in ((0, 1) if axis == "both" else (AXES.index(axis),)):
            if name in ("misalignment", "tilt_offset"):
                delta[k] += p["delta"]
            elif name == "lever_arm":
                lever[k] = (p["pos_x"], p["pos_z"])
            elif name == "saturation":
                limit[k] = p["limit"]
            elif name == "noise_level":
                s2[k] = p["sigma2"]
            elif name == "gravity_mismatch":
                g_true = p["g"]
            else:
                terms[k][name] = p
    a = np.column_stack([-g_true * np.sin(th + delta[0]), -g_true * np.cos(th + delta[1])])
    if np.any(lever != 0):
        w, al = rates(kind, t)
        a[:, 0] += -w**2 * lever[0, 0] + al * lever[0, 1]
        a[:, 1] += w**2 * lever[1, 1] + al * lever[1, 0]
    a = np.column_stack([np.clip(a[:, k], -limit[k], limit[k]) for k in range(2)])
    out = np.empty((n, 2))
    for k in range(2):
        x, tk = a[:, k].copy(), terms[k]
        if "lowpass_lag" in tk:
            x = lowpass_loop(x, t, tk["lowpass_lag"]["tau"])
        if "nonlinearity_k2" in tk:
            x = x + tk["nonlinearity_k2"]["k2"] * x * x
        if "cross_axis" in tk:
            x = x + tk["cross_axis"]["k_ip"] * x * a[:, 1 - k]
        x = (1 + scale[k]) * x + bias[k] + np.sqrt(s2[k]) * rng.standard_normal(n)
        if "bias_drift" in tk:
            p = tk["bias_drift"]
            x = x + (p["rate"] * (t - t[0]) if "rate" in p
                     else p["rate_per_sample"] * np.arange(n))
        if "bias_random_walk" in tk:
            p = tk["bias_random_walk"]
            dt = np.diff(t) if "q" in p else np.ones(n - 1)
            q = p["q"] if "q" in p else p["q_per_sample"]
            x = x + np.concatenate([[0.0], np.cumsum(q * np.sqrt(dt) * rng.standard_normal(n - 1))])
        if "quantization" in tk:
            lsb = tk["quantization"]["lsb"]
            x = lsb * np.floor(x / lsb + 0.5)
        out[:, k] = x
    return th, out, t
