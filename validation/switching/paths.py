"""Paths for the switching study (:mod:`validation.switching.score`), made with numpy alone:
white noise plus a random walk or a telegraph (two levels, switches at uniform random times).
Nothing here imports the detector (``bench``, ``calib``) or the scorer."""

from __future__ import annotations

import numpy as np


def make_path(rng: np.random.Generator, kind: str, faint: bool) -> tuple[np.ndarray, float,
                                                                        float, dict]:
    """(path, σ², Δt, what was made) of one walk or telegraph (module docstring)."""
    n = int(rng.choice([2001, 4001, 6001, 12001]))
    dt = 1.0 / float(rng.choice([50.0, 100.0, 200.0]))
    sigma = float(rng.uniform(0.05, 1.0))
    t = np.arange(n) * dt
    if kind == "walk":
        qt = float(rng.uniform(0.3, 1.2 if faint else 4.0))
        q = qt * sigma / np.sqrt(t[-1])
        drift = np.cumsum(rng.normal(0.0, q * np.sqrt(dt), n))
        info = {"q_sqrt_T_over_sigma": qt}
    else:
        k = int(rng.integers(4, 31))
        times = np.sort(rng.uniform(0.05, 0.95, k) * t[-1])
        h = float(rng.uniform(0.2, 0.6))
        drift = h * sigma * ((int(rng.integers(0, 2)) + np.searchsorted(times, t, "right")) % 2)
        info = {"h_over_sigma": h, "switches": k}
    return drift + rng.normal(0.0, sigma, n), sigma**2, dt, info
