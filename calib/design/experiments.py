"""Candidate experiments: a θ(t) design × N × sweep rate, built from numbers (no MuJoCo).

Designs (the vocabulary of ``bench.tilt.ThetaDesign`` / ``SweepProfile``), one full turn
``span = 2π`` rad, sweep rate ``ω̄`` (rad/s, the mean rate), duration ``T``:

=========== ====================================================== ============ ===========
design      θ (rad)                                                 T (s)        timed
=========== ====================================================== ============ ===========
uniform     static, ``linspace(0, 2π, N)`` (the course design)      2π/ω̄         no
held        static, 8 positions over [0, 2π), N/8 samples each      2π/ω̄         no
sweep       constant rate, ``θ = 2π·t/T``                           2π/ω̄         yes
reversal    up then down, ``θ = 2π·(1 - |2t/T - 1|)``               4π/ω̄         yes
accel       rate growing from 0, ``θ = 2π·(t/T)²``                  2π/ω̄         yes
=========== ====================================================== ============ ===========

Timed designs are sampled uniformly, ``t_k = k·T/(N - 1)``; static designs carry no sample
times (as the course's ``ensayo.mat``), so the effects that need timing are not testable
there and a drift is per sample (the nominal period ``T/(N - 1)`` converts it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * np.pi
HELD_POSITIONS = 8
DESIGNS: tuple[str, ...] = ("uniform", "held", "sweep", "reversal", "accel")
"""Design names, in the order of the module table."""
TIMED: frozenset[str] = frozenset({"sweep", "reversal", "accel"})
RATE_RANGE = (1e-6, 1e3)
"""Mean sweep rates a design may have, rad/s: from one turn in 73 days to 160 turns a second
(beyond, the sample period underflows the timing effects' arithmetic)."""


@dataclass(frozen=True)
class Experiment:
    """One candidate experiment.

    design : a name of :data:`DESIGNS`.  n : samples N.  rate : mean sweep rate ω̄, rad/s
    (static designs: the pace of the positions, which sets the duration only).
    """

    design: str
    n: int
    rate: float

    def __post_init__(self) -> None:
        if self.design not in DESIGNS:
            raise ValueError(f"unknown design {self.design!r}; choose from {', '.join(DESIGNS)}")
        if int(self.n) != self.n or self.n < 16:
            raise ValueError(f"N must be an integer >= 16, got {self.n}")
        if self.design == "held" and self.n < 2 * HELD_POSITIONS:
            raise ValueError(f"held needs N >= {2 * HELD_POSITIONS}")
        lo, hi = RATE_RANGE
        if not (np.isfinite(self.rate) and lo <= self.rate <= hi):
            raise ValueError(f"sweep rate must be within [{lo:g}, {hi:g}] rad/s, got {self.rate}")

    @property
    def timed(self) -> bool:
        """Whether the run carries sample times (sweeps)."""
        return self.design in TIMED

    @property
    def duration(self) -> float:
        """T, s: one turn at the mean rate (the reversal goes there and back)."""
        return (2.0 if self.design == "reversal" else 1.0) * TWO_PI / self.rate

    @property
    def period(self) -> float:
        """Sample period T/(N - 1), s (nominal for static designs)."""
        return self.duration / (self.n - 1)

    @property
    def label(self) -> str:
        return f"{self.design} N={self.n} ω̄={self.rate:g} rad/s"

    def theta(self) -> np.ndarray:
        """θ (N,) rad, in time order."""
        n = int(self.n)
        if self.design == "uniform":
            return np.linspace(0.0, TWO_PI, n)
        if self.design == "held":
            per = n // HELD_POSITIONS
            pos = np.linspace(0.0, TWO_PI, HELD_POSITIONS, endpoint=False)
            th = np.repeat(pos, per)
            return np.concatenate([th, np.full(n - th.size, pos[-1])])
        u = np.linspace(0.0, 1.0, n)
        if self.design == "sweep":
            return TWO_PI * u
        if self.design == "reversal":
            return TWO_PI * (1.0 - np.abs(2.0 * u - 1.0))
        return TWO_PI * u**2  # accel

    def times(self) -> np.ndarray | None:
        """t (N,) s for timed designs, else None."""
        return np.linspace(0.0, self.duration, int(self.n)) if self.timed else None

    def to_dict(self) -> dict:
        return {"design": self.design, "n": int(self.n), "rate": float(self.rate),
                "duration": self.duration, "timed": self.timed}
