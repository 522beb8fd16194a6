"""Static inertial logs with known noise (package docstring), and their exact Allan curves.

A reading ``y_k`` (sampled every τ0 = 1/fs s; unit u: m/s² for an accelerometer, rad/s for a
gyro) is the sum of independent components. For each, the *true* overlapping Allan variance at
τ = m·τ0 — the expectation of ``s(m) = (1/2M) Σ_k (ȳ_{k+m} − ȳ_k)²``, ȳ the mean of m samples,
M = n − 2m + 1 — is given exactly for the discrete process:

=================  ============================================  ==================================
component          how it is made                                true Allan variance AVAR(m)
=================  ============================================  ==================================
white              ``σ_w·w_k``                                   ``σ_w²/m``            (= N²/τ)
Δv quantization    ``(D_k − D_{k−1})/τ0``, ``D_k = Δ·round(V_k/Δ)``  ``3Q²/τ²``, Q = Δ/√12
                   the integrated output V_k = τ0·Σ_{j≤k} y_j
                   (of the other components) counted in steps Δ
flicker (1/f)      sum of J AR(1) processes, correlation times   Σ_j ``AR1(m; σ_j², φ_j)`` ≈
                   T_j log-spaced by r (3 per decade), each of   ``(2 ln 2/π)·B²`` (flat, 0.664·B)
                   variance ``σ_j² = B² ln(r)/π``                between 3·T_1 and T_J/3
Gauss–Markov       one AR(1): ``x_k = φx_{k−1} + σ√(1−φ²)w_k``,    ``AR1(m; σ², φ)``
                   ``φ = e^{−τ0/T_c}``, stationary start
random walk        ``K·√τ0·Σ_{j≤k} w_j``                          ``K²τ0·(2m² + 1)/(6m)`` (= K²τ/3
                                                                 for m ≫ 1)
thermal drift      ``A·(1 − e^{−t/T_th})``, deterministic (a       the overlapping Allan variance of
                   warm-up)                                      the path itself (no expectation)
reading lattice    each reading rounded to a step δ (an ADC's    ``(δ²/12)/m`` — white, part of N:
                   LSB), last                                    ``N_eff² = N² + δ²/(12·fs)`` when
                                                                 the noise spans a few steps
=================  ============================================  ==================================

with ``AR1(m; σ², φ) = σ²·[Var(ȳ_m) − Cov(ȳ_1, ȳ_2)]/σ²`` in closed form (unit-variance AR(1),
``R(k) = φ^|k|``)::

    m²·Var(ȳ_m)       = m + 2φ[m(1 − φ) − (1 − φ^m)]/(1 − φ)²
    m²·Cov(ȳ_1, ȳ_2)  = φ(1 − φ^m)²/(1 − φ)²
    AVAR(m)           = Var(ȳ_m) − Cov(ȳ_1, ȳ_2)      (= ½E(ȳ_2 − ȳ_1)²)

Why the flicker bank is 1/f: an AR(1) of variance σ² and correlation time T has the one-sided
spectrum ``4σ²T/(1 + (2πfT)²)``; summed over T log-spaced by r, ``Σ_j ≈ (1/ln r)∫ 4σ²T/(1 +
(2πfT)²) d ln T = σ²/(f·ln r)``, so ``σ_j² = h_{-1}·ln r`` gives ``S(f) = h_{-1}/f`` and, with
``h_{-1} = B²/π`` (IEEE Std 952 C.3), the Allan floor ``2 ln2·h_{-1} = (2 ln 2/π)B²``. The
bank's own curve is the exact sum (``true_avar``), not the idealized floor.

Why the Δv quantization is ``3Q²/τ²``: the counted output differs from the true one by the
rounding error ``e_k = D_k − V_k``, uniform on ±Δ/2 and white when the increments dither the
counter (the per-sample increment's noise is at least about a step), variance Δ²/12 = Q²; the
rate is ``y_k + (e_k − e_{k−1})/τ0`` and the mean of m rates carries ``(e_{k+m} − e_k)/(mτ0)``,
so ``AVAR = ½·E[(e_{k+2m} − 2e_{k+m} + e_k)²]/(mτ0)² = 3Q²/τ²`` (IEEE Std 952 C.1). When the
other components are too quiet to dither the counter this is not true; :func:`static_log`
refuses such a spec.

Everything is drawn from the ``numpy.random.Generator`` given (same seed, same bytes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

PER_DECADE = 3
"""AR(1) processes per decade of correlation time in the flicker bank."""


@dataclass(frozen=True)
class NoiseSpec:
    """The true noise of one axis (unit u of the readings: m/s² or rad/s).

    rate : fs, Hz.
    white : N, u/√Hz (per-sample σ_w = N·√fs).
    flicker : B, u (Allan floor 0.664·B).
    walk : K, u/√s.
    quant_step : Δ, u·s — the step of the integrated output (Q = Δ/√12), or 0.
    gm_sigma, gm_tc : σ (u) and T_c (s) of a Gauss–Markov component, or 0.
    drift : A (u) of the warm-up ``A·(1 − e^{−t/T_th})``, or 0; drift_tc : T_th, s.
    flicker_band : (T_1, T_J) s, the correlation times the flicker bank spans; default
        (τ0/2, 20 × the record length).
    read_step : δ, u — the readings' lattice step (an ADC's LSB), or 0.
    """

    rate: float
    white: float
    flicker: float = 0.0
    walk: float = 0.0
    quant_step: float = 0.0
    gm_sigma: float = 0.0
    gm_tc: float = 1.0
    drift: float = 0.0
    drift_tc: float = 1.0
    flicker_band: tuple[float, float] | None = None
    read_step: float = 0.0

    @property
    def white_eff(self) -> float:
        """N with the reading lattice's white part: ``√(N² + δ²/(12·fs))`` (u/√Hz)."""
        return math.sqrt(self.white ** 2 + self.read_step ** 2 / (12.0 * self.rate))

    @property
    def q(self) -> float:
        """The quantization noise coefficient Q = Δ/√12 (u·s)."""
        return self.quant_step / math.sqrt(12.0)

    def band(self, n: int) -> tuple[float, float]:
        return self.flicker_band or (0.5 / self.rate, 20.0 * n / self.rate)

    def bank(self, n: int) -> tuple[np.ndarray, float]:
        """(correlation times T_j s, the per-component variance σ_j² u²) of the flicker."""
        t1, tj = self.band(n)
        count = int(math.ceil(PER_DECADE * math.log10(tj / t1))) + 1
        times = np.geomspace(t1, tj, count)
        r = (tj / t1) ** (1.0 / (count - 1))
        return times, self.flicker ** 2 * math.log(r) / math.pi


def _ar1(rng: np.random.Generator, n: int, sigma: float, tc: float, rate: float
         ) -> np.ndarray:
    phi = math.exp(-1.0 / (tc * rate))
    w = rng.standard_normal(n)
    w[1:] *= math.sqrt(1.0 - phi * phi)  # x_0 from the stationary law N(0, σ²)
    return sigma * lfilter([1.0], [1.0, -phi], w)


def static_log(spec: NoiseSpec, n: int, rng: np.random.Generator, level: float = 0.0
               ) -> tuple[np.ndarray, np.ndarray]:
    """(y (n,), drift (n,)): the readings of one held axis around ``level`` (u) and the drift
    path inside them (module table)."""
    tau0 = 1.0 / spec.rate
    y = spec.white * math.sqrt(spec.rate) * rng.standard_normal(n)
    if spec.flicker > 0:
        times, var = spec.bank(n)
        for t in times:
            y += _ar1(rng, n, math.sqrt(var), t, spec.rate)
    if spec.gm_sigma > 0:
        y += _ar1(rng, n, spec.gm_sigma, spec.gm_tc, spec.rate)
    if spec.walk > 0:
        y += spec.walk * math.sqrt(tau0) * np.cumsum(rng.standard_normal(n))
    t = np.arange(n) * tau0
    drift = spec.drift * (1.0 - np.exp(-t / spec.drift_tc)) if spec.drift else np.zeros(n)
    y = y + drift + level
    if spec.quant_step > 0:
        step = spec.quant_step
        if spec.white * math.sqrt(spec.rate) * tau0 < 0.5 * step:
            raise ValueError("the white noise does not dither the Δv counter (per-sample "
                             "increment σ_w·τ0 below half a step): the quantization noise would "
                             "not be 3Q²/τ²")
        v = np.concatenate([[0.0], np.cumsum(y) * tau0])
        counted = step * np.round(v / step)
        y = np.diff(counted) / tau0
    if spec.read_step > 0:
        y = spec.read_step * np.round(y / spec.read_step)
    return y, drift


def ar1_avar(m: np.ndarray, sigma2: float, phi: float) -> np.ndarray:
    """Exact AVAR(m) of a stationary AR(1) of variance σ² and coefficient φ (module
    docstring)."""
    m = np.asarray(m, dtype=float)
    g = 1.0 - phi
    pm = phi ** m
    var = (m + 2.0 * phi * (m * g - (1.0 - pm)) / g ** 2) / m ** 2
    cov = phi * (1.0 - pm) ** 2 / g ** 2 / m ** 2
    return sigma2 * (var - cov)


def path_avar(x: np.ndarray, m: np.ndarray) -> np.ndarray:
    """The overlapping Allan variance of one path ``x`` at each m (its own estimate, for the
    deterministic drift)."""
    c = np.concatenate([[0.0], np.cumsum(np.asarray(x, dtype=float))])
    out = []
    for mm in np.asarray(m, dtype=int):
        means = (c[mm:] - c[:-mm]) / mm
        d = means[mm:] - means[:-mm]
        out.append(0.5 * float(np.mean(d * d)))
    return np.array(out)


def true_avar(spec: NoiseSpec, n: int, m: np.ndarray, drift: np.ndarray | None = None
              ) -> dict[str, np.ndarray]:
    """The true overlapping Allan variance of each component at the octaves ``m`` of an
    n-sample log (module table; u²), and their sum under ``"total"``. The drift's needs its
    path (``static_log``'s second output)."""
    m = np.asarray(m, dtype=float)
    tau0 = 1.0 / spec.rate
    out = {"white": spec.white_eff ** 2 * spec.rate / m,
           "quantization": 3.0 * spec.q ** 2 / (m * tau0) ** 2,
           "walk": spec.walk ** 2 * tau0 * (2.0 * m ** 2 + 1.0) / (6.0 * m)}
    flick = np.zeros_like(m)
    if spec.flicker > 0:
        times, var = spec.bank(n)
        for t in times:
            flick += ar1_avar(m, var, math.exp(-tau0 / t))
    out["flicker"] = flick
    out["gauss_markov"] = (ar1_avar(m, spec.gm_sigma ** 2, math.exp(-tau0 / spec.gm_tc))
                           if spec.gm_sigma > 0 else np.zeros_like(m))
    out["drift"] = (path_avar(drift, m) if drift is not None and spec.drift
                    else np.zeros_like(m))
    out["total"] = sum(v for v in out.values())
    return out


def octaves(n: int) -> np.ndarray:
    """m = 1, 2, 4, … ≤ n/4 (the octave grid)."""
    return 2 ** np.arange(int(math.log2(max(n // 4, 1))) + 1)


__all__ = ["PER_DECADE", "NoiseSpec", "ar1_avar", "octaves", "path_avar", "static_log",
           "true_avar"]
