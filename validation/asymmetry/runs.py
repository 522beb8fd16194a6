"""Runs for the K2-or-asymmetry study (:mod:`validation.asymmetry.score`), made with numpy
alone: nothing here imports the detector (``bench``, ``calib``) or the scorer.

A run: N of 3001, 4001 or 6001 samples at 50, 100 or 200 Hz over one of three table motions
(stop and go: holds of 2–5 s and cycloidal moves of 0.5–1.5 rad in 0.8–1.5 s; a constant
rate of 0.3–1 rad/s; a back-and-forth sine of ±2.5 rad, 2–5 periods per run); readings with
the course signs ``A_x = −g sin θ``, ``A_y = −g cos θ`` and white noise of std 0.05–0.5
m/s² per axis; on one axis the effect, sized by z, the norm of its centred column in noise
stds (``coef·‖c − c̄‖ = z·σ``):

* ``k2``: ``K2·A_r²`` (the catalog's second-order term);
* ``asymmetry``: ``κ·max(A_r, 0)`` (a gain that differs by the sign of the input);
* ``k3``: ``K3·A_r³`` (IEEE Std 1293's third-order term, not in the catalog);
* ``lever``: ``−r·cos β·ω² + r·sin β·α`` with β uniform (a site off the hinge at radius r,
  angle β from the sensitive axis: the catalog's lever arm);
* ``speed``: ``c·|ω|`` (a bias that grows with the rotation rate, not in the catalog).

The last two need a varying rate: their runs are stop and go or back and forth; ω and α are
numpy's central differences of θ.
"""

from __future__ import annotations

import numpy as np

G = 9.80665
"""Gravity of the runs, m/s² (the analysis' default)."""


def motion(rng: np.random.Generator, n: int, dt: float, varying: bool = False
           ) -> tuple[np.ndarray, np.ndarray, str]:
    """(t s, θ rad, design name) of one run (module docstring); ``varying``: not the constant
    rate."""
    t = np.arange(n) * dt
    kind = int(rng.choice([0, 2])) if varying else int(rng.integers(0, 3))
    if kind == 0:
        theta = np.zeros(n)
        here, i = float(rng.uniform(-np.pi, np.pi)), 0
        while i < n:
            hold = int(rng.uniform(2.0, 5.0) / dt)
            theta[i:i + hold] = here
            i += hold
            move = int(rng.uniform(0.8, 1.5) / dt)
            step = float(rng.uniform(0.5, 1.5) * rng.choice([-1.0, 1.0]))
            s = np.arange(min(move, max(n - i, 0))) / move
            theta[i:i + s.size] = here + step * (s - np.sin(2.0 * np.pi * s) / (2.0 * np.pi))
            i += s.size
            here += step
        return t, theta, "stop_and_go"
    if kind == 1:
        return t, float(rng.uniform(0.3, 1.0)) * t + float(rng.uniform(-3.0, 3.0)), "constant"
    period = t[-1] / float(rng.uniform(2.0, 5.0))
    return t, 2.5 * np.sin(2.0 * np.pi * t / period), "back_and_forth"


def make_run(rng: np.random.Generator, kind: str, z_range: tuple[float, float]) -> dict:
    """One run with ``kind`` ("k2", "asymmetry", "k3", "lever" or "speed") of z drawn in
    ``z_range``: ``{"tita" rad, "datos" (N, 2) m/s², "t" s, "noise_var" (m/s²)², "info"}``."""
    n = int(rng.choice([3001, 4001, 6001]))
    dt = 1.0 / float(rng.choice([50.0, 100.0, 200.0]))
    t, theta, name = motion(rng, n, dt, varying=kind in ("lever", "speed"))
    sigma = rng.uniform(0.05, 0.5, 2)
    ref = np.column_stack([-G * np.sin(theta), -G * np.cos(theta)])
    k = int(rng.integers(0, 2))
    z = float(rng.uniform(*z_range))
    omega = np.gradient(theta, t)
    if kind == "lever":
        beta = float(rng.uniform(0.0, 2.0 * np.pi))
        col = -np.cos(beta) * omega**2 + np.sin(beta) * np.gradient(omega, t)
    elif kind == "speed":
        col = np.abs(omega)
    else:
        col = {"asymmetry": np.maximum(ref[:, k], 0.0), "k2": ref[:, k] ** 2,
               "k3": ref[:, k] ** 3}[kind]
    spread = float(np.linalg.norm(col - col.mean()))
    coef = z * float(sigma[k]) / spread if spread > 0.0 else 0.0
    datos = ref + rng.normal(0.0, 1.0, (n, 2)) * sigma
    datos[:, k] += coef * col
    return {"tita": theta, "datos": datos, "t": t, "noise_var": tuple(float(s) ** 2 for s in sigma),
            "info": {"kind": kind, "axis": "xy"[k], "z": z, "coef": coef, "design": name, "n": n}}
