"""Noise characterization of a static inertial log: overlapping Allan deviation per axis, the
fitted noise terms with intervals and the τ range each was read from, whether the model
describes the curve, the quantization step (``tiltbench noise``).

**Allan deviation.** ``allantools.oadev`` (rate-like data, ``data_type="freq"``) on the octave
grid τ = m/fs, m = 1, 2, 4, …, ≤ N/4. Each point gets a χ² confidence interval from its
equivalent degrees of freedom ``ν_i = 2 (E s_i)²/Var s_i``, computed from the exact moments of
the fitted model (:func:`calib.noise.allan_model.edf`; for a pure power-law noise this is
Greenhall's EDF, ``allantools.edf_greenhall``, which the tests compare).

**Noise terms** (IEEE Std 952-1997 Annex C, IEEE Std 1293-2018 Annex, El-Sheimy et al. 2008: the
readings of the Allan deviation plot as a fit). The expected Allan variance is the sum of the
terms, exactly ``E s(τ_i) = X_i·θ`` at every τ (:mod:`calib.noise.allan_model`):

=====================  ======================  =======  ==================================
term                   unit (accelerometer;    slope    IEEE reading it replaces
                       gyro: rad for m/s)
=====================  ======================  =======  ==================================
white_noise_density N  (m/s²)/√Hz              −½       −½ line at τ = 1 s
bias_instability B     m/s²                    0        flat minimum / 0.664
rate_random_walk K     m/s²/√s                 +½       +½ line at τ = 3 s
quantization_noise Q   m/s                     −1       −1 line at τ = √3 s (3Q²/τ²)
gauss_markov σ, T_c    m/s², s                 +½ → −½  the bump near τ ≈ 1.89·T_c
=====================  ======================  =======  ==================================

The last two enter only when the rule of :mod:`calib.noise.allan_fit` asks for them (the three
core terms do not describe the curve); that module states the estimator (GLS with the full
covariance, IRLS), the adequacy checks (χ² p ≥ 0.01; B under every point's upper χ² bound:
``B ≤ min σ_A/0.664``), the model rule (add Q, then a Gauss–Markov term, then narrow the τ
range to the widest adequate one), the score-type intervals and the resolved rules (zero
rejected at ``alpha``; for K also ≥ 2 octave steps of rise with ≥ 8 clusters each).

Each term reports the τ range it was read from: the octaves of the model's range where it is
the largest term (the model's whole range when it is nowhere the largest). The model's own
range is reported too (``fit_range``); outside it, the model is not claimed to describe the
curve.

**An export's low-pass filter** (:mod:`calib.noise.shaping`). When its rule finds the
readings filtered (the curve level or rising over the first octave where white noise falls),
the filter is read from the log and every process of the model reaches the readings through
it: the moments are those of ``h_m ∗ f`` (``shaping``, at the fit's rate), the twin filters
at the log's rate (``export_filter``), N's interval is widened by the filter estimate's
spread, and the whole octave grid can be described (the rule used to narrow the range to the
octaves beyond the filter). Only ``tiltbench noise``'s fit (``select``) reads it.

**Long logs** (more than :data:`MAX_FIT_SAMPLES`) are averaged in blocks of 2^k samples before
the fit, so its cost stays bounded; τ then starts at 2^k/fs (white, flicker, walk, the
integrated-output quantization keep their Allan variance at every τ ≥ 2^k/fs).

**Logs with gaps** (``segments``). A gap is never filled: a log split at its gaps
(:func:`calib.logs.static_log.log_segments`, the reader's rule) is characterized from its
segments, each evenly sampled at the one rate. The octave grid is the longest segment's; octave
m pools the overlapping Allan variances of the segments that hold it (n_s ≥ 2m), weighted
by their numbers of differences ``c_s(m) = n_s − 2m + 1`` (:func:`pooled_adev`), and the fit
reads the exact moments of that pooled estimator with the segments as independent records
(:func:`calib.noise.allan_model.pooled_moments`: IEEE Std 952-1997 Annex C's Allan variance of
each record, their degrees of freedom adding as in Greenhall's EDF). A segment too short for
the grid's first octave contributes nothing (said in a note); when no segment holds 5 octaves
the log is refused, naming the longest. Long logs are averaged in blocks per segment (each
truncated to a multiple of the block). The rise rule of K counts the non-overlapping clusters
of every segment, ``Σ_s ⌊n_s/m⌋`` (none straddles a gap). One segment is exactly one record.

**Quantization step.** Readings on a lattice (every distinct value a multiple of one step from
the smallest) give the step; it is reported, and its white contribution Δ²/12 is part of N.

**Axes and kinds.** Each column is an axis of a kind, ``accelerometer`` (m/s²) or ``gyro``
(rad/s); the same model applies (IEEE Std 952 is the gyro standard: angle random walk, bias
instability, rate random walk), only the units differ (:mod:`calib.noise.term_units`, which
also gives the datasheet units: µg/√Hz, µg, °/√h, °/h).

The checks of the log before (sample rate, the table did not move, quantization step):
:mod:`calib.logs.static_log`, re-exported here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from calib import distributions as stats
from calib.input_rules import DataError
from calib.logs.static_log import check_static, quantization_step, sample_rate_of
from calib.noise.allan_fit import (
    CORE,
    FLICKER,
    GM,
    K_RISE_CLUSTERS,
    K_RISE_STEPS,
    LACK_OF_FIT_P,
    LADDER,
    LADDER_NAMES,
    WALK,
    WHITE,
    Engine,
    Model,
    ModelFit,
    rise_steps,
)
from calib.noise.allan_model import (
    ALL_TERM_NAMES,
    EXTRA_TERM_NAMES,
    FLICKER_FLOOR,
    TERM_NAMES,
    edf,
    record_moments,
    supported_octaves,
    term_value,
)
from calib.noise.shaping import (
    blocked_filter,
    shaping_filter,
    shaping_spread,
    shaping_summary,
)
from calib.noise.term_units import KINDS, SI_UNITS, datasheet, si_unit
from calib.results import ResultMixin, readonly

TERM_UNITS = {k: SI_UNITS["accelerometer"][k] for k in ALL_TERM_NAMES}
"""SI unit of each term of an accelerometer axis (a gyro's: :data:`SI_UNITS`)."""
UNITS = {
    "sample_rate": "Hz", "n": "count", "level": "1", "alpha": "1", "duration": "s",
    **{f"terms.{k}.{f}": u for k, u in TERM_UNITS.items()
       for f in ("value", "interval", "upper_bound")},
    **{f"gyro_terms.{k}.{f}": SI_UNITS["gyro"][k] for k in ALL_TERM_NAMES
       for f in ("value", "interval", "upper_bound")},
    "axes.*.taus": "s", "axes.*.fit_range": "s", "axes.*.terms.*.tau_range": "s",
    "axes.*.terms.*.correlation_time": "s",
    "axes.*.adev": "the axis's reading unit (axes.*.unit: m/s^2 or rad/s)",
    "axes.*.adev_ci": "the axis's reading unit", "axes.*.model_adev": "the axis's reading unit",
    "axes.*.mean": "the axis's reading unit", "axes.*.std": "the axis's reading unit",
    "axes.*.quantization_step": "the axis's reading unit",
    "axes.*.terms.*.value": "axes.*.terms.*.unit (SI; accelerometer: "
    + ", ".join(f"{k} {v}" for k, v in SI_UNITS["accelerometer"].items() if k != "reading")
    + "; gyro: " + ", ".join(f"{k} {v}" for k, v in SI_UNITS["gyro"].items() if k != "reading")
    + ")",
    "axes.*.terms.*.interval": "axes.*.terms.*.unit", "axes.*.terms.*.upper_bound":
    "axes.*.terms.*.unit", "axes.*.terms.*.datasheet.*": "axes.*.terms.*.datasheet.unit "
    "(µg = 9.80665e-6 m/s^2, ° = π/180 rad, h = 3600 s)",
    "axes.*.b_bound": "axes.*.terms.bias_instability.unit",
    "axes.*.b_bound_tau": "s",
    "axes.*.edf": "1", "axes.*.noise_alpha": "1 (0 white, -1 flicker, -2 random walk)",
    "axes.*.terms.*.z": "1", "axes.*.terms.*.p_value": "1",
    "axes.*.theta": "white (unit)^2 per sample, flicker (unit)^2, random walk (unit)^2 per "
    "sample, quantization (unit)^2 per sample^-2, Gauss-Markov (unit)^2",
    "axes.*.chi2": "1", "axes.*.dof": "count", "axes.*.p_fit": "1",
    "axes.*.k_rise_steps": "count", "axes.*.n": "count", "axes.*.tried.*.chi2": "1",
    "axes.*.tried.*.dof": "count", "axes.*.tried.*.p": "1", "axes.*.tried.*.tau_range": "s",
    "axes.*.n_fit_segments": "count", "block": "count", "static_check.window": "s",
    "axes.*.shaping": "1 (filter taps at the fit's rate, sum 1)",
    "axes.*.export_filter": "1 (filter taps at the log's rate, sum 1)",
    "axes.*.block": "count",
    "segments.*.start": "row (0-based index of the log's first reading of the segment)",
    "segments.*.stop": "row (one past the segment's last reading)",
    "segments.*.n": "count", "segments.*.n_fit": "count (after block means)",
    "segments.*.duration": "s (n / sample_rate)", "segments.*.octaves": "count",
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
samples, then cached); the terms' Allan variances are unchanged by block means at τ ≥ r/fs."""


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
    """``allantools.oadev`` of the rate-like readings ``y`` at τ = m/rate: (τ s, ADEV in the
    readings' unit, number of overlapping differences)."""
    import allantools

    taus, adev, _, n = allantools.oadev(np.asarray(y, dtype=float), rate=float(rate),
                                        data_type="freq", taus=np.asarray(ms) / rate)
    if taus.size != len(ms):
        raise DataError(f"allantools returned {taus.size} of {len(ms)} octave points")
    return np.asarray(taus), np.asarray(adev), np.asarray(n)


def pooled_adev(pieces: list[np.ndarray], rate: float, ms: tuple[int, ...]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The overlapping Allan deviation pooled over independent segments (module docstring):
    ``s(m) = Σ_s c_s(m)·s_s(m) / Σ_s c_s(m)``, ``s_s`` each segment's
    :func:`overlapping_adev` at the octaves it holds (n_s ≥ 2m), ``c_s`` its number of
    overlapping differences. Returns (τ s, ADEV, Σ_s c_s per octave); one segment is
    :func:`overlapping_adev` itself."""
    if len(pieces) == 1:
        return overlapping_adev(pieces[0], rate, ms)
    k = len(ms)
    num, count = np.zeros(k), np.zeros(k)
    for y in pieces:
        own = supported_octaves(np.asarray(y).size, ms)
        if not own:
            continue
        _, adev, c = overlapping_adev(y, rate, own)
        num[:len(own)] += c * adev ** 2
        count[:len(own)] += c
    if np.any(count <= 0):
        raise DataError(f"no segment holds the octaves m = "
                        f"{', '.join(str(m) for m, c in zip(ms, count, strict=True) if c <= 0)}")
    return np.asarray(ms) / rate, np.sqrt(num / count), count


def rise_record_length(lengths: tuple[int, ...], ms: tuple[int, ...]) -> int:
    """The record length ``n`` for :func:`calib.noise.allan_fit.rise_steps` (which counts an
    octave when ``n // m ≥ K_RISE_CLUSTERS``) that counts the clusters of segments: an octave
    counts when the segments hold ``Σ_s ⌊n_s/m⌋ ≥ K_RISE_CLUSTERS`` non-overlapping clusters
    in all (none straddling a gap). Both counts fall with m, so they agree when ``n = 8·m*``,
    m* the largest octave of the grid (powers of 2) that passes. One segment: its length."""
    if len(lengths) == 1:
        return int(lengths[0])
    passing = [m for m in ms if sum(n // m for n in lengths) >= K_RISE_CLUSTERS]
    return K_RISE_CLUSTERS * max(passing) if passing else 0


def adev_intervals(adev: np.ndarray, nu: np.ndarray, level: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided χ² interval at ``level`` of each ADEV point with ``nu`` degrees of freedom:
    ``σ·√(ν/χ²_ν((1 ± level)/2))`` (lo, hi)."""
    lo = adev * np.sqrt(nu / stats.chi2.ppf(0.5 + level / 2.0, nu))
    hi = adev * np.sqrt(nu / stats.chi2.ppf(0.5 - level / 2.0, nu))
    return lo, hi


# --- results ------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class TermFit(ResultMixin):
    """One fitted noise term of one axis (module docstring).

    name : a name of :data:`calib.noise.allan_model.ALL_TERM_NAMES`.
    resolved : the log resolves the term (score test of zero rejected at ``alpha``; for the
        rate random walk also the rise rule of :mod:`calib.noise.allan_fit`).
    value : estimate in the term's unit (:attr:`unit`), or None when not resolved.
    interval : (lo, hi) at ``level``, same unit; lo = 0 when zero is not excluded.
    upper_bound : hi — what an unresolved term is reported as.
    tau_range : (τ_first, τ_last), s — the τ where this term is the largest of the model
        (the model's whole range when it is nowhere).
    z, p_value : score statistic of "term = 0" and its one-sided p.
    kind : ``accelerometer`` or ``gyro`` (the unit).
    correlation_time : s, the Gauss–Markov term's T_c (on the half-octave grid), else None.
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
    kind: str = "accelerometer"
    correlation_time: float | None = None

    _TITLE = "Noise term"
    _UNITS = "see calib.noise.term_units"

    @property
    def unit(self) -> str:
        return si_unit(self.name, self.kind)

    def datasheet(self) -> dict:
        """Value, interval and upper bound in the datasheet unit (µg/√Hz, µg, °/√h, °/h…)."""
        v, unit = datasheet(self.name, self.kind, self.value)
        lo, _ = datasheet(self.name, self.kind, self.interval[0])
        hi, _ = datasheet(self.name, self.kind, self.interval[1])
        ub, _ = datasheet(self.name, self.kind, self.upper_bound)
        return {"value": v, "interval": [lo, hi], "upper_bound": ub, "unit": unit}

    def summary(self) -> str:
        lo, hi = self.interval
        t0, t1 = self.tau_range
        where = f"τ {t0:.3g}–{t1:.3g} s"
        ds = self.datasheet()
        tc = ("" if self.correlation_time is None
              else f", T_c {self.correlation_time:.3g} s (half-octave grid)")
        if not self.resolved:
            return (f"{self.name}: not resolved (< {self.upper_bound:.3g} {self.unit} = "
                    f"{ds['upper_bound']:.3g} {ds['unit']} at {self.level:.1%}; "
                    f"z = {self.z:.2f}, p = {self.p_value:.2g}; {where}{tc})")
        return (f"{self.name}: {self.value:.4g} {self.unit} [{lo:.4g}, {hi:.4g}] = "
                f"{ds['value']:.4g} {ds['unit']} [{ds['interval'][0]:.4g}, "
                f"{ds['interval'][1]:.4g}] at {self.level:.1%} ({where}; z = {self.z:.1f}{tc})")

    def to_dict(self) -> dict:
        return {"name": self.name, "resolved": bool(self.resolved),
                "value": None if self.value is None else float(self.value),
                "interval": [float(v) for v in self.interval],
                "upper_bound": float(self.upper_bound),
                "tau_range": [float(v) for v in self.tau_range], "z": float(self.z),
                "p_value": float(self.p_value), "level": float(self.level),
                "unit": self.unit, "kind": self.kind,
                "correlation_time": (None if self.correlation_time is None
                                     else float(self.correlation_time)),
                "datasheet": self.datasheet()}

    @classmethod
    def from_dict(cls, d: dict) -> TermFit:
        tc = d.get("correlation_time")
        return cls(name=d["name"], resolved=bool(d["resolved"]),
                   value=None if d["value"] is None else float(d["value"]),
                   interval=tuple(float(v) for v in d["interval"]),
                   upper_bound=float(d["upper_bound"]),
                   tau_range=tuple(float(v) for v in d["tau_range"]), z=float(d["z"]),
                   p_value=float(d["p_value"]), level=float(d["level"]),
                   kind=d.get("kind", "accelerometer"),
                   correlation_time=None if tc is None else float(tc))

    def to_noise_term(self):
        """The profile's :class:`calib.noise.sensor_profile.NoiseTerm`, or None when not
        resolved."""
        from calib.noise.sensor_profile import NoiseTerm

        if not self.resolved:
            return None
        return NoiseTerm(value=float(self.value), interval=tuple(self.interval),
                         tau_range=tuple(self.tau_range), level=self.level,
                         correlation_time=self.correlation_time)


@dataclass(frozen=True, eq=False)
class AxisNoise(ResultMixin):
    """Allan deviation and noise terms of one axis.

    axis, kind : the axis name and ``accelerometer``/``gyro``.
    taus (k,) s; adev (k,) in the reading unit; adev_ci (k, 2) at ``level`` (χ², EDF); edf
    (k,) exact EDF of each point for the fitted model; noise_alpha (k,) the power-law type of
    the model's local slope; model_adev (k,) of the fit; theta (5,) and cov (p, p): the GLS
    estimate (every term of :data:`ALL_TERM_NAMES`, 0 outside the model) and the covariance of
    the model's terms; terms: the three core :class:`TermFit` and the extra ones of the model;
    chi2, dof, p_fit: the chosen model's adequacy on ``fit_range``; fit_ok: a model of the
    rule describes the curve there; rule: which rung of the ladder; octaves: [lo, hi) indices
    of ``fit_range`` in ``taus``; b_bound: the largest B the Allan minimum allows (same unit
    as B) and b_bound_tau where; k_rise_steps: octave steps of the rise rule of K; tried: the
    models the rule fitted (terms, τ range, χ², dof, p, bound); quantization_step or None;
    mean, std of the readings; n samples; n_fit samples after block means; ms the octaves;
    n_fit_segments: the samples (after block means) of each segment the Allan variance was
    pooled over (module docstring: Logs with gaps); () or one entry: one record of n_fit;
    shaping: the export's low-pass filter the moments include (:mod:`calib.noise.shaping`:
    its taps, Σ = 1, at the fit's rate: after block means), or None; export_filter: the same
    filter at the log's own rate (what the twin applies before its block means), or None;
    block: readings per block mean of the fit (1: none).
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
    terms: tuple[TermFit, ...]
    chi2: float
    dof: int
    p_fit: float
    quantization_step: float | None
    mean: float
    std: float
    n: int
    kind: str = "accelerometer"
    fit_ok: bool = True
    rule: str = "three terms"
    octaves: tuple[int, int] = (0, 0)
    b_bound: float = float("inf")
    b_bound_tau: float = float("nan")
    k_rise_steps: int = 0
    n_fit: int = 0
    ms: tuple[int, ...] = ()
    tried: tuple[dict, ...] = ()
    n_fit_segments: tuple[int, ...] = ()
    shaping: tuple[float, ...] | None = None
    export_filter: tuple[float, ...] | None = None
    block: int = 1

    _TITLE = "Allan deviation of one axis"
    _UNITS = "τ s; ADEV in the reading unit; terms in calib.noise.term_units"

    def __post_init__(self) -> None:
        for name in ("taus", "adev", "adev_ci", "edf", "model_adev", "theta", "cov"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "noise_alpha", readonly(self.noise_alpha, int))
        object.__setattr__(self, "terms", tuple(self.terms))
        object.__setattr__(self, "octaves", tuple(int(v) for v in self.octaves))
        object.__setattr__(self, "ms", tuple(int(v) for v in self.ms))
        object.__setattr__(self, "tried", tuple(self.tried))
        object.__setattr__(self, "n_fit_segments", tuple(int(v) for v in self.n_fit_segments))
        for name in ("shaping", "export_filter"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))

    @property
    def fit_lengths(self) -> tuple[int, ...]:
        """The samples of each record the fit read (after block means): the segments, or the
        one record of ``n_fit``."""
        return self.n_fit_segments or (int(self.n_fit),)

    def term(self, name: str) -> TermFit | None:
        """The :class:`TermFit` ``name``; None for an extra term outside the model."""
        for t in self.terms:
            if t.name == name:
                return t
        if name in ALL_TERM_NAMES:
            return None
        raise KeyError(name)

    @property
    def unit(self) -> str:
        return SI_UNITS[self.kind]["reading"]

    @property
    def lack_of_fit(self) -> bool:
        return not self.fit_ok

    @property
    def fit_range(self) -> tuple[float, float]:
        lo, hi = self.octaves
        return float(self.taus[lo]), float(self.taus[hi - 1])

    def summary(self) -> str:
        lines = [f"axis {self.axis} ({self.kind}): {self.n} samples, mean {self.mean:.5g} "
                 f"{self.unit}, std {self.std:.4g} {self.unit}, τ {self.taus[0]:.3g}–"
                 f"{self.taus[-1]:.3g} s ({self.taus.size} octaves)"]
        lines += ["  " + t.summary() for t in self.terms]
        shaped = shaping_summary(self.export_filter, self.block * self.ms[0] / self.taus[0]
                                 if self.ms else 1.0)
        if shaped is not None:
            lines.append(f"  {shaped} (in the model and the twin)")
        q = self.quantization_step
        lines.append("  quantization step: " + ("none seen (readings not on a lattice)"
                                                if q is None else f"{q:.4g} {self.unit}"))
        if q is not None and self.std < q:
            lines.append(f"  note: the readings' std ({self.std:.3g} {self.unit}) is below the "
                         "quantization step: the Allan deviation measures the quantizer more "
                         "than the sensor")
        t0, t1 = self.fit_range
        fit = (f"  model ({self.rule}) on τ {t0:.3g}–{t1:.3g} s: χ² = {self.chi2:.2f} on "
               f"{self.dof} dof (p = {self.p_fit:.2g}); bias instability ≤ {self.b_bound:.3g} "
               f"{si_unit('bias_instability', self.kind)} by the Allan minimum's upper χ² "
               f"bound (at τ = {self.b_bound_tau:.3g} s); the walk's rise: "
               f"{self.k_rise_steps} octave step(s) with ≥ {K_RISE_CLUSTERS} clusters "
               f"({K_RISE_STEPS} needed to resolve K)")
        if not self.fit_ok:
            fit += (f" — NO model of the rule describes this curve (p < {LACK_OF_FIT_P:g} or B "
                    "above the Allan minimum on every τ range of ≥ 5 octaves): read the "
                    "figure; `--save` refuses this profile unless --save-failed-fit")
        elif self.octaves != (0, self.taus.size):
            fit += (f" — the octaves outside τ {t0:.3g}–{t1:.3g} s are not described by the "
                    "model (the widest τ range where one is adequate)")
        lines.append(fit)
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"axis": self.axis, "kind": self.kind, "unit": self.unit,
                "taus": self.taus.tolist(), "adev": self.adev.tolist(),
                "adev_ci": self.adev_ci.tolist(), "edf": self.edf.tolist(),
                "noise_alpha": self.noise_alpha.tolist(),
                "model_adev": self.model_adev.tolist(), "theta": self.theta.tolist(),
                "cov": self.cov.tolist(), "terms": {t.name: t.to_dict() for t in self.terms},
                "chi2": float(self.chi2), "dof": int(self.dof), "p_fit": float(self.p_fit),
                "fit_ok": bool(self.fit_ok), "lack_of_fit": bool(self.lack_of_fit),
                "rule": self.rule, "fit_range": list(self.fit_range),
                "octaves": list(self.octaves), "b_bound": float(self.b_bound),
                "b_bound_tau": float(self.b_bound_tau), "k_rise_steps": int(self.k_rise_steps),
                "quantization_step": (None if self.quantization_step is None
                                      else float(self.quantization_step)),
                "mean": float(self.mean), "std": float(self.std), "n": int(self.n),
                "n_fit": int(self.n_fit), "ms": list(self.ms), "tried": list(self.tried),
                "n_fit_segments": list(self.n_fit_segments),
                "shaping": None if self.shaping is None else list(self.shaping),
                "export_filter": (None if self.export_filter is None
                                  else list(self.export_filter)),
                "block": int(self.block)}

    @classmethod
    def from_dict(cls, d: dict) -> AxisNoise:
        q = d.get("quantization_step")
        return cls(axis=d["axis"], taus=d["taus"], adev=d["adev"], adev_ci=d["adev_ci"],
                   edf=d["edf"], noise_alpha=d["noise_alpha"], model_adev=d["model_adev"],
                   theta=d["theta"], cov=d["cov"],
                   terms=tuple(TermFit.from_dict(d["terms"][k]) for k in ALL_TERM_NAMES
                               if k in d["terms"]),  # θ's order, whatever the JSON's
                   chi2=float(d["chi2"]), dof=int(d["dof"]), p_fit=float(d["p_fit"]),
                   quantization_step=None if q is None else float(q), mean=float(d["mean"]),
                   std=float(d["std"]), n=int(d["n"]), kind=d.get("kind", "accelerometer"),
                   fit_ok=bool(d.get("fit_ok", True)), rule=d.get("rule", "three terms"),
                   octaves=tuple(d.get("octaves", (0, len(d["taus"])))),
                   b_bound=float(d.get("b_bound", float("inf"))),
                   b_bound_tau=float(d.get("b_bound_tau", float("nan"))),
                   k_rise_steps=int(d.get("k_rise_steps", 0)), n_fit=int(d.get("n_fit", 0)),
                   ms=tuple(d.get("ms", ())), tried=tuple(d.get("tried", ())),
                   n_fit_segments=tuple(d.get("n_fit_segments", ())),
                   shaping=None if d.get("shaping") is None else tuple(d["shaping"]),
                   export_filter=(None if d.get("export_filter") is None
                                  else tuple(d["export_filter"])),
                   block=int(d.get("block", 1)))


@dataclass(frozen=True, eq=False)
class NoiseCharacterization(ResultMixin):
    """The result of :func:`characterize_noise`: per-axis :class:`AxisNoise`, the settings,
    the static check and the source; ``notes``: axes left out and why, segments too short.

    n : the readings characterized (all segments); ``duration`` = n / sample_rate, the time
    sampled (the gaps not counted).
    segments : ((start, stop), …) the rows of each record the Allan variance was pooled over
        (module docstring: Logs with gaps); one entry (or ``()`` from an older JSON): one
        record.
    """

    sample_rate: float
    n: int
    level: float
    alpha: float
    axes: tuple[AxisNoise, ...]
    static_check: dict[str, Any] = field(default_factory=dict)
    source: dict[str, str] | None = None
    block: int = 1
    notes: tuple[str, ...] = ()
    segments: tuple[tuple[int, int], ...] = ()

    _TITLE = "Noise characterization (Allan deviation)"
    _UNITS = "Hz, s; readings m/s² (accelerometer) or rad/s (gyro); terms: calib.noise.term_units"

    def __post_init__(self) -> None:
        object.__setattr__(self, "axes", tuple(self.axes))
        object.__setattr__(self, "notes", tuple(self.notes))
        object.__setattr__(self, "segments",
                           tuple((int(a), int(b)) for a, b in self.segments))

    @property
    def duration(self) -> float:
        return self.n / self.sample_rate

    @property
    def fit_ok(self) -> bool:
        return all(a.fit_ok for a in self.axes)

    def axis(self, name: str) -> AxisNoise:
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(name)

    def summary(self) -> str:
        head = (f"noise: {self.n} samples at {self.sample_rate:g} Hz ({self.duration:.4g} s); "
                f"intervals at {self.level:.1%} (score-type, GLS on the octave Allan "
                f"variances); a term is resolved when zero is rejected at α = {self.alpha:g} "
                f"(the walk K also needs {K_RISE_STEPS} octave steps of rise with ≥ 8 "
                "clusters each)")
        if len(self.segments) > 1:
            sizes = [b - a for a, b in self.segments]
            shown = " + ".join(str(v) for v in sizes[:6]) + (" + …" if len(sizes) > 6 else "")
            head += (f"\nsegments: {len(sizes)} stretches between gaps in time, {shown} "
                     "samples; the gaps never filled, the Allan variance pooled over the "
                     "segments (note below)")
        if self.block > 1:
            head += (f"\nlong log: averaged in blocks of {self.block} samples before the fit "
                     f"(τ from {self.block / self.sample_rate:g} s)")
        return "\n".join([head] + [a.summary() for a in self.axes]
                         + [f"note: {n}" for n in self.notes])

    def to_dict(self) -> dict:
        return {"sample_rate": float(self.sample_rate), "n": int(self.n),
                "duration": float(self.duration), "level": float(self.level),
                "alpha": float(self.alpha), "fit_ok": bool(self.fit_ok),
                "axes": {a.axis: a.to_dict() for a in self.axes},
                "static_check": self.static_check, "source": self.source,
                "block": int(self.block), "notes": list(self.notes),
                "segments": self._segments_dict(), "units": UNITS}

    def _segments_dict(self) -> list[dict]:
        """Each segment's rows, samples, samples after block means, duration and how many
        octaves of the grid it holds (:data:`UNITS`)."""
        ms = self.axes[0].ms if self.axes else ()
        out = []
        for a, b in self.segments:
            fit = (b - a) // self.block
            out.append({"start": a, "stop": b, "n": b - a, "n_fit": fit,
                        "duration": (b - a) / self.sample_rate,
                        "octaves": len(supported_octaves(fit, ms))})
        return out

    @classmethod
    def from_dict(cls, d: dict) -> NoiseCharacterization:
        return cls(sample_rate=float(d["sample_rate"]), n=int(d["n"]), level=float(d["level"]),
                   alpha=float(d["alpha"]),
                   axes=tuple(AxisNoise.from_dict(a) for a in d["axes"].values()),
                   static_check=d.get("static_check", {}), source=d.get("source"),
                   block=int(d.get("block", 1)), notes=tuple(d.get("notes", ())),
                   segments=tuple((int(g["start"]), int(g["stop"]))
                                  for g in d.get("segments", ())))

    def to_profile(self, calibration: dict | None = None, tool_version: str = "unknown"):
        """The :class:`calib.noise.sensor_profile.SensorProfile` of this log: resolved terms as
        NoiseTerms, unresolved ones null (their upper bounds in ``extra``), the extra terms of
        each axis's model, the quantization step, whether the model describes each axis's
        curve (``fit_ok``) and on which τ range, the sample rate and ``calibration`` if
        given."""
        from calib.noise.sensor_profile import SensorProfile

        def per_axis(name):
            terms = tuple(None if a.term(name) is None else a.term(name).to_noise_term()
                          for a in self.axes)
            return None if all(t is None for t in terms) else terms

        bounds = {a.axis: {t.name: t.upper_bound for t in a.terms
                           if not t.resolved and t.name in TERM_NAMES} for a in self.axes}
        qs = tuple(a.quantization_step for a in self.axes)
        return SensorProfile(
            sample_rate=self.sample_rate,
            white_noise_density=tuple(a.term("white_noise_density").to_noise_term()
                                      for a in self.axes),
            bias_instability=per_axis("bias_instability"),
            rate_random_walk=per_axis("rate_random_walk"),
            quantization_step=None if all(q is None for q in qs) else qs,
            quantization_noise=per_axis("quantization_noise"),
            gauss_markov=per_axis("gauss_markov"),
            fit_tau_range=tuple(a.fit_range for a in self.axes),
            export_filter=(None if all(a.export_filter is None for a in self.axes)
                           else tuple(a.export_filter for a in self.axes)),
            calibration=calibration, source=self.source, tool_version=tool_version,
            axes=tuple(a.axis for a in self.axes),
            extra={"unresolved_upper_bounds": bounds, "level": self.level,
                   "alpha": self.alpha, "n": self.n,
                   "lack_of_fit": {a.axis: bool(a.lack_of_fit) for a in self.axes}})


# --- the fit of one axis ------------------------------------------------------------------


def _term_ranges(taus: np.ndarray, design: np.ndarray, theta: np.ndarray,
                 lo: int, hi: int) -> dict[int, tuple[float, float]]:
    parts = design[lo:hi] * np.maximum(theta, 0.0)
    top = np.argmax(parts, axis=1)
    out = {}
    for a in range(theta.size):
        idx = np.nonzero(top == a)[0] + lo
        out[a] = ((float(taus[lo]), float(taus[hi - 1])) if idx.size == 0
                  else (float(taus[idx[0]]), float(taus[idx[-1]])))
    return out


def _tried(f: ModelFit, taus: np.ndarray) -> dict:
    m = f.model
    return {"terms": list(m.names), "tau_range": [float(taus[m.lo]), float(taus[m.hi - 1])],
            "chi2": float(f.chi2), "dof": int(f.dof), "p": float(f.p),
            "b_bound_ok": bool(f.bound_ok)}


def fit_axis_noise(y: np.ndarray, rate: float, *, axis: str = "x", kind: str = "accelerometer",
                   level: float = 0.683, alpha: float = 0.05,
                   tau_range: tuple[float, float] | None = None, block: int = 1,
                   select: bool = False,
                   segments: tuple[tuple[int, int], ...] | None = None) -> AxisNoise:
    """Allan deviation and the noise terms of one axis (module docstring).

    Parameters
    ----------
    y : (N,) readings of a static log (m/s² or rad/s by ``kind``), evenly spaced at ``rate``
        Hz (within each segment).
    kind : ``accelerometer`` or ``gyro``: the units only.
    level : two-sided level of the intervals (ADEV points and terms).
    alpha : one-sided significance for "resolved".
    tau_range : (τ_min, τ_max) s to restrict the octave grid, or None (all of it).
    block : average the readings in blocks of this many samples first (:data:`MAX_FIT_SAMPLES`;
        per segment); the quantization step, mean and std are those of the raw readings.
    select : apply the model rule of :mod:`calib.noise.allan_fit` (``tiltbench noise``); False:
        the three core terms on the whole range, whatever their adequacy (the gap workflow's
        flicker test, :mod:`calib.gap.walk`, whose false-alarm rates were measured so).
    segments : ((start, stop), …) rows of ``y`` between the log's gaps, or None (one record);
        the Allan variance is pooled over those that hold the grid's first octave (module
        docstring: Logs with gaps), the raw statistics are over all of them.
    """
    if kind not in KINDS:
        raise DataError(f"axis {axis}: kind must be one of {', '.join(KINDS)}, got {kind!r}")
    y_all = np.asarray(y, dtype=float)
    if segments is not None and len(segments) > 1:
        return _fit_segments(y_all, rate, segments, axis=axis, kind=kind, level=level,
                             alpha=alpha, tau_range=tau_range, block=block, select=select)
    if segments is not None:  # one segment: that record
        (a, b), = segments
        y_all = y_all[a:b]
    raw = y_all
    n_raw = raw.size
    y = raw if block == 1 else raw[:n_raw // block * block].reshape(-1, block).mean(axis=1)
    rate = rate / block
    n = y.size
    ms = octave_factors(n, rate, tau_range)
    _check_octaves(ms, axis, tau_range)
    taus, adev, _ = overlapping_adev(y, rate, ms)
    return _fit_records(adev, taus, ms, (n,), raw=raw, rate=rate, axis=axis, kind=kind,
                        level=level, alpha=alpha, select=select, block=block)


def _check_octaves(ms: tuple[int, ...], axis: str, tau_range) -> None:
    if len(ms) < 5:
        raise DataError(f"axis {axis}: {len(ms)} octave τ points"
                        + (f" within --tau-range {tau_range[0]:g},{tau_range[1]:g} s"
                           if tau_range else "")
                        + "; the fit needs 5 (a log of at least "
                        f"{MIN_SAMPLES} samples, τ range spanning 4 octaves)")


def _fit_segments(y_all: np.ndarray, rate: float, segments, *, axis, kind, level, alpha,
                  tau_range, block, select) -> AxisNoise:
    """:func:`fit_axis_noise` of a log with gaps: block means per segment (each truncated to a
    multiple of ``block``), the longest segment's octave grid, the pooled Allan variance over
    the segments that hold its first octave (module docstring: Logs with gaps)."""
    raws = [y_all[a:b] for a, b in segments]
    pieces = [r if block == 1 else r[:r.size // block * block].reshape(-1, block).mean(axis=1)
              for r in raws]
    rate = rate / block
    ms = octave_factors(max(p.size for p in pieces), rate, tau_range)
    _check_octaves(ms, axis, tau_range)
    used = [p for p in pieces if supported_octaves(p.size, ms)]
    taus, adev, _ = pooled_adev(used, rate, ms)
    return _fit_records(adev, taus, ms, tuple(p.size for p in used),
                        raw=np.concatenate(raws), rate=rate, axis=axis, kind=kind, level=level,
                        alpha=alpha, select=select, block=block, records=raws)


def _filters(raws: list[np.ndarray], block: int
             ) -> tuple[tuple[float, ...] | None, tuple[float, ...] | None]:
    """(the shaping filter at the fit's rate, the export filter at the log's rate) of a log
    (:mod:`calib.noise.shaping`): the export filter read on the records (the rule on the
    longest, the spectrum over all of them), the fit's that of its block means
    (:func:`calib.noise.shaping.blocked_filter`). Both None when the readings are not
    filtered; the first alone None when one block spans the filter."""
    export = shaping_filter(list(raws))
    if export is None:
        return None, None
    return blocked_filter(export, block), export


def _fit_records(adev, taus, ms, lengths: tuple[int, ...], *, raw, rate, axis, kind, level,
                 alpha, select, block=1, records=None) -> AxisNoise:
    """The fit of the octave Allan deviations ``adev`` of records of ``lengths`` samples (one
    record, or the segments they were pooled over) with their moments (shaped by the log's
    export filter when the model rule runs and finds one, :mod:`calib.noise.shaping`; read on
    ``records``, the raw readings of each segment, or on ``raw``)."""
    s = adev ** 2
    if not (np.all(np.isfinite(s)) and s[0] > 0):
        raise DataError(f"axis {axis}: the readings do not change from sample to sample (a "
                        "dead or saturated axis, or a quantization step far above the noise): "
                        "there is no noise to characterize")
    shaping, export = (_filters(records or [raw], block) if select else (None, None))
    mom = record_moments(lengths, ms, shaping)
    # a white floor keeps V positive definite whatever the fit does (a trillionth of the
    # smallest-τ variance: far below anything the data can tell)
    floor = 1e-12 * s[0] / mom.design[0, 0]
    engine = Engine(s, mom, floor, nonnegative=select)
    k = len(ms)
    if select:
        chosen, ok, tried = engine.select()
    else:
        chosen = engine.fit(Model(CORE, None, 0, k))
        ok, tried = chosen.adequate, [chosen]
    spread = None
    if shaping is not None:  # the filter was read from this log: N's interval widens
        spread = shaping_spread(export, raw.size, ms, block)
    return _axis_result(engine, chosen, ok, tried, raw=raw, taus=taus, adev=adev, ms=ms,
                        lengths=lengths, rate=rate, axis=axis, kind=kind, level=level,
                        alpha=alpha, export=export, spread=spread, block=block)


def _caps(kind: str, rate: float) -> np.ndarray:
    """The largest θ of each term (θ units at ``rate``): the upper end of its physical range
    (:data:`calib.noise.sensor_profile.TERM_RANGES`, gyro :data:`GYRO_TERM_RANGES`)."""
    from calib.noise.allan_model import theta_from_terms
    from calib.noise.sensor_profile import GYRO_TERM_RANGES, TERM_RANGES

    top = {n: r[1] for n, r in (GYRO_TERM_RANGES if kind == "gyro" else TERM_RANGES).items()}
    return theta_from_terms(top["white_noise_density"], top["bias_instability"],
                            top["rate_random_walk"], rate, q=top["quantization_noise"],
                            gm_sigma=top["gauss_markov"])


def _axis_result(engine: Engine, chosen: ModelFit, ok: bool, tried: list[ModelFit], *,
                 raw, taus, adev, ms, lengths, rate, axis, kind, level, alpha,
                 export=None, spread=None, block=1) -> AxisNoise:
    model = chosen.model
    n = int(sum(lengths))
    theta = chosen.theta
    z_one = float(stats.norm.ppf(1.0 - alpha))
    caps = _caps(kind, rate)
    ends = engine.intervals(chosen, level, caps=caps)
    design_all, tensor_all = engine.mom.full(model.g)
    ranges = _term_ranges(taus, design_all, theta, model.lo, model.hi)
    rise = rise_steps(chosen, design_all, ms, rise_record_length(lengths, ms))
    terms = []
    tc_seconds = (None if model.g is None else float(engine.mom.gm_tc[model.g]) / rate)
    for a in model.active:
        name = ALL_TERM_NAMES[a]
        lo, hi, z0 = ends[a]
        # resolved: zero rejected, a positive estimate, and (the walk) the rise rule
        resolved = z0 > z_one and theta[a] > 0 and (a != WALK or rise >= K_RISE_STEPS)
        est = term_value(name, max(theta[a], 0.0), rate)
        lo_t, hi_t = term_value(name, lo, rate), term_value(name, hi, rate)
        if a == WHITE and spread is not None:
            lo_t, hi_t = _with_filter_spread(est, lo_t, hi_t, spread, level)
            hi_t = min(hi_t, term_value(name, caps[a], rate))  # the term's physical range
        terms.append(TermFit(name=name, resolved=bool(resolved),
                             value=est if resolved else None,
                             interval=(min(lo_t, est), max(hi_t, est)),
                             upper_bound=max(hi_t, est), tau_range=ranges[a], z=z0,
                             p_value=float(stats.norm.sf(z0)), level=level, kind=kind,
                             correlation_time=tc_seconds if a == GM else None))
    th = np.maximum(theta, 0.0)
    th[WHITE] = max(th[WHITE], engine.floor)
    model_avar = design_all @ th
    model_adev = np.sqrt(model_avar)
    nu = edf(design_all, tensor_all, th)
    lo_ci, hi_ci = adev_intervals(adev, nu, level)
    slopes = np.gradient(np.log(np.maximum(model_adev, 1e-300)), np.log(taus))
    noise_alpha = np.clip(np.rint(-2.0 * slopes - 1.0), -2, 0).astype(int)
    b_bound = term_value("bias_instability", chosen.b_bound, rate)
    rule = LADDER_NAMES[LADDER.index(model.active)]
    return AxisNoise(axis=axis, taus=taus, adev=adev, adev_ci=np.column_stack([lo_ci, hi_ci]),
                     edf=nu, noise_alpha=noise_alpha, model_adev=model_adev, theta=theta,
                     cov=chosen.cov, terms=tuple(terms), chi2=chosen.chi2, dof=chosen.dof,
                     p_fit=chosen.p, quantization_step=quantization_step(raw),
                     mean=float(raw.mean()), std=float(raw.std(ddof=1)), n=raw.size,
                     kind=kind, fit_ok=bool(ok), rule=rule, octaves=(model.lo, model.hi),
                     b_bound=b_bound, b_bound_tau=float(taus[chosen.b_bound_index]),
                     k_rise_steps=rise, n_fit=n, ms=ms,
                     tried=tuple(_tried(f, taus) for f in tried),
                     n_fit_segments=lengths if len(lengths) > 1 else (),
                     shaping=engine.mom.shaping, export_filter=export, block=int(block))


def _with_filter_spread(est: float, lo: float, hi: float, spread: np.ndarray, level: float
                        ) -> tuple[float, float]:
    """N's interval [lo, hi] widened by the error of a filter read from the log
    (:mod:`calib.noise.shaping`). The short-τ octaves tie N to the filter's passband level, so
    that level's relative error moves N by half of it (N² scales with it): in log N, the
    variance ``Σ_f,00 / 4`` of the first octave's white Allan variance over re-estimates of
    the filter is added in quadrature to each side's half-width (the whole of it: as if N were
    read from the short τ alone — conservative when the long τ hold it too)."""
    if not est > 0.0:
        return lo, hi
    z = float(stats.norm.ppf(0.5 + level / 2.0))
    extra = z * z * float(spread[0, 0]) / 4.0
    down = math.sqrt(math.log(est / lo) ** 2 + extra) if lo > 0 else math.inf
    up = math.sqrt(math.log(hi / est) ** 2 + extra)
    return (est * math.exp(-down) if math.isfinite(down) else 0.0), est * math.exp(up)


def characterize_noise(acc: np.ndarray, rate: float, *, level: float = 0.683,
                       alpha: float = 0.05, tau_range: tuple[float, float] | None = None,
                       axes: tuple[str, ...] = ("x", "y", "z"),
                       kinds: tuple[str, ...] | None = None, source: dict | None = None,
                       static_check: dict | None = None, select: bool = True,
                       notes: tuple[str, ...] = (),
                       segments: Sequence[int] | Sequence[tuple[int, int]] | None = None,
                       t: np.ndarray | None = None,
                       progress: Callable[[str], None] | None = None
                       ) -> NoiseCharacterization:
    """Allan deviation and noise terms of every column of ``acc`` ((N, k) readings of a static
    log at ``rate`` Hz: m/s² for an accelerometer axis, rad/s for a gyro axis; see the module
    docstring), named by ``axes`` and of the sensor kinds ``kinds`` (default: every column an
    accelerometer). Check the log first with :func:`check_static`. ``select``: the model rule
    (:func:`fit_axis_noise`).

    ``segments``: the stretches of a log with gaps (:func:`calib.logs.static_log.log_segments`)
    — their lengths in order (summing to N) or (start, stop) row pairs (in order, not
    overlapping; rows outside them unused) — or None: one record. The Allan variance is
    pooled over them (module docstring: Logs with gaps); the result records them
    (``segments``) with a note. Refused in one line when no segment holds the 5 octaves a
    fit needs (naming the longest: by its times when ``t`` ((N,) s) is given, else its rows).

    ``progress``: called with ``"axes fitted k/n"`` after each axis (a long or filtered log
    takes seconds per axis), or None."""
    acc = np.asarray(acc, dtype=float)
    if acc.ndim == 1:
        acc = acc[:, None]
    if not (np.isfinite(rate) and rate > 0):
        raise DataError(f"sample rate must be a positive number of Hz, got {rate}")
    if not (0.0 < level < 1.0) or not (0.0 < alpha < 0.5):
        raise DataError(f"level {level} must be in (0, 1) and alpha {alpha} in (0, 0.5)")
    bounds = segment_bounds(segments, acc.shape[0])
    if sum(b - a for a, b in bounds) < MIN_SAMPLES:
        raise DataError(f"{sum(b - a for a, b in bounds)} samples: an Allan deviation fit "
                        f"needs at least {MIN_SAMPLES} (record a longer static log)")
    if not all(np.isfinite(acc[a:b]).all() for a, b in bounds):
        raise DataError("the readings hold NaN or Inf")
    if len(axes) < acc.shape[1]:
        raise DataError(f"{acc.shape[1]} columns but {len(axes)} axis names")
    kinds = kinds or ("accelerometer",) * acc.shape[1]
    n = sum(b - a for a, b in bounds)
    block = 1 if n <= MAX_FIT_SAMPLES else 2 ** math.ceil(math.log2(n / MAX_FIT_SAMPLES))
    notes = tuple(notes)
    if len(bounds) > 1:
        notes += _segment_notes(bounds, rate, block, tau_range, source, t)
    fits = []
    for k in range(acc.shape[1]):
        fits.append(fit_axis_noise(acc[:, k], rate, axis=axes[k], kind=kinds[k], level=level,
                                   alpha=alpha, tau_range=tau_range, block=block,
                                   select=select, segments=bounds))
        if progress is not None:  # "what k/n": a counter to the CLI's progress
            progress(f"axes fitted {k + 1}/{acc.shape[1]}")
    fits = tuple(fits)
    return NoiseCharacterization(sample_rate=float(rate), n=int(n), level=level,
                                 alpha=alpha, axes=fits, static_check=static_check or {},
                                 source=source, block=block, notes=notes, segments=bounds)


def segment_bounds(segments, n: int) -> tuple[tuple[int, int], ...]:
    """((start, stop), …) rows of ``segments`` (:func:`characterize_noise`) in a log of ``n``
    rows: None → one record ((0, n),); lengths → consecutive rows (they must sum to n); pairs
    → checked (in order, not overlapping, not empty, inside the log)."""
    if segments is None:
        return ((0, int(n)),)
    items = list(segments)
    if not items:
        raise DataError("segments: none given (None means one record)")
    if all(np.ndim(v) == 0 for v in items):
        lengths = [int(v) for v in items]
        if any(v <= 0 for v in lengths) or sum(lengths) != n:
            raise DataError(f"segments: lengths {lengths} must be positive and sum to the "
                            f"{n} readings")
        stops = np.cumsum(lengths)
        return tuple((int(b - v), int(b)) for v, b in zip(lengths, stops, strict=True))
    pairs = tuple((int(a), int(b)) for a, b in items)
    last = 0
    for a, b in pairs:
        if not last <= a < b <= n:
            raise DataError(f"segments: {pairs} must be (start, stop) rows in order, not "
                            f"empty or overlapping, within the {n} readings")
        last = b
    return pairs


def _segment_notes(bounds, rate: float, block: int, tau_range, source, t
                   ) -> tuple[str, ...]:
    """The notes of a segmented characterization (what was pooled, what was left out), or a
    one-line refusal when no segment holds the 5 octaves a fit needs."""
    where = f"{source['name']}: " if source and source.get("name") else ""
    fit_lengths = [(b - a) // block for a, b in bounds]
    longest = int(np.argmax(fit_lengths))
    ms = octave_factors(fit_lengths[longest], rate / block, tau_range)
    a0, b0 = bounds[longest]

    def span(a: int, b: int) -> str:
        return (f"rows {a}–{b - 1}" if t is None
                else f"t = {float(t[a]):.6g} to {float(t[b - 1]):.6g} s")

    if len(ms) < 5:
        raise DataError(
            f"{where}no segment between the gaps holds the 5 octave τ points an Allan fit "
            f"needs: the longest of {len(bounds)} ({span(a0, b0)}, {b0 - a0} samples = "
            f"{(b0 - a0) / rate:.4g} s) holds {len(ms)}"
            + (f" within --tau-range {tau_range[0]:g},{tau_range[1]:g} s" if tau_range else "")
            + f"; a segment of at least {MIN_SAMPLES * block} samples "
            f"({MIN_SAMPLES * block / rate:.4g} s) without a gap is needed (a gap is never "
            "filled: record a longer still stretch)")
    used = [k for k, f in enumerate(fit_lengths) if supported_octaves(f, ms)]
    out = [f"the Allan variance pooled over {len(used)} of {len(bounds)} segments between "
           f"gaps in time (never filled; octave grid of the longest, {b0 - a0} samples): "
           "octave m averages the overlapping differences of the segments of ≥ 2m "
           "samples, the segments taken as independent records"]
    short = [k for k in range(len(bounds)) if k not in used]
    if short:
        rows = ", ".join(span(*bounds[k]) for k in short[:3])
        out.append(f"{len(short)} segment(s) shorter than the first octave needs "
                   f"({2 * ms[0]} samples{' after block means' if block > 1 else ''}) "
                   f"contribute nothing ({rows}{', …' if len(short) > 3 else ''})")
    return tuple(out)


__all__ = ["EXTRA_TERM_NAMES", "FLICKER", "FLICKER_FLOOR", "LACK_OF_FIT_P", "MAX_FIT_SAMPLES",
           "MIN_SAMPLES", "TERM_NAMES", "TERM_UNITS", "UNITS", "AxisNoise",
           "NoiseCharacterization", "TermFit", "adev_intervals", "characterize_noise",
           "check_static", "fit_axis_noise", "octave_factors", "overlapping_adev",
           "pooled_adev", "quantization_step", "rise_record_length", "sample_rate_of",
           "segment_bounds"]
