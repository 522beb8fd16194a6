"""Paths for the switching study (:mod:`validation.switching.score`), made with numpy alone:
white noise plus a random walk, a telegraph (two levels, switches at uniform random times) or
a staircase (2–6 steps of one sign and size, 0.25–0.6 σ, at uniform random times).
Nothing here imports the detector (``bench``, ``calib``) or the scorer."""

from __future__ import annotations

import numpy as np


def make_path(rng: np.random.Generator, kind: str, faint: bool) -> tuple[np.ndarray, float,
                                                                        float, dict]:
    """(path, σ², Δt, what was made) of one walk, telegraph or staircase (module docstring)."""
    n = int(rng.choice([2001, 4001, 6001, 12001]))
    dt = 1.0 / float(rng.choice([50.0, 100.0, 200.0]))
    sigma = float(rng.uniform(0.05, 1.0))
    t = np.arange(n) * dt
    if kind == "walk":
        qt = float(rng.uniform(0.3, 1.2 if faint else 4.0))
        q = qt * sigma / np.sqrt(t[-1])
        drift = np.cumsum(rng.normal(0.0, q * np.sqrt(dt), n))
        info = {"q_sqrt_T_over_sigma": qt}
    elif kind == "staircase":
        k = int(rng.integers(2, 7))
        times = np.sort(rng.uniform(0.05, 0.95, k) * t[-1])
        h = float(rng.uniform(0.25, 0.6)) * float(rng.choice([-1.0, 1.0]))
        drift = h * sigma * np.searchsorted(times, t, "right")
        info = {"h_over_sigma": h, "steps": k}
    else:
        k = int(rng.integers(4, 31))
        times = np.sort(rng.uniform(0.05, 0.95, k) * t[-1])
        h = float(rng.uniform(0.2, 0.6))
        drift = h * sigma * ((int(rng.integers(0, 2)) + np.searchsorted(times, t, "right")) % 2)
        info = {"h_over_sigma": h, "switches": k}
    return drift + rng.normal(0.0, sigma, n), sigma**2, dt, info


G = 9.80665
"""Gravity of the runs made by :func:`make_run`, m/s² (the analysis' default)."""


def make_run(rng: np.random.Generator, kind: str, faint: bool, max_n: int = 6001
             ) -> dict | None:
    """A whole calibration run around one path of :func:`make_path` (None when the path is
    longer than ``max_n``): the table turns at a constant 0.2–1 rad/s from a random angle, or
    stops and goes (45° moves of 1 s, raised cosine, every 4 s); the course signs
    ``A_x = −g sin θ + e``, ``A_y = −g cos θ + v`` with the path ``e`` on x and white noise
    ``v`` of the same σ on y. Returns ``{"tita" rad, "datos" (N, 2) m/s², "t" s, "noise_var"
    (m/s²)², "info"}``."""
    e, s2, dt, info = make_path(rng, kind, faint)
    n = e.size
    if n > max_n:
        return None
    t = np.arange(n) * dt
    if rng.integers(0, 2) == 0:
        theta = float(rng.uniform(0.2, 1.0)) * t + float(rng.uniform(-np.pi, np.pi))
        info["design"] = "constant_rate"
    else:
        move = np.clip((t % 4.0) / 1.0, 0.0, 1.0)
        theta = np.deg2rad(45.0) * (np.floor(t / 4.0) + 0.5 - 0.5 * np.cos(np.pi * move))
        info["design"] = "stop_and_go"
    datos = np.column_stack([-G * np.sin(theta) + e,
                             -G * np.cos(theta) + rng.normal(0.0, np.sqrt(s2), n)])
    return {"tita": theta, "datos": datos, "t": t, "noise_var": (s2, s2), "info": info}
