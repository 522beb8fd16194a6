"""Table-motion designs of the drive part, with exact θ, ω = dθ/dt and α = d²θ/dt².

A design is a chain of segments, each a closed form in the time τ since the segment began
(no numerical derivative anywhere):

* ``hold(T)``: θ constant, ω = α = 0;
* ``cyc(Δ, T)``: a cycloidal point-to-point move, u = τ/T,
  θ = θ₀ + Δ·(u − sin 2πu / 2π), ω = (Δ/T)·(1 − cos 2πu), α = (2πΔ/T²)·sin 2πu
  (rate and acceleration zero at both ends, peak rate 2Δ/T);
* ``ramp(ω₀, ω₁, T)``: the rate goes from ω₀ to ω₁ along the same cycloid,
  ω = ω₀ + (ω₁ − ω₀)·(u − sin 2πu / 2π), α = ((ω₁ − ω₀)/T)·(1 − cos 2πu),
  θ = θ₀ + ω₀τ + (ω₁ − ω₀)·T·(u²/2 + (cos 2πu − 1)/4π²);
* ``cruise(ω, T)``: constant rate.

Designs (none of them in ``validation/`` or ``validation/independent/``):

* ``stopgo_dwell``: stop-and-go with long dwells (3–7 s) and short steps of 30–90°, mostly
  forward, now and then back;
* ``sweep_pause``: constant-rate sweeps of 90–270° (cycloidal ramps in and out) separated by
  pauses of 2–5 s, the direction reversed at random;
* ``pose_tour``: random pose visits in [−π, π) with timed moves (duration grows with the
  distance, T = 0.6 + 0.9·√|Δ| s) and dwells of 1.5–4 s;
* ``shuttle``: back and forth between about −100° and +190° with trapezoidal rate profiles
  (cycloidal ramps, cruise) and dwells of 2–4 s at the ends;
* ``pose_holds``: the pose tour logged only while the table holds — the moves fall between
  two samples, so θ jumps (a static run).

Sampling: ``rate_hz`` uniform (t_k = k / rate), or jittered (each t_k moved by up to ±0.3 of
a step, still increasing). How the timing reaches ``tiltbench gap``: ``"t"`` (t in the file),
``"rate"`` (uniform, no t: ``--rate``), ``"none"`` (neither: samples in time order only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * np.pi

DESIGNS = ("stopgo_dwell", "sweep_pause", "pose_tour", "shuttle", "pose_holds")
MOVING_DESIGNS = DESIGNS[:4]


@dataclass(frozen=True)
class Seg:
    """One segment: ``kind`` hold | cyc | ramp | cruise; ``T`` s; ``a``: Δ (rad) of a cyc,
    ω₀ of a ramp, ω of a cruise (rad/s); ``b``: ω₁ of a ramp (rad/s)."""

    kind: str
    T: float
    a: float = 0.0
    b: float = 0.0

    def at(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(θ − θ₀, ω, α) at the local times ``tau`` (s)."""
        z = np.zeros_like(tau)
        if self.kind == "hold":
            return z, z, z
        if self.kind == "cruise":
            return self.a * tau, z + self.a, z
        u = tau / self.T
        c, s = np.cos(TWO_PI * u), np.sin(TWO_PI * u)
        if self.kind == "cyc":
            d = self.a
            return (d * (u - s / TWO_PI), d / self.T * (1.0 - c),
                    TWO_PI * d / self.T**2 * s)
        if self.kind == "ramp":
            w0, dw = self.a, self.b - self.a
            return (w0 * tau + dw * self.T * (u**2 / 2.0 + (c - 1.0) / TWO_PI**2),
                    w0 + dw * (u - s / TWO_PI), dw / self.T * (1.0 - c))
        raise ValueError(self.kind)

    @property
    def span(self) -> float:
        """θ change over the whole segment (rad)."""
        return float(self.at(np.array([self.T]))[0][0])


@dataclass(frozen=True)
class Motion:
    """One run: ``theta``, ``omega``, ``alpha`` (N,) in rad, rad/s, rad/s² — the table's
    true motion, read exactly by the encoder; ``time`` (N,) s, the true sample times (also
    for runs whose file carries no t); ``moving`` (N,) bool, inside a move (not a hold);
    ``timing`` how the file gives the times ("t" | "rate" | "none"); ``rate_hz`` the nominal
    rate; ``moves`` the number of moves."""

    design: str
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    time: np.ndarray
    moving: np.ndarray
    timing: str
    sampling: str
    rate_hz: float
    moves: int

    @property
    def n(self) -> int:
        return int(self.theta.size)

    @property
    def clock(self) -> np.ndarray:
        """What a drift or a walk runs on: t (s) when the file is timed, else the sample
        index (docs/effects.md: per sample without timing)."""
        return self.time if self.timing != "none" else np.arange(self.n, dtype=float)

    def summary(self) -> dict:
        return {"theta_min": float(self.theta.min()), "theta_max": float(self.theta.max()),
                "omega_max": float(np.abs(self.omega).max()),
                "alpha_max": float(np.abs(self.alpha).max()),
                "moves": self.moves, "moving_fraction": float(self.moving.mean()),
                "duration": float(self.time[-1] - self.time[0])}


def _stopgo(rng, dur):
    segs = [Seg("hold", rng.uniform(2.0, 4.0))]
    while sum(s.T for s in segs) < dur:
        d = np.deg2rad(rng.choice([30.0, 45.0, 60.0, 90.0]))
        d *= 1.0 if rng.uniform() < 0.8 else -1.0
        segs += [Seg("cyc", 0.5 + 0.5 * np.sqrt(abs(d)), d), Seg("hold", rng.uniform(3.0, 7.0))]
    return float(rng.uniform(-np.pi, np.pi)), segs


def _sweep_pause(rng, dur):
    segs = [Seg("hold", rng.uniform(1.5, 3.0))]
    sign = 1.0 if rng.uniform() < 0.5 else -1.0
    while sum(s.T for s in segs) < dur:
        w = sign * rng.uniform(0.4, 1.0)
        ta = rng.uniform(0.5, 1.0)
        span = np.deg2rad(rng.uniform(90.0, 270.0))
        cruise = max(span / abs(w) - ta, 0.5)   # each ramp covers w·ta/2
        segs += [Seg("ramp", ta, 0.0, w), Seg("cruise", cruise, w), Seg("ramp", ta, w, 0.0),
                 Seg("hold", rng.uniform(2.0, 5.0))]
        if rng.uniform() < 0.4:
            sign = -sign
    return float(rng.uniform(-np.pi, np.pi)), segs


def _tour(rng, dur):
    th = float(rng.uniform(-np.pi, np.pi))
    segs = [Seg("hold", rng.uniform(1.5, 4.0))]
    cur = th
    while sum(s.T for s in segs) < dur:
        target = rng.uniform(-np.pi, np.pi)
        d = target - cur
        if abs(d) < np.deg2rad(10.0):
            continue
        segs += [Seg("cyc", 0.6 + 0.9 * np.sqrt(abs(d)), d), Seg("hold", rng.uniform(1.5, 4.0))]
        cur = target
    return th, segs


def _shuttle(rng, dur):
    lo = np.deg2rad(-100.0 + rng.uniform(-10.0, 10.0))
    hi = np.deg2rad(190.0 + rng.uniform(-10.0, 10.0))
    segs = [Seg("hold", rng.uniform(2.0, 4.0))]
    up = True
    while sum(s.T for s in segs) < dur:
        w = rng.uniform(0.8, 1.6) * (1.0 if up else -1.0)
        ta = rng.uniform(0.4, 0.9)
        cruise = (hi - lo) / abs(w) - ta
        segs += [Seg("ramp", ta, 0.0, w), Seg("cruise", cruise, w), Seg("ramp", ta, w, 0.0),
                 Seg("hold", rng.uniform(2.0, 4.0))]
        up = not up
    return float(lo), segs


BUILDERS = {"stopgo_dwell": _stopgo, "sweep_pause": _sweep_pause, "pose_tour": _tour,
          "shuttle": _shuttle, "pose_holds": _tour}


def evaluate(theta0: float, segs: list[Seg], t: np.ndarray):
    """θ, ω, α, moving at the times ``t`` of the chain ``segs`` starting at ``theta0``."""
    starts = np.concatenate([[0.0], np.cumsum([s.T for s in segs])])
    th0 = theta0 + np.concatenate([[0.0], np.cumsum([s.span for s in segs])])
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segs) - 1)
    theta, omega, alpha = np.empty_like(t), np.empty_like(t), np.empty_like(t)
    moving = np.zeros(t.size, dtype=bool)
    for k in np.unique(idx):
        m = idx == k
        d, w, a = segs[k].at(t[m] - starts[k])
        theta[m], omega[m], alpha[m] = th0[k] + d, w, a
        moving[m] = segs[k].kind != "hold"
    return theta, omega, alpha, moving


def make(design: str, rng: np.random.Generator, n: int, rate_hz: float, timing: str,
         sampling: str = "uniform") -> Motion:
    """N samples of ``design`` at ``rate_hz`` (module docstring)."""
    if design == "pose_holds":
        return _holds(rng, n, rate_hz, timing)
    k = np.arange(n, dtype=float)
    t = k / rate_hz
    if sampling == "jitter":
        t = t + rng.uniform(-0.3, 0.3, n) / rate_hz
        t[0] = 0.0
    theta0, segs = BUILDERS[design](rng, float(t[-1]) + 1.0)
    theta, omega, alpha, moving = evaluate(theta0, segs, t)
    moves = int(np.sum(np.diff(moving.astype(int)) == 1) + moving[0])
    return Motion(design, theta, omega, alpha, t, moving, timing, sampling, rate_hz, moves)


def _holds(rng, n, rate_hz, timing) -> Motion:
    """The pose tour, sampled at ``rate_hz`` and kept only while holding: θ jumps between
    held poses (held samples of a moving run, logged in time order)."""
    theta0, segs = _tour(rng, 3.0 * n / rate_hz)
    t_all = np.arange(int(3.5 * n), dtype=float) / rate_hz
    theta, _, _, moving = evaluate(theta0, segs, t_all)
    keep = np.flatnonzero(~moving)[:n]
    if keep.size < n:
        raise RuntimeError("pose_holds: not enough held samples")
    t, theta = t_all[keep], theta[keep]
    z = np.zeros(n)
    jumps = int(np.sum(np.abs(np.diff(theta)) > 0))
    return Motion("pose_holds", theta, z, z.copy(), t, np.zeros(n, dtype=bool), timing,
                  "holds", rate_hz, jumps)


__all__ = ["DESIGNS", "MOVING_DESIGNS", "Motion", "Seg", "evaluate", "make"]
