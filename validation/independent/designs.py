"""θ schedules (designs) of the independent set, with their exact rates.

Every moving design is a chain of polynomial segments in the time τ since the segment began,
so θ, ω = dθ/dt and α = d²θ/dt² are exact at any sample time (no numerical derivative):

* ``hold(T)``: θ constant;
* ``move(Δθ, T)``: minimum-jerk point-to-point move, θ = θ₀ + Δθ·s(u), u = τ/T,
  s(u) = 10u³ − 15u⁴ + 6u⁵ (zero rate and acceleration at both ends; Flash & Hogan 1985);
* ``ramp(ω₀, ω₁, T)``: the rate changes along the same s(u): ω = ω₀ + (ω₁ − ω₀)·s(u), so
  θ = θ₀ + ω₀τ + (ω₁ − ω₀)·T·S(u), S(u) = 2.5u⁴ − 3u⁵ + u⁶;
* ``cruise(ω, T)``: constant rate.

Static designs hold poses and jump between them between two samples (a table logged only
while it holds): no rates, a direction per jump. Timing of a file: ``"t"`` (t written in the
file, possibly non-uniform), ``"rate"`` (uniform, no t: the scorer passes ``--rate``) or
``"none"`` (no timing at all: static poses in time order).

The designs are chosen to differ from the project's own validation set: random-order poses,
few poses with many repeats, back-and-forth moves with dwells, non-uniform sampling, partial
ranges (θ within [−60°, 200°]), several turns, negative directions, slow and fast stretches,
a rocking motion whose rate grows, stop-and-go steps.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Polynomial

PARTIAL = (np.deg2rad(-60.0), np.deg2rad(200.0))
"""θ range (rad) of the partial designs."""


@dataclass(frozen=True)
class Motion:
    """One run's encoder samples and what the physics needs from them.

    theta, omega, alpha: (N,) rad, rad/s, rad/s² (the table's true motion; the encoder reads
    theta exactly). t: (N,) s or None (untimed). timing: "t" | "rate" | "none". rate: Hz for
    "rate". stop_times: (K,) s (or sample indices when untimed) at which a motion ended;
    stop_dirs: (K,) the sign of that motion. last_dir: (N,) sign of the last motion before
    each sample (0 before the first).
    """

    design: str
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    t: np.ndarray | None
    timing: str
    rate: float | None
    stop_times: np.ndarray
    stop_dirs: np.ndarray
    last_dir: np.ndarray

    @property
    def n(self) -> int:
        return self.theta.size

    @property
    def clock(self) -> np.ndarray:
        """Time of each sample in s, or the sample index when untimed."""
        return self.t if self.t is not None else np.arange(self.n, dtype=float)

    @property
    def moving(self) -> bool:
        return bool(np.any(self.omega != 0.0))


_S = Polynomial([0, 0, 0, 10, -15, 6])      # minimum-jerk shape s(u)
_SI = _S.integ()                   # S(u) = ∫₀ᵘ s


@dataclass(frozen=True)
class Segment:
    duration: float
    poly: Polynomial  # θ(τ) − θ₀, τ in s


def hold(T: float) -> Segment:
    return Segment(T, Polynomial([0.0]))


def move(dtheta: float, T: float) -> Segment:
    return Segment(T, dtheta * _S(Polynomial([0, 1.0 / T])))


def ramp(w0: float, w1: float, T: float) -> Segment:
    return Segment(T, Polynomial([0, w0]) + (w1 - w0) * T * _SI(Polynomial([0, 1.0 / T])))


def cruise(w: float, T: float) -> Segment:
    return Segment(T, Polynomial([0, w]))


def evaluate(segments: list[Segment], t: np.ndarray, theta0: float = 0.0):
    """θ, ω, α (N,) at times t (s, within the chain's duration) of a segment chain."""
    starts = np.concatenate([[0.0], np.cumsum([s.duration for s in segments])])
    bases = [theta0]
    for s in segments:
        bases.append(bases[-1] + float(s.poly(s.duration)))
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segments) - 1)
    theta = np.empty_like(t)
    omega = np.empty_like(t)
    alpha = np.empty_like(t)
    for i, s in enumerate(segments):
        m = idx == i
        tau = t[m] - starts[i]
        theta[m] = bases[i] + s.poly(tau)
        omega[m] = s.poly.deriv(1)(tau)
        alpha[m] = s.poly.deriv(2)(tau)
    return theta, omega, alpha, float(starts[-1])


def _stops(segments: list[Segment]) -> tuple[np.ndarray, np.ndarray]:
    """Times where a moving stretch meets a hold (or the end), and the sign of that motion."""
    times, dirs, t0, last = [], [], 0.0, 0.0
    for s in segments:
        net = float(s.poly(s.duration))
        is_hold = s.poly.degree() == 0
        if is_hold and last != 0.0:
            times.append(t0)
            dirs.append(np.sign(last))
            last = 0.0
        elif not is_hold:
            last = net if net != 0.0 else last
        t0 += s.duration
    return np.asarray(times), np.asarray(dirs)


def _last_dir(omega: np.ndarray) -> np.ndarray:
    sgn = np.sign(omega)
    idx = np.where(sgn != 0, np.arange(sgn.size), -1)
    idx = np.maximum.accumulate(idx)
    return np.where(idx >= 0, sgn[np.maximum(idx, 0)], 0.0)


def sample_times(rng: np.random.Generator, n: int, duration: float, kind: str) -> np.ndarray:
    """n sample times (s) over [0, duration]: ``uniform``; ``jitter`` (uniform ± 30 % of a
    period, strictly increasing); ``bursty`` (gaps: a logger that drops stretches — the rate
    alternates between two values)."""
    if kind == "uniform":
        return np.linspace(0.0, duration, n)
    if kind == "jitter":
        h = duration / (n - 1)
        t = np.linspace(0.0, duration, n) + rng.uniform(-0.3, 0.3, n) * h
        t[0], t[-1] = 0.0, duration
        return t
    if kind == "bursty":
        w = np.where((np.arange(n - 1) // 250) % 2 == 0, 1.0, 2.7) * rng.uniform(0.8, 1.2, n - 1)
        return np.concatenate([[0.0], np.cumsum(w)]) * duration / np.sum(w)
    raise ValueError(kind)


def from_segments(name: str, segments: list[Segment], *, theta0: float, n: int, rate: float,
                  timing: str, sampling: str, rng: np.random.Generator) -> Motion:
    """Sample a chain at ``rate`` Hz (nominal): N = max(n, the chain's duration·rate + 1)
    rounded up to a multiple of 1000 plus one, the chain padded with a final hold to fill
    (N − 1)/rate s."""
    duration = sum(s.duration for s in segments)
    need = int(np.ceil(duration * rate)) + 1
    if need > n:
        n = int(np.ceil((need - 1) / 1000.0)) * 1000 + 1
    total = (n - 1) / rate
    segments = [*segments, hold(total - duration)] if total > duration else segments
    t = sample_times(rng, n, total, sampling)
    theta, omega, alpha, _ = evaluate(segments, t, theta0)
    st, sd = _stops(segments)
    return Motion(name, theta, omega, alpha, t, timing, rate if timing == "rate" else None,
                  st, sd, _last_dir(omega))


# --- moving designs (segment chains) --------------------------------------------------------

def backforth_dwell(rng, n, rate=100.0, timing="rate", sampling="uniform"):
    """Back and forth between random angles inside [−60°, 200°] with dwells of 1–3 s."""
    lo, hi = PARTIAL
    segs, th, cur = [hold(1.0)], [], rng.uniform(lo, lo + 0.5)
    theta0 = cur
    up = True
    for _ in range(7):
        tgt = rng.uniform(hi - 1.2, hi) if up else rng.uniform(lo, lo + 1.2)
        segs += [move(tgt - cur, rng.uniform(1.5, 4.0)), hold(rng.uniform(1.0, 3.0))]
        th.append(tgt)
        cur, up = tgt, not up
    return from_segments("backforth_dwell", segs, theta0=theta0, n=n, rate=rate, timing=timing,
                         sampling=sampling, rng=rng)


def slow_fast_turns(rng, n, rate=100.0, timing="rate", sampling="uniform", sign=1.0, turns=2.5):
    """Several turns (default 2.5) alternating slow (0.3–0.6 rad/s) and fast (1.5–3 rad/s)
    stretches joined by smooth rate ramps; ``sign`` −1 turns the negative way."""
    segs, w, total = [hold(0.5)], 0.0, 0.0
    fast = False
    while total < turns * 2 * np.pi:
        w1 = rng.uniform(1.5, 3.0) if fast else rng.uniform(0.3, 0.6)
        T = rng.uniform(0.8, 1.5)
        segs.append(ramp(sign * w, sign * w1, T))
        total += abs(float(segs[-1].poly(T)))
        Tc = rng.uniform(2.0, 4.0) if fast else rng.uniform(3.0, 6.0)
        segs.append(cruise(sign * w1, Tc))
        total += w1 * Tc
        w, fast = w1, not fast
    segs += [ramp(sign * w, 0.0, 1.5), hold(1.0)]
    return from_segments("slow_fast_turns" if sign > 0 else "negative_turns", segs,
                         theta0=rng.uniform(-np.pi, np.pi), n=n, rate=rate, timing=timing,
                         sampling=sampling, rng=rng)


def stop_and_go(rng, n, rate=100.0, timing="rate", sampling="uniform", sign=-1.0):
    """One full turn (negative way by default) in 10–14 unequal steps with dwells."""
    k = int(rng.integers(10, 15))
    steps = rng.dirichlet(np.full(k, 3.0)) * 2 * np.pi * sign
    segs = [hold(1.0)]
    for s in steps:
        segs += [move(float(s), rng.uniform(0.6, 1.6)), hold(rng.uniform(0.8, 2.0))]
    return from_segments("stop_and_go", segs, theta0=rng.uniform(0, 2 * np.pi), n=n, rate=rate,
                         timing=timing, sampling=sampling, rng=rng)


def growing_rock(rng, n, rate=100.0, timing="rate", sampling="uniform"):
    """Rocking about a random centre, amplitude 40–110°, each swing faster than the last
    (swing time 3 s down to 0.7 s): the rate and acceleration vary over a wide range."""
    c = rng.uniform(-1.0, 1.0)
    amp = np.deg2rad(rng.uniform(40, 110))
    k = 10
    durations = np.geomspace(3.0, 0.7, k)
    segs, cur = [hold(1.0), move(amp, 1.5), hold(0.5)], amp
    for i, T in enumerate(durations):
        tgt = -amp if i % 2 == 0 else amp
        segs += [move(tgt - cur, float(T)), hold(0.3)]
        cur = tgt
    segs += [move(-cur, 1.5), hold(1.0)]
    return from_segments("growing_rock", segs, theta0=c, n=n, rate=rate, timing=timing,
                         sampling=sampling, rng=rng)


def partial_sweep(rng, n, rate=100.0, timing="t", sampling="jitter"):
    """Up from −60° to 200° and back at a rate that changes (slow, fast, slow), jittered
    sample times written in the file."""
    lo, hi = PARTIAL
    span = hi - lo
    segs = [hold(1.0)]
    for sgn in (1.0, -1.0):
        w_slow, w_fast = rng.uniform(0.25, 0.4), rng.uniform(0.9, 1.4)
        # slow third, fast third, slow third of the span; ramps take their share
        r1 = ramp(0, sgn * w_slow, 1.0)
        r2 = ramp(sgn * w_slow, sgn * w_fast, 1.0)
        r3 = ramp(sgn * w_fast, sgn * w_slow, 1.0)
        r4 = ramp(sgn * w_slow, 0, 1.0)
        ramps = sum(abs(float(r.poly(1.0))) for r in (r1, r2, r3, r4))
        rest = span - ramps
        segs += [r1, cruise(sgn * w_slow, rest * 0.3 / w_slow), r2,
                 cruise(sgn * w_fast, rest * 0.4 / w_fast), r3,
                 cruise(sgn * w_slow, rest * 0.3 / w_slow), r4, hold(2.0)]
    return from_segments("partial_sweep", segs, theta0=lo, n=n, rate=rate, timing=timing,
                         sampling=sampling, rng=rng)


# --- static designs (held poses, jumps between them) ----------------------------------------

def _static(name, poses, counts, rng, timing, rate):
    theta = np.repeat(poses, counts).astype(float)
    n = theta.size
    jumps = np.flatnonzero(np.diff(theta) != 0) + 1
    dirs = np.sign(np.diff(theta)[jumps - 1])
    last = np.zeros(n)
    for j, d in zip(jumps, dirs, strict=True):
        last[j:] = d
    t = np.arange(n) / rate if timing in ("t", "rate") else None
    stop_times = jumps / rate if t is not None else jumps.astype(float)
    return Motion(name, theta, np.zeros(n), np.zeros(n), t, timing,
                  rate if timing == "rate" else None, stop_times, dirs, last)


def random_poses(rng, n, timing="none", rate=50.0):
    """18–30 poses at random angles over two turns (−π … 3π), in random order, unequal
    numbers of samples per pose."""
    k = int(rng.integers(18, 31))
    poses = rng.uniform(-np.pi, 3 * np.pi, k)
    w = rng.uniform(0.5, 1.5, k)
    counts = np.floor(w / w.sum() * n).astype(int)
    counts[: n - counts.sum()] += 1
    return _static("random_poses", poses, counts, rng, timing, rate)


def repeated_poses(rng, n, timing="none", rate=50.0):
    """Five poses (0°, 72°, …) visited eight times each in shuffled order (no pose twice in a
    row), a few seconds each."""
    base = np.arange(5) * 2 * np.pi / 5 + rng.uniform(0, 0.3)
    order = []
    while len(order) < 40:
        order = list(rng.permutation(np.repeat(np.arange(5), 8)))
        if any(a == b for a, b in zip(order, order[1:], strict=False)):
            order = []
    counts = np.full(40, n // 40)
    counts[: n - counts.sum()] += 1
    return _static("repeated_poses", base[order], counts, rng, timing, rate)


def partial_poses(rng, n, timing="none", rate=50.0):
    """Nine unevenly spaced poses inside [−60°, 200°], visited up, down and up again."""
    lo, hi = PARTIAL
    poses = np.sort(rng.uniform(lo, hi, 9))
    poses[0], poses[-1] = lo, hi
    seq = np.concatenate([poses, poses[::-1][1:], poses[1:]])
    counts = np.full(seq.size, n // seq.size)
    counts[: n - counts.sum()] += 1
    return _static("partial_poses", seq, counts, rng, timing, rate)


DESIGNS: dict[str, Callable[..., Motion]] = {
    "backforth_dwell": backforth_dwell,
    "slow_fast_turns": slow_fast_turns,
    "negative_turns": lambda rng, n, **kw: slow_fast_turns(rng, n, sign=-1.0, **kw),
    "stop_and_go": stop_and_go,
    "growing_rock": growing_rock,
    "partial_sweep": partial_sweep,
    "random_poses": random_poses,
    "repeated_poses": repeated_poses,
    "partial_poses": partial_poses,
}
"""Name → builder ``(rng, n, **options) -> Motion``."""
