"""Noise characterization of a static accelerometer log: overlapping Allan deviation per axis,
the fitted noise terms with intervals, the quantization step (``tiltbench noise``).

**Allan deviation.** ``allantools.oadev`` (rate-like data, ``data_type="freq"``) on the octave
grid τ = m/fs, m = 1, 2, 4, …, ≤ N/4. Each point gets a χ² confidence interval from its
equivalent degrees of freedom (``allantools.edf_greenhall``, overlapping estimator), with the
power-law noise type α ∈ {0 white, −1 flicker, −2 random walk} read from the local slope
μ = d log ADEV / d log τ of the fitted model (α = −2μ − 1 rounded, IEEE Std 1139; the fitted
model's slope, because the data's own slope between two noisy points is itself noisy).

**Noise terms** (IEEE Std 952-1997 Annex C and IEEE Std 1293-2018 Annex: the readings of the
Allan deviation plot as a fit). The expected Allan variance is the sum of the three terms,
``AVAR(τ) = N²/τ + (2 ln2/π)·B² + K²·τ/3`` for m ≫ 1 — exactly, at every τ,
``E s(τ_i) = X_i·θ`` with θ = (N²·fs, B², K²/fs) and X from :mod:`calib.noise.allan_model`:

=====================  ===============  =======  ===========================================
term                   unit             slope    IEEE reading it replaces
=====================  ===============  =======  ===========================================
white_noise_density N  (m/s²)/√Hz       −½       −½ line at τ = 1 s
bias_instability B     m/s²             0        flat minimum / 0.664
rate_random_walk K     m/s²/√s          +½       +½ line at τ = 3 s
=====================  ===============  =======  ===========================================

θ is estimated by generalized least squares on the octave Allan variances with their full
covariance ``V(θ)`` (adjacent octaves of the overlapping estimator correlate by 0.5–0.7;
:func:`calib.noise.allan_model.allan_moments`), iterated so that V is evaluated at the fit
(whitened by Cholesky, solved by QR; no normal matrix is inverted).

**Intervals** (coverage claimed: ``level``, two-sided, per term; checked over ≥ 200 simulated
logs in ``tests/test_allan.py``). A Wald interval θ̂ ± z·se(θ̂) undercovers the random-walk
term (its information sits in the few longest τ, whose estimates are skewed χ² with 2–5
degrees of freedom; measured 0.82 at 0.95). The interval is instead the set of values θ_0 that
a score-type test accepts: with θ_a fixed at θ_0 the other two terms are refitted, the
covariance is evaluated *under that hypothesis* V(θ_0, θ̂_rest), and θ_0 is kept while
``|θ̂_a(V) − θ_0| / se_a(V) ≤ z_{(1+level)/2}`` (the construction of Wilson's interval for a
proportion; it is wider upwards where the data would be noisier). A negative estimate is taken
as 0 in this test, so the interval is then [0, upper] (it only accepts more values: the
coverage cannot drop). Bounds are mapped to the term by the monotone ``√`` of the table; a
term's interval always contains its estimate and never goes below 0.

**Resolved or not.** A term other than white noise is *resolved* when the same test rejects
θ_a = 0 one-sided at ``alpha`` (default 0.05): z_0 = θ̂_a(V_0)/se_a(V_0) > z_{1-α}, V_0 the
covariance with that term absent. An unresolved term is reported as "not resolved" with the
upper end of its interval (the upper bound at ``level``), not as a number: on a log with
white noise only the rate of false "resolved" is α per term (tested).

**Adequacy.** The GLS residual ``χ² = rᵀV⁻¹r`` with n_τ − 3 degrees of freedom tests whether
the three-term model describes the curve (a low-pass filter at small τ, temperature drift or a
periodic disturbance at large τ make it fail); p < 0.01 is reported as lack of fit, and the
τ range can be restricted (``tau_range``).

**Long logs** (more than :data:`MAX_FIT_SAMPLES`) are averaged in blocks of 2^k samples before
the fit, so its cost stays bounded; τ then starts at 2^k/fs.

**Quantization.** Readings on a lattice (every distinct value a multiple of one step from the
smallest) give the step; it is reported, and its white contribution Δ²/12 is part of N.

The checks of the log before (sample rate, the table did not move, quantization step):
:mod:`calib.logs.static_log`, re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from scipy import stats

from calib.input_rules import DataError
from calib.logs.static_log import check_static, quantization_step, sample_rate_of
from calib.noise.allan_model import (
    FLICKER_FLOOR,
    TERM_NAMES,
    allan_moments,
    avar_covariance,
    terms_from_theta,
)
from calib.results import ResultMixin, readonly

TERM_UNITS = {"white_noise_density": "(m/s^2)/sqrt(Hz)", "bias_instability": "m/s^2",
              "rate_random_walk": "m/s^2/sqrt(s)"}
UNITS = {
    "sample_rate": "Hz", "n": "count", "level": "1", "alpha": "1", "duration": "s",
    "taus": "s", "adev": "m/s^2", "adev_ci": "m/s^2", "model_adev": "m/s^2", "edf": "1",
    "noise_alpha": "1 (0 white, -1 flicker, -2 random walk; frequency data)",
    **{f"terms.{k}.{f}": u for k, u in TERM_UNITS.items()
       for f in ("value", "interval", "upper_bound")},
    "terms.*.tau_range": "s", "terms.*.z": "1", "terms.*.p_value": "1",
    "theta": "white (m/s^2)^2 per sample, flicker (m/s^2)^2, random walk (m/s^2)^2 per sample",
    "chi2": "1", "dof": "count", "p_fit": "1", "quantization_step": "m/s^2",
    "mean": "m/s^2", "std": "m/s^2", "block": "count", "static_check.window": "s",
    "static_check.shift": "m/s^2", "static_check.var_ratio": "1",
    "static_check.max_shift": "m/s^2", "static_check.max_var_ratio": "1",
    "static_check.max_rate": "rad/s", "static_check.max_gyro_rate": "rad/s",
    "static_check.shift_noise_floor": "m/s^2", "static_check.excess_std": "m/s^2",
    "static_check.excess_limit": "m/s^2",
}
MIN_SAMPLES = 64
"""Shortest log: octaves m = 1 … N/4 must give at least 5 Allan points (3 terms + 2 dof)."""
MAX_FIT_SAMPLES = 2 ** 17
"""Longer logs are averaged in blocks of r = 2^k samples (τ from r/fs) before the fit: the
covariance of the Allan variances costs an FFT of the record per pair of τ (seconds at 2^17
samples); the white density, the flicker floor and the walk are unchanged by block means."""
LACK_OF_FIT_P = 0.01
"""p below which the three-term model is said not to describe the Allan curve."""


# --- the Allan deviation ------------------------------------------------------------------


def octave_factors(n: int, rate: float, tau_range: tuple[float, float] | None = None
                   ) -> tuple[int, ...]:
    """Averaging factors m = 1, 2, 4, … ≤ n/4 (allantools' octave grid), within ``tau_range``
    (s) if given."""
    ms = [1 << k for k in range(int(math.log2(max(n // 4, 1))) + 1)]
    if tau_range is not None:
        lo, hi = tau_range
        ms = [m for m in ms if lo * (1 - 1e-9) <= m / rate <= hi * (1 + 1e-9)]
    return tuple(ms)


def overlapping_adev(y: np.ndarray, rate: float, ms: tuple[int, ...]
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``allantools.oadev`` of the rate-like readings ``y`` (m/s²) at τ = m/rate: (τ s, ADEV
    m/s², number of overlapping differences)."""
    import allantools

    taus, adev, _, n = allantools.oadev(np.asarray(y, dtype=float), rate=float(rate),
                                        data_type="freq", taus=np.asarray(ms) / rate)
    if taus.size != len(ms):
        raise DataError(f"allantools returned {taus.size} of {len(ms)} octave points")
    return np.asarray(taus), np.asarray(adev), np.asarray(n)


def adev_intervals(adev: np.ndarray, ms: tuple[int, ...], n: int, slopes: np.ndarray,
                   level: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """χ² intervals of each ADEV point from its EDF (module docstring): (lo, hi, edf, α)."""
    import allantools

    alpha = np.clip(np.rint(-2.0 * slopes - 1.0), -2, 0).astype(int)
    edf = np.array([_edf(int(a), int(m), int(n) + 1) for a, m in zip(alpha, ms, strict=True)],
                   dtype=float)
    lo, hi = np.empty_like(adev), np.empty_like(adev)
    for i, (dev, e) in enumerate(zip(adev, edf, strict=True)):
        lo[i], hi[i] = allantools.confidence_interval(float(dev), float(e), ci=level)
    return lo, hi, edf, alpha


@lru_cache(maxsize=4096)
def _edf(alpha: int, m: int, n: int) -> float:
    """Greenhall's EDF of the overlapping Allan variance (a pure function of its integers,
    cached: its series costs ~2 ms per point and a Monte Carlo repeats the same ones)."""
    import allantools

    return float(allantools.edf_greenhall(alpha=alpha, d=2, m=m, N=n, overlapping=True,
                                          modified=False))


# --- the GLS fit and its score intervals --------------------------------------------------


def _gls(s: np.ndarray, design: np.ndarray, cov: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Batched GLS: s (n,) or (G, n), design (n, p), cov (G, n, n) → (θ (G, p),
    Cov θ (G, p, p), χ² (G,)).

    Whitened by Cholesky, columns equilibrated, solved by QR: ``R θ = Qᵀ s_w``,
    ``Cov θ = R⁻¹R⁻ᵀ`` (R is p×p triangular; no normal matrix).
    """
    chol = np.linalg.cholesky(cov)
    xw = np.linalg.solve(chol, np.broadcast_to(design, cov.shape[:1] + design.shape))
    sw = np.linalg.solve(chol, np.broadcast_to(s, cov.shape[:2])[..., None])[..., 0]
    scale = np.linalg.norm(xw, axis=1)
    q, r = np.linalg.qr(xw / scale[:, None, :])
    qs = np.einsum("gnp,gn->gp", q, sw)
    theta = np.linalg.solve(r, qs[..., None])[..., 0] / scale
    ri = np.linalg.inv(r)
    cov_theta = ri @ np.swapaxes(ri, 1, 2) / (scale[:, :, None] * scale[:, None, :])
    res = sw - np.einsum("gnp,gp->gn", xw, theta)
    return theta, cov_theta, np.einsum("gn,gn->g", res, res)


def _fit_theta(s, design, tensor, floor, iterations=6):
    """IRLS: θ with V evaluated at the previous θ (clipped at 0; white at least ``floor``)."""
    theta = np.array([s[0] / design[0, 0], 0.0, 0.0])
    for _ in range(iterations):
        v = avar_covariance(tensor, _valid(theta, floor))[None]
        est, cov, chi2 = _gls(s, design, v)
        theta = est[0]
    return theta, cov[0], float(chi2[0])


def _valid(theta: np.ndarray, floor: float) -> np.ndarray:
    t = np.maximum(theta, 0.0)
    t[..., 0] = np.maximum(t[..., 0], floor)
    return t


def _score_z(s, design, tensor, a: int, values: np.ndarray, start: np.ndarray, floor: float,
             iterations: int = 3, clip: bool = False) -> np.ndarray:
    """z(θ_0) = (θ̂_a(V) − θ_0)/se_a(V), V under the hypothesis θ_a = θ_0 with the other terms
    refitted (module docstring), for every θ_0 in ``values`` at once. ``clip``: θ̂_a(V) taken
    as max(θ̂_a(V), 0) (for the interval: a negative estimate then gives [0, upper] with
    upper > 0, where the unclipped test would accept no θ_0 ≥ 0 at all; it only ever accepts
    more values, so the coverage does not drop)."""
    theta = np.tile(start, (values.size, 1))
    theta[:, a] = values
    free = [b for b in range(3) if b != a]
    for _ in range(iterations):
        v = np.einsum("ga,ijab,gb->gij", _valid(theta, floor), tensor, _valid(theta, floor))
        sub = s[None, :] - design[:, a][None, :] * values[:, None]
        theta[:, free] = _gls(sub, design[:, free], v)[0]
    v = np.einsum("ga,ijab,gb->gij", _valid(theta, floor), tensor, _valid(theta, floor))
    est, cov, _ = _gls(s, design, v)
    top = np.maximum(est[:, a], 0.0) if clip else est[:, a]
    return (top - values) / np.sqrt(cov[:, a, a])


def _crossing(s, design, tensor, a, start, floor, target, lo, hi, rising_side):
    """θ_0 in [lo, hi] where z(θ_0) = target, z decreasing in θ_0 (grid, then bisection)."""
    for _ in range(40):
        z_hi = _score_z(s, design, tensor, a, np.array([hi]), start, floor, clip=True)[0]
        if z_hi < target or not rising_side:
            break
        lo, hi = hi, hi * 2.0 + 1e-300
    grid = np.linspace(lo, hi, 9)
    for _ in range(3):  # bracket / 8³: far finer than the interval's own sampling error
        z = _score_z(s, design, tensor, a, grid, start, floor, clip=True)
        above = np.nonzero(z >= target)[0]
        if above.size == 0:
            return float(grid[0])
        k = int(above[-1])
        if k == grid.size - 1:
            return float(grid[-1])
        grid = np.linspace(grid[k], grid[k + 1], 9)
    return float(0.5 * (grid[0] + grid[-1]))


@dataclass(frozen=True, eq=False)
class TermFit(ResultMixin):
    """One fitted noise term of one axis (module docstring).

    name : "white_noise_density", "bias_instability" or "rate_random_walk".
    resolved : the log resolves the term (score test of zero rejected at ``alpha``).
    value : estimate in the term's unit (:data:`TERM_UNITS`), or None when not resolved.
    interval : (lo, hi) at ``level``, same unit; lo = 0 when zero is not excluded.
    upper_bound : hi — what an unresolved term is reported as.
    tau_range : (τ_first, τ_last), s — the τ where this term is the largest of the three
        (the fit's whole range when it is nowhere).
    z, p_value : score statistic of "term = 0" and its one-sided p.
    """

    name: str
    resolved: bool
    value: float | None
    interval: tuple[float, float]
    upper_bound: float
    tau_range: tuple[float, float]
    z: float
    p_value: float
    level: float

    _TITLE = "Noise term"
    _UNITS = "see TERM_UNITS"

    @property
    def unit(self) -> str:
        return TERM_UNITS[self.name]

    def summary(self) -> str:
        lo, hi = self.interval
        t0, t1 = self.tau_range
        where = f"τ {t0:.3g}–{t1:.3g} s"
        if not self.resolved:
            return (f"{self.name}: not resolved (< {self.upper_bound:.3g} {self.unit} at "
                    f"{self.level:.1%}; z = {self.z:.2f}, p = {self.p_value:.2g}; {where})")
        return (f"{self.name}: {self.value:.4g} {self.unit} [{lo:.4g}, {hi:.4g}] at "
                f"{self.level:.1%} ({where}; z = {self.z:.1f})")

    def to_dict(self) -> dict:
        return {"name": self.name, "resolved": bool(self.resolved),
                "value": None if self.value is None else float(self.value),
                "interval": [float(v) for v in self.interval],
                "upper_bound": float(self.upper_bound),
                "tau_range": [float(v) for v in self.tau_range], "z": float(self.z),
                "p_value": float(self.p_value), "level": float(self.level),
                "unit": self.unit}

    @classmethod
    def from_dict(cls, d: dict) -> TermFit:
        return cls(name=d["name"], resolved=bool(d["resolved"]),
                   value=None if d["value"] is None else float(d["value"]),
                   interval=tuple(float(v) for v in d["interval"]),
                   upper_bound=float(d["upper_bound"]),
                   tau_range=tuple(float(v) for v in d["tau_range"]), z=float(d["z"]),
                   p_value=float(d["p_value"]), level=float(d["level"]))

    def to_noise_term(self):
        """The profile's :class:`calib.noise.sensor_profile.NoiseTerm`, or None when not
        resolved."""
        from calib.noise.sensor_profile import NoiseTerm

        if not self.resolved:
            return None
        return NoiseTerm(value=float(self.value), interval=tuple(self.interval),
                         tau_range=tuple(self.tau_range), level=self.level)


@dataclass(frozen=True, eq=False)
class AxisNoise(ResultMixin):
    """Allan deviation and noise terms of one axis.

    taus (k,) s; adev (k,) m/s²; adev_ci (k, 2) m/s² at ``level`` (EDF χ²); edf (k,);
    noise_alpha (k,) power-law type used for the EDF; model_adev (k,) m/s² of the fit;
    theta (3,) and cov (3, 3): the GLS estimate and covariance (units in :data:`UNITS`);
    terms: the three :class:`TermFit`; chi2, dof, p_fit: the model's adequacy;
    quantization_step m/s² or None; mean, std m/s² of the readings; n samples.
    """

    axis: str
    taus: np.ndarray
    adev: np.ndarray
    adev_ci: np.ndarray
    edf: np.ndarray
    noise_alpha: np.ndarray
    model_adev: np.ndarray
    theta: np.ndarray
    cov: np.ndarray
    terms: tuple[TermFit, TermFit, TermFit]
    chi2: float
    dof: int
    p_fit: float
    quantization_step: float | None
    mean: float
    std: float
    n: int

    _TITLE = "Allan deviation of one axis"
    _UNITS = "τ s; ADEV m/s²; terms in TERM_UNITS"

    def __post_init__(self) -> None:
        for name in ("taus", "adev", "adev_ci", "edf", "model_adev", "theta", "cov"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "noise_alpha", readonly(self.noise_alpha, int))
        object.__setattr__(self, "terms", tuple(self.terms))

    def term(self, name: str) -> TermFit:
        return self.terms[TERM_NAMES.index(name)]

    @property
    def lack_of_fit(self) -> bool:
        return self.p_fit < LACK_OF_FIT_P

    def summary(self) -> str:
        lines = [f"axis {self.axis}: {self.n} samples, mean {self.mean:.5g} m/s², std "
                 f"{self.std:.4g} m/s², τ {self.taus[0]:.3g}–{self.taus[-1]:.3g} s "
                 f"({self.taus.size} octaves)"]
        lines += ["  " + t.summary() for t in self.terms]
        q = self.quantization_step
        lines.append("  quantization step: " + ("none seen (readings not on a lattice)"
                                                if q is None else f"{q:.4g} m/s²"))
        if q is not None and self.std < q:
            lines.append(f"  note: the readings' std ({self.std:.3g} m/s²) is below the "
                         "quantization step: the Allan deviation measures the quantizer more "
                         "than the sensor")
        fit = (f"  model fit: χ² = {self.chi2:.2f} on {self.dof} dof (p = {self.p_fit:.2g})")
        if self.lack_of_fit:
            fit += (" — the white + bias-instability + random-walk model misses something "
                    "(a filter at small τ, drift or a periodic disturbance at large τ): read "
                    "the figure, or restrict --tau-range")
        lines.append(fit)
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"axis": self.axis, "taus": self.taus.tolist(), "adev": self.adev.tolist(),
                "adev_ci": self.adev_ci.tolist(), "edf": self.edf.tolist(),
                "noise_alpha": self.noise_alpha.tolist(),
                "model_adev": self.model_adev.tolist(), "theta": self.theta.tolist(),
                "cov": self.cov.tolist(), "terms": {t.name: t.to_dict() for t in self.terms},
                "chi2": float(self.chi2), "dof": int(self.dof), "p_fit": float(self.p_fit),
                "lack_of_fit": bool(self.lack_of_fit),
                "quantization_step": (None if self.quantization_step is None
                                      else float(self.quantization_step)),
                "mean": float(self.mean), "std": float(self.std), "n": int(self.n)}

    @classmethod
    def from_dict(cls, d: dict) -> AxisNoise:
        q = d.get("quantization_step")
        return cls(axis=d["axis"], taus=d["taus"], adev=d["adev"], adev_ci=d["adev_ci"],
                   edf=d["edf"], noise_alpha=d["noise_alpha"], model_adev=d["model_adev"],
                   theta=d["theta"], cov=d["cov"],
                   terms=tuple(TermFit.from_dict(d["terms"][k]) for k in TERM_NAMES),
                   chi2=float(d["chi2"]), dof=int(d["dof"]), p_fit=float(d["p_fit"]),
                   quantization_step=None if q is None else float(q), mean=float(d["mean"]),
                   std=float(d["std"]), n=int(d["n"]))


@dataclass(frozen=True, eq=False)
class NoiseCharacterization(ResultMixin):
    """The result of :func:`characterize_noise`: per-axis :class:`AxisNoise`, the settings,
    the static check and the source."""

    sample_rate: float
    n: int
    level: float
    alpha: float
    axes: tuple[AxisNoise, ...]
    static_check: dict[str, Any] = field(default_factory=dict)
    source: dict[str, str] | None = None
    block: int = 1

    _TITLE = "Noise characterization (Allan deviation)"
    _UNITS = "Hz, s, m/s²; terms in (m/s²)/√Hz, m/s², m/s²/√s"

    def __post_init__(self) -> None:
        object.__setattr__(self, "axes", tuple(self.axes))

    @property
    def duration(self) -> float:
        return self.n / self.sample_rate

    def axis(self, name: str) -> AxisNoise:
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(name)

    def summary(self) -> str:
        head = (f"noise: {self.n} samples at {self.sample_rate:g} Hz ({self.duration:.4g} s); "
                f"intervals at {self.level:.1%} (score-type, GLS on the octave Allan "
                f"variances); a term is resolved when zero is rejected at α = {self.alpha:g}")
        if self.block > 1:
            head += (f"\nlong log: averaged in blocks of {self.block} samples before the fit "
                     f"(τ from {self.block / self.sample_rate:g} s)")
        return "\n".join([head] + [a.summary() for a in self.axes])

    def to_dict(self) -> dict:
        return {"sample_rate": float(self.sample_rate), "n": int(self.n),
                "duration": float(self.duration), "level": float(self.level),
                "alpha": float(self.alpha), "axes": {a.axis: a.to_dict() for a in self.axes},
                "static_check": self.static_check, "source": self.source,
                "block": int(self.block), "units": UNITS}

    @classmethod
    def from_dict(cls, d: dict) -> NoiseCharacterization:
        return cls(sample_rate=float(d["sample_rate"]), n=int(d["n"]), level=float(d["level"]),
                   alpha=float(d["alpha"]),
                   axes=tuple(AxisNoise.from_dict(a) for a in d["axes"].values()),
                   static_check=d.get("static_check", {}), source=d.get("source"),
                   block=int(d.get("block", 1)))

    def to_profile(self, calibration: dict | None = None, tool_version: str = "unknown"):
        """The :class:`calib.noise.sensor_profile.SensorProfile` of this log: resolved terms as
        NoiseTerms, unresolved ones null (their upper bounds in ``extra``), the quantization
        step, the sample rate and ``calibration`` if given."""
        from calib.noise.sensor_profile import SensorProfile

        def per_axis(name):
            terms = tuple(a.term(name).to_noise_term() for a in self.axes)
            return None if all(t is None for t in terms) else terms

        bounds = {a.axis: {t.name: t.upper_bound for t in a.terms if not t.resolved}
                  for a in self.axes}
        qs = tuple(a.quantization_step for a in self.axes)
        return SensorProfile(
            sample_rate=self.sample_rate,
            white_noise_density=tuple(a.term("white_noise_density").to_noise_term()
                                      for a in self.axes),
            bias_instability=per_axis("bias_instability"),
            rate_random_walk=per_axis("rate_random_walk"),
            quantization_step=None if all(q is None for q in qs) else qs,
            calibration=calibration, source=self.source, tool_version=tool_version,
            axes=tuple(a.axis for a in self.axes),
            extra={"unresolved_upper_bounds": bounds, "level": self.level,
                   "alpha": self.alpha, "n": self.n,
                   "lack_of_fit": {a.axis: bool(a.lack_of_fit) for a in self.axes}})


def _term_ranges(taus: np.ndarray, design: np.ndarray, theta: np.ndarray):
    parts = design * np.maximum(theta, 0.0)
    top = np.argmax(parts, axis=1)
    out = []
    for a in range(3):
        idx = np.nonzero(top == a)[0]
        out.append((float(taus[0]), float(taus[-1])) if idx.size == 0
                   else (float(taus[idx[0]]), float(taus[idx[-1]])))
    return out


def fit_axis_noise(y: np.ndarray, rate: float, *, axis: str = "x", level: float = 0.683,
                   alpha: float = 0.05, tau_range: tuple[float, float] | None = None,
                   block: int = 1) -> AxisNoise:
    """Allan deviation and the three noise terms of one axis (module docstring).

    Parameters
    ----------
    y : (N,) readings of a static log, m/s², evenly spaced at ``rate`` Hz.
    level : two-sided level of the intervals (ADEV points and terms).
    alpha : one-sided significance for "resolved".
    tau_range : (τ_min, τ_max) s to restrict the octave grid, or None (all of it).
    block : average the readings in blocks of this many samples first (:data:`MAX_FIT_SAMPLES`);
        the quantization step, mean and std are those of the raw readings.
    """
    raw = np.asarray(y, dtype=float)
    n_raw = raw.size
    y = raw if block == 1 else raw[:n_raw // block * block].reshape(-1, block).mean(axis=1)
    rate = rate / block
    n = y.size
    ms = octave_factors(n, rate, tau_range)
    if len(ms) < 5:
        raise DataError(f"axis {axis}: {len(ms)} octave τ points"
                        + (f" within --tau-range {tau_range[0]:g},{tau_range[1]:g} s"
                           if tau_range else "")
                        + "; the fit needs 5 (a log of at least "
                        f"{MIN_SAMPLES} samples, τ range spanning 4 octaves)")
    taus, adev, _ = overlapping_adev(y, rate, ms)
    s = adev ** 2
    if not (np.all(np.isfinite(s)) and s[0] > 0):
        raise DataError(f"axis {axis}: the readings do not change from sample to sample (a "
                        "dead or saturated axis, or a quantization step far above the noise): "
                        "there is no noise to characterize")
    design, tensor = allan_moments(n, ms)
    # a white floor keeps V positive definite whatever the fit does (a trillionth of the
    # smallest-τ variance: far below anything the data can tell)
    floor = 1e-12 * s[0] / design[0, 0]
    theta, cov, chi2 = _fit_theta(s, design, tensor, floor)
    dof = len(ms) - 3
    z_two = stats.norm.ppf(0.5 + level / 2.0)
    z_one = stats.norm.ppf(1.0 - alpha)
    se = np.sqrt(np.diag(cov))
    ranges = _term_ranges(taus, design, theta)
    terms = []
    for a, name in enumerate(TERM_NAMES):
        est = max(theta[a], 0.0)
        zero = floor if a == 0 else 0.0
        z0 = float(_score_z(s, design, tensor, a, np.array([zero]), theta, floor)[0])
        hi = _crossing(s, design, tensor, a, theta, floor, -z_two, est, est + 4 * se[a] + floor,
                       True)
        lo = zero if z0 <= z_two else _crossing(s, design, tensor, a, theta, floor, z_two,
                                                zero, max(est, zero), False)
        resolved = z0 > z_one
        conv = np.zeros(3)
        bounds = []
        for v in (lo, hi, est):
            conv[:] = 0.0
            conv[a] = v
            bounds.append(float(terms_from_theta(conv, rate)[a]))
        lo_t, hi_t, est_t = bounds
        terms.append(TermFit(name=name, resolved=bool(resolved),
                             value=est_t if resolved else None,
                             interval=(min(lo_t, est_t), max(hi_t, est_t)),
                             upper_bound=max(hi_t, est_t), tau_range=ranges[a], z=z0,
                             p_value=float(stats.norm.sf(z0)), level=level))
    model = design @ np.maximum(theta, 0.0)
    model_adev = np.sqrt(np.maximum(model, 0.0))
    lmt = np.log(taus)
    slopes = np.gradient(np.log(np.maximum(model_adev, 1e-300)), lmt)
    lo_ci, hi_ci, edf, noise_alpha = adev_intervals(adev, ms, n, slopes, level)
    return AxisNoise(axis=axis, taus=taus, adev=adev, adev_ci=np.column_stack([lo_ci, hi_ci]),
                     edf=edf, noise_alpha=noise_alpha, model_adev=model_adev, theta=theta,
                     cov=cov, terms=tuple(terms), chi2=chi2, dof=dof,
                     p_fit=float(stats.chi2.sf(chi2, dof)),
                     quantization_step=quantization_step(raw), mean=float(raw.mean()),
                     std=float(raw.std(ddof=1)), n=n_raw)


def characterize_noise(acc: np.ndarray, rate: float, *, level: float = 0.683,
                       alpha: float = 0.05, tau_range: tuple[float, float] | None = None,
                       axes: tuple[str, ...] = ("x", "y"), source: dict | None = None,
                       static_check: dict | None = None) -> NoiseCharacterization:
    """Allan deviation and noise terms of every column of ``acc`` ((N, k) m/s², a static log
    at ``rate`` Hz; see the module docstring). Check the log first with :func:`check_static`."""
    acc = np.asarray(acc, dtype=float)
    if acc.ndim == 1:
        acc = acc[:, None]
    if not (np.isfinite(rate) and rate > 0):
        raise DataError(f"sample rate must be a positive number of Hz, got {rate}")
    if not (0.0 < level < 1.0) or not (0.0 < alpha < 0.5):
        raise DataError(f"level {level} must be in (0, 1) and alpha {alpha} in (0, 0.5)")
    if acc.shape[0] < MIN_SAMPLES:
        raise DataError(f"{acc.shape[0]} samples: an Allan deviation fit needs at least "
                        f"{MIN_SAMPLES} (record a longer static log)")
    if not np.isfinite(acc).all():
        raise DataError("the readings hold NaN or Inf")
    n = acc.shape[0]
    block = 1 if n <= MAX_FIT_SAMPLES else 2 ** math.ceil(math.log2(n / MAX_FIT_SAMPLES))
    fits = tuple(fit_axis_noise(acc[:, k], rate, axis=axes[k], level=level, alpha=alpha,
                                tau_range=tau_range, block=block) for k in range(acc.shape[1]))
    return NoiseCharacterization(sample_rate=float(rate), n=int(n), level=level,
                                 alpha=alpha, axes=fits, static_check=static_check or {},
                                 source=source, block=block)


__all__ = ["FLICKER_FLOOR", "LACK_OF_FIT_P", "MIN_SAMPLES", "TERM_NAMES", "TERM_UNITS",
           "UNITS", "AxisNoise", "NoiseCharacterization", "TermFit", "adev_intervals",
           "characterize_noise", "check_static", "fit_axis_noise", "octave_factors",
           "overlapping_adev", "quantization_step", "sample_rate_of"]
