"""θ designs of the validation set: each returns ``(tita, t)``, ``t`` None for untimed runs.

All timed designs sample at 100 Hz (``t = k / 100``) and start and end at rest unless stated
(a sensor whose low-pass filter has settled before the record starts: no start-up transient).
``n`` sets the number of samples; the duration of a timed run is ``n / 100`` s.

=================  =====  ========================================================================
name               timed  θ schedule
=================  =====  ========================================================================
full_turn          yes    0 → 2π, constant rate between 1 s raised-cosine start and stop
several_turns      yes    0 → 6π, the same profile
past_2pi           yes    0 → 2π + 0.3
overshoot          no     0 → 6.2841 (just past 2π), uniform steps: the course file's shape
oscillating        yes    θ = π(1 - cos(2πt/P)), P = duration/2: up and down twice (reversals)
negative           yes    0 → -2π (negative angles, turning backwards)
held_poses         no     10 static poses 0.15 + 2πk/10, n/10 samples each
stop_and_go        yes    8 holds (60 % of each cycle) and smooth moves of 2π/8 (40 %), a turn
short              no     0 → 2π in n ≈ 400 samples
varying_rate       yes    θ = ω̄(t - P/2π sin(2πt/P)), P = duration/3: rate 0 … 2ω̄, 0 → 4π
mujoco_sweep       yes    MuJoCo servo sweep with a varying rate (:mod:`validation.sweep`)
=================  =====  ========================================================================
"""

from __future__ import annotations

import numpy as np

from validation import sweep

RATE: float = 100.0
"""Sample rate of the timed designs, Hz."""

TWO_PI = 2.0 * np.pi


def _times(n: int) -> np.ndarray:
    return np.arange(n, dtype=float) / RATE


def ramp_profile(t: np.ndarray, theta0: float, theta1: float, ramp: float = 1.0) -> np.ndarray:
    """θ(t) from θ0 to θ1 over ``[t0, t_end]``: rate ``ω_p·w(t)`` with raised-cosine ramps
    ``w = (1 - cos(πτ/ramp))/2`` of ``ramp`` s at both ends, constant ``ω_p`` between.

    ``∫ w = τ/2 - ramp/(2π)·sin(πτ/ramp)`` on a ramp, so the whole run covers
    ``ω_p·(D - ramp)`` and ``ω_p = (θ1 - θ0)/(D - ramp)``.
    """
    tau = t - t[0]
    d = tau[-1]
    ramp = min(ramp, d / 3.0)

    def rise(x):  # ∫_0^x w
        x = np.clip(x, 0.0, ramp)
        return x / 2.0 - ramp / (2.0 * np.pi) * np.sin(np.pi * x / ramp)

    down = np.clip(tau - (d - ramp), 0.0, ramp)  # time into the stop ramp, w(ramp - x)
    covered = (rise(tau) + np.clip(tau - ramp, 0.0, d - 2 * ramp)
               + ramp / 2.0 - rise(ramp - down))
    return theta0 + (theta1 - theta0) * covered / (d - ramp)


def full_turn(n: int = 2400):
    t = _times(n)
    return ramp_profile(t, 0.0, TWO_PI), t


def several_turns(n: int = 4000):
    t = _times(n)
    return ramp_profile(t, 0.0, 3 * TWO_PI), t


def past_2pi(n: int = 2000):
    t = _times(n)
    return ramp_profile(t, 0.0, TWO_PI + 0.3), t


def overshoot(n: int = 3000):
    return np.linspace(0.0, 6.2841, n), None


def oscillating(n: int = 4000):
    t = _times(n)
    period = t[-1] / 2.0
    return np.pi * (1.0 - np.cos(TWO_PI * t / period)), t


def negative(n: int = 2400):
    t = _times(n)
    return ramp_profile(t, 0.0, -TWO_PI), t


def held_poses(n: int = 2000, poses: int = 10):
    angles = 0.15 + TWO_PI * np.arange(poses) / poses
    counts = [len(c) for c in np.array_split(np.arange(n), poses)]
    return np.repeat(angles, counts), None


def stop_and_go(n: int = 3200, stops: int = 8, hold_fraction: float = 0.6):
    """Hold, move 2π/stops with a minimum-jerk profile ``10u³ - 15u⁴ + 6u⁵``, repeat; the last
    hold is at 2π. Every cycle has the same length; the samples are uniform in time."""
    t = _times(n)
    cycle = (t[-1] + 1.0 / RATE) / (stops + hold_fraction)  # a final hold closes the run
    k = np.minimum(np.floor(t / cycle), stops).astype(int)
    u = (t - k * cycle) / cycle
    move = np.clip((u - hold_fraction) / (1.0 - hold_fraction), 0.0, 1.0)
    move = np.where(k < stops, move, 0.0)
    s = move**3 * (10.0 - 15.0 * move + 6.0 * move**2)
    return TWO_PI * (k + s) / stops, t


def short(n: int = 400):
    return np.linspace(0.0, TWO_PI, n), None


def varying_rate(n: int = 3000, turns: float = 2.0):
    t = _times(n)
    period = t[-1] / 3.0
    mean_rate = turns * TWO_PI / t[-1]
    return mean_rate * (t - period / TWO_PI * np.sin(TWO_PI * t / period)), t


def mujoco_sweep(n: int = 3000):
    run = sweep.simulate(n)
    return np.array(run.tita), np.array(run.t)


DESIGNS = {
    "full_turn": full_turn,
    "several_turns": several_turns,
    "past_2pi": past_2pi,
    "overshoot": overshoot,
    "oscillating": oscillating,
    "negative": negative,
    "held_poses": held_poses,
    "stop_and_go": stop_and_go,
    "short": short,
    "varying_rate": varying_rate,
    "mujoco_sweep": mujoco_sweep,
}
"""Design name → function ``(n) -> (tita, t or None)``."""

TIMED: frozenset[str] = frozenset(
    {"full_turn", "several_turns", "past_2pi", "oscillating", "negative", "stop_and_go",
     "varying_rate", "mujoco_sweep"})

CLEAN_N: dict[str, int] = {name: 1200 for name in DESIGNS} | {"short": 400}
"""Samples of the cheap clean runs (:func:`validation.cases.clean_cases`)."""


def design(name: str, n: int | None = None):
    """``(tita, t or None)`` of the design ``name`` with ``n`` samples (its default if None)."""
    if name not in DESIGNS:
        raise KeyError(f"unknown design {name!r}; known: {', '.join(DESIGNS)}")
    return DESIGNS[name]() if n is None else DESIGNS[name](n)
