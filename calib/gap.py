"""Discrepancy workflow, estimation side: where the nominal model and the data disagree.

Given a measured calibration run (θ, readings, optional times) and the stated noise variances,
:func:`analyze_gap` measures the gap of the nominal model (bias + scale per axis), tests every
effect of ``docs/effects.md`` as an extension of the model (:mod:`calib.effects`), names the
missing effect(s) with their estimates ± std in the catalog's units, and measures the gap that
is left. The bench (:mod:`bench.gap`) re-simulates with the named effects and measures its own
"after" gap with the same yardstick, :func:`calib.diagnostics.gap_measure`.

Selection criterion (stated once)
---------------------------------
Forward stepwise selection by likelihood-ratio tests with a Bonferroni-controlled family
error rate:

1. Step 0 — quantization: the readings of each axis are tested for a lattice
   (:func:`calib.diagnostics.detect_lattice`); a lattice is named (its lsb adds lsb²/12 to
   the noise variance of every later test).
2. Every step — every remaining candidate (per axis: misalignment, nonlinearity_k2,
   cross_axis, bias_drift, bias_random_walk, saturation, noise_level, and with timing
   lowpass_lag, lever_arm; both axes: tilt_offset) is fitted on top of the current model and
   tested by its likelihood ratio (reference distributions in :meth:`Extensions.test`). The
   candidate with the smallest p-value is added if ``p < α_step = family_alpha / m``, m the
   number of tests at the first step (testable candidates + 2 lattice tests); all nonlinear
   parameters are then re-fitted. Stop when no candidate passes. Under noise alone the run
   names nothing unless some first-step test passes, so ``P(false alarm) ≤ family_alpha``
   (Bonferroni; default 0.005, i.e. ≤ 0.5 % of clean runs).
3. One backward pass: an effect whose drop-one test no longer passes ``α_step`` is removed.

Noise level last. ``noise_level`` competes at every step, so a mere change of σ² is never
taken by a noise-like structured candidate (random walk, low-pass). It cannot take the place of
a real structured effect: an effect that explains ΔRSS gives ``LR = ΔRSS/σ²`` (log p ≈ -LR/2)
while the same ΔRSS as extra variance gives the χ² test ``log p ≈ -(n/2)(ρ - 1 - ln ρ)``,
``ρ = 1 + ΔRSS/(nσ²)``, always less extreme; so noise_level is in effect tested after the
structured effects, on the residuals of the extended model.

Known confusions, reported in ``not_identifiable``: ``gravity_mismatch`` always (absorbed by
the scale factors); ``tilt_offset`` vs equal ``misalignment`` of both sensors whenever either
is named (identical on one table; the 1-parameter tilt offset is preferred by the selection
when the two δ agree); ``lowpass_lag`` vs a tilt offset / misalignment and ``bias_drift`` vs
``bias_random_walk`` when the alternative explains the data within a likelihood ratio of 10
(``|Δ(-2 log L)| < 2 ln 10``, AIC-penalised when the parameter counts differ); candidates
that this θ design cannot test (collinear columns). Effects that need timing are skipped
without ``t`` or ``rate`` and listed in ``needs_timing``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy import linalg as sla
from scipy import optimize, stats

from calib.calibration import Calibration, calibrate
from calib.conventions import AXES, G
from calib.diagnostics import (
    GapMeasure,
    Lattice,
    detect_lattice,
    gap_measure,
)
from calib.effects import (
    EFFECT_NAMES,
    LINEAR_COLUMNS,
    NEEDS_TIMING,
    AxisState,
    Extensions,
    ModelState,
    RunData,
    Trial,
    lowpass,
)
from calib.filters import walk_filter
from calib.io import Ensayo
from calib.ls import NotIdentifiableError, fit_linear

PER_AXIS_CANDIDATES: tuple[str, ...] = (
    "noise_level", "misalignment", "nonlinearity_k2", "cross_axis", "bias_drift",
    "bias_random_walk", "saturation", "lowpass_lag", "lever_arm")
"""Per-axis extensions tested at every step (``tilt_offset`` is tested for both axes)."""

AMBIGUITY_LR = 2.0 * float(np.log(10.0))
"""Two explanations whose ``-2 log L`` differ by less than this (likelihood ratio < 10) are
reported as not told apart."""

MAX_STEPS = 10

REASONS = {
    "gravity_mismatch": (
        "absorbed by the scale factors: a different local g is a common scale change of both "
        "axes; only an independent gravity reference (or a known scale) separates them"),
    "tilt_offset": (
        "identical on one table: a table-angle offset equals the same misalignment of both "
        "sensors; mounting the sensor block rotated by 90° (or an independent inclinometer) "
        "separates them"),
    "lowpass_lag": (
        "at a constant sweep rate a lag τ looks like an angle offset -τ·ω; a sweep with a "
        "varying rate or a reversal (up-then-down) separates them"),
    "bias_drift": (
        "a linear trend is one realisation of a random walk; a longer run, or repeated runs, "
        "separate them"),
}


# ------------------------------------------------------------------------------ results

@dataclass(frozen=True)
class EffectEstimate:
    """A named effect with its evidence.

    name : catalog name.  axis : "x", "y" or "both".
    params : catalog keys → estimates (catalog units, ``docs/effects.md``).
    std : same keys → standard deviations.
    statistic : likelihood-ratio statistic ``-2 log Λ`` of dropping the effect from the final
        model (quantization: the number of distinct reading levels on the lattice).
    p_value : its p-value under the reference distribution of :meth:`Extensions.test`.
    """

    name: str
    axis: str
    params: dict
    std: dict
    statistic: float
    p_value: float
    interval: dict = field(default_factory=dict, compare=False)
    """Optional 95 % intervals (key → (low, high)): noise_level, the χ²(dof) interval of σ²;
    bias_random_walk, the REML profile-likelihood interval of q (asymmetric; its std is
    (high - low)/(2·1.96), see :func:`_q_uncertainty`)."""

    def to_dict(self) -> dict:
        """``{"name", "axis", "params", "std", "statistic", "p_value"}`` (documented JSON),
        plus ``"interval": {key: [low, high]}`` only for an effect that has one (additive)."""
        out = {"name": self.name, "axis": self.axis,
               "params": {k: float(v) for k, v in self.params.items()},
               "std": {k: float(v) for k, v in self.std.items()},
               "statistic": float(self.statistic), "p_value": float(self.p_value)}
        if self.interval:
            out["interval"] = {k: [float(lo), float(hi)] for k, (lo, hi) in self.interval.items()}
        return out

    def __str__(self) -> str:
        vals = ", ".join(f"{k} = {v:.6g} ± {self.std.get(k, float('nan')):.3g}"
                         for k, v in self.params.items())
        ci = "".join(f"; 95% interval of {k}: [{lo:.6g}, {hi:.6g}]"
                     for k, (lo, hi) in self.interval.items())
        return (f"{self.name} ({self.axis}): {vals}{ci}; statistic = {self.statistic:.4g}, "
                f"p = {self.p_value:.3g}")


@dataclass(frozen=True)
class ExtendedModel:
    """The model fitted by :func:`analyze_gap`: nominal parameters plus the named extensions.

    names : parameter names, ``"x.bias"``, ``"x.scale"``, ``"x.c_k2"``, …, ``"sin_tilt"``
        (linear parameters: bias m/s², scale dimensionless, column coefficients in the units of
        :data:`calib.effects.LINEAR_COLUMNS` times (1 + scale)).
    params, cov : estimates and their joint covariance (Gauss-Newton: it includes the
        uncertainty of the limit L and the time constant τ).
    nonlinear : ``"x.tau"``, ``"x.limit"``, ``"x.q"``, ``"x.sigma2"`` → (value, std).
    sigma2 : (2,) variance of the white error of each axis in the model (σ² + lsb²/12).
    noise_var : (2,) white-noise variance σ² of each axis before any rounding (the estimate
        when ``noise_level`` is named, else the stated one), (m/s²)².
    state : the model structure (:class:`calib.effects.ModelState`).
    gains : (2,) multipliers of the tilt column (1 + nominal scale).
    time_unit : "s" or "sample" (drift and random walk units).
    """

    names: tuple[str, ...]
    params: np.ndarray
    cov: np.ndarray
    nonlinear: dict
    sigma2: tuple[float, float]
    noise_var: tuple[float, float]
    state: ModelState
    gains: tuple[float, float]
    time_unit: str

    def __post_init__(self) -> None:
        for name in ("params", "cov"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))

    def value(self, name: str, default: float = 0.0) -> float:
        return float(self.params[self.names.index(name)]) if name in self.names else default

    def axis_params(self, axis: str) -> dict:
        """Parameters of one axis (and the shared tilt) → {"value", "std"}."""
        out = {}
        for i, n in enumerate(self.names):
            if n.startswith(f"{axis}.") or n == "sin_tilt":
                out[n.split(".", 1)[-1]] = {"value": float(self.params[i]),
                                            "std": float(self.std[i])}
        for n, (v, s) in self.nonlinear.items():
            if n.startswith(f"{axis}."):
                out[n.split(".", 1)[1]] = {"value": float(v), "std": float(s)}
        return out

    def to_dict(self) -> dict:
        return {"names": list(self.names), "params": self.params.tolist(),
                "std": self.std.tolist(), "cov": self.cov.tolist(),
                "nonlinear": {k: {"value": float(v), "std": float(s)}
                              for k, (v, s) in self.nonlinear.items()},
                "sigma2": list(self.sigma2), "noise_var": list(self.noise_var),
                "time_unit": self.time_unit}


@dataclass(frozen=True)
class GapAnalysis:
    """What :func:`analyze_gap` found.

    Attributes
    ----------
    effects : the named effects, catalog order.
    not_identifiable : ``{"names": [...], "reason": str}`` for each confusion.
    gap_before : per axis, the gap of the nominal model (bias + scale, stated σ²).
    gap_after_fit : per axis, the gap of the extended model fitted here (data vs the model).
    nominal : the nominal calibration (per-axis OLS, stated σ²; :class:`Calibration`).
    final : the extended model with its covariance (:class:`ExtendedModel`).
    residuals_before : (N, 2) data - nominal model, m/s².
    residuals_after : (N, 2) whitened residuals of the extended model scaled to m/s² (white
        with variance ``final.sigma2`` under the model: data - model, or the normalised
        Kalman innovations × σ with a random walk).
    fitted : (N, 2) mean reading of the extended model (no random walk), m/s².
    needs_timing : effects skipped because the run has no timing.
    criterion : family α, per-step α, number of tests and the rule, for the record.
    steps : the selection trace (every candidate's LR and p at each step).
    """

    effects: tuple[EffectEstimate, ...]
    not_identifiable: tuple[dict, ...]
    gap_before: dict
    gap_after_fit: dict
    nominal: Calibration
    final: ExtendedModel
    residuals_before: np.ndarray
    residuals_after: np.ndarray
    fitted: np.ndarray
    needs_timing: tuple[str, ...]
    criterion: dict
    steps: tuple[dict, ...] = field(default=())
    g: float = G
    noise_var: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self) -> None:
        for name in ("residuals_before", "residuals_after", "fitted"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def named(self) -> list[tuple[str, str]]:
        """(name, axis) of every named effect."""
        return [(e.name, e.axis) for e in self.effects]

    def effect(self, name: str, axis: str | None = None) -> EffectEstimate:
        for e in self.effects:
            if e.name == name and (axis is None or e.axis == axis):
                return e
        raise KeyError(f"effect {name} ({axis}) not named")

    def to_dict(self) -> dict:
        """The documented JSON object (``gap_after`` here is the fitted one; the bench
        replaces it by the re-simulated gap), plus ``needs_timing`` and ``criterion``."""
        return {
            "effects": [e.to_dict() for e in self.effects],
            "not_identifiable": [{"names": list(d["names"]), "reason": d["reason"]}
                                 for d in self.not_identifiable],
            "gap_before": {a: self.gap_before[a].to_dict() for a in AXES},
            "gap_after": {a: self.gap_after_fit[a].to_dict() for a in AXES},
            "needs_timing": list(self.needs_timing),
            "criterion": dict(self.criterion),
        }

    def summary(self) -> str:
        out = [f"Gap analysis: N = {self.residuals_before.shape[0]}, g = {self.g} m/s², "
               f"stated σ² = {self.noise_var[0]:.4g}, {self.noise_var[1]:.4g} (m/s²)²"]
        c = self.criterion
        out.append(f"criterion: forward LR selection, family α = {c['family_alpha']:g}, "
                   f"{c['n_tests']} tests, per-step α = {c['alpha_step']:.3g} (Bonferroni)")
        out.append("gap before (nominal: bias + scale):")
        for a in AXES:
            m = self.gap_before[a]
            out.append(f"  {a}: χ²/dof = {m.chi2_dof:.4f}, max signature z = "
                       f"{m.max_signature_z:.2f} ({m.worst}, p = {m.max_signature_p:.3g})")
        if self.effects:
            out.append("named effects:")
            out += [f"  {e}" for e in self.effects]
        else:
            out.append("named effects: none — the nominal model explains the data within the "
                       "stated noise")
        for d in self.not_identifiable:
            out.append(f"  not identifiable: {' / '.join(d['names'])}: {d['reason']}")
        if self.needs_timing:
            out.append(f"  skipped (need t or --rate): {', '.join(self.needs_timing)}")
        out.append("gap after (extended model fitted here):")
        for a in AXES:
            m = self.gap_after_fit[a]
            out.append(f"  {a}: χ²/dof = {m.chi2_dof:.4f}, max signature z = "
                       f"{m.max_signature_z:.2f} ({m.worst}, p = {m.max_signature_p:.3g})")
        return "\n".join(out)


# ------------------------------------------------------------------- the estimation

def _ratio(c: float, s: float, cov2: np.ndarray) -> tuple[float, float]:
    """``c / (1 + s)`` and its delta-method std; ``cov2`` = cov of (s, c)."""
    v = c / (1.0 + s)
    grad = np.array([-c / (1.0 + s) ** 2, 1.0 / (1.0 + s)])
    return v, float(np.sqrt(max(grad @ cov2 @ grad, 0.0)))


def quantized_moments(mu: np.ndarray, sigma2: float, lsb: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of ``lsb·round((μ + v)/lsb)``, v ~ N(0, σ²), per sample.

    Sums over the lattice points within ±8σ of μ (the rest has probability < 1e-15).
    """
    s = np.sqrt(sigma2)
    if s == 0:
        return lsb * np.floor(mu / lsb + 0.5), np.zeros_like(mu)
    span = int(np.ceil(8 * s / lsb)) + 1
    base = np.floor(mu / lsb + 0.5)
    m1 = np.zeros_like(mu)
    m2 = np.zeros_like(mu)
    for j in range(-span, span + 1):
        level = (base + j) * lsb
        p = (stats.norm.cdf((level + lsb / 2 - mu) / s)
             - stats.norm.cdf((level - lsb / 2 - mu) / s))
        m1 += p * level
        m2 += p * level * level
    return m1, np.maximum(m2 - m1 * m1, 1e-300)


class _Reporter:
    """Final fit of a model: parameters with covariance, effect estimates, residuals."""

    def __init__(self, ext: Extensions, state: ModelState) -> None:
        self.ext, self.state, self.run = ext, state, ext.run
        self._fit()

    def _axis_rows(self, k: int, gain: float) -> tuple[np.ndarray, np.ndarray, list[str],
                                                       np.ndarray | None]:
        ext, st = self.ext, self.state.axes[k]
        r = ext.reference(k, st.tau, st.limit)
        names, cols = ext.columns(k, st)
        parts = [self.run.datos[:, k] - r, np.ones_like(r), r, *cols]
        pnames = ["bias", "scale", *names]
        a = self.run.a_ref[:, k]
        if np.isfinite(st.limit):  # Gauss-Newton column: d mean / dL
            parts.append(gain * ext._filter(np.sign(a) * (np.abs(a) > st.limit), st.tau))
            pnames.append("d_limit")
        if st.tau > 0:
            eps = 1e-3
            d = (ext.reference(k, st.tau * (1 + eps), st.limit)
                 - ext.reference(k, st.tau * (1 - eps), st.limit)) / (2 * eps * st.tau)
            parts.append(gain * d)
            pnames.append("d_tau")
        if self.state.tilt:
            parts.append(ext.tilt_column(k, st))
        z = np.column_stack(parts)
        if st.q > 0:  # differenced and whitened: the bias drops out (smoother gives it)
            w = ext.whiten(st, z)
            w = np.delete(w, 1, axis=1)
            pnames = pnames[1:]
        else:
            w = z / np.sqrt(st.sigma2_eff)
        tilt = w[:, -1] if self.state.tilt else None
        h = w[:, 1:-1] if self.state.tilt else w[:, 1:]
        return w[:, 0], h, [f"{AXES[k]}.{n}" for n in pnames], tilt

    def _fit(self) -> None:
        ext, state = self.ext, self.state
        base = ext.fit(state).fit
        gains = [1.0 + float(base.params[base.param_names.index(f"{a}.scale")]) for a in AXES]
        rows = [self._axis_rows(k, gains[k]) for k in range(2)]
        ys = [r[0] for r in rows]
        hs = [r[1] for r in rows]
        names = rows[0][2] + rows[1][2]
        h = sla.block_diag(*hs)
        if state.tilt:
            h = np.column_stack([h, np.concatenate([rows[0][3], rows[1][3]])])
            names.append("sin_tilt")
        fit = fit_linear(h, np.concatenate(ys), tuple(names), sigma2=1.0, intercept=None)
        params, cov = np.array(fit.params), np.array(fit.cov)
        self.gn_std = {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(names)
                       if n.endswith(("d_limit", "d_tau"))}
        keep = [i for i, n in enumerate(names) if not n.endswith(("d_limit", "d_tau"))]
        names = [names[i] for i in keep]
        params, cov = params[keep], cov[np.ix_(keep, keep)]
        self.innov: dict[int, np.ndarray] = {}
        for k in range(2):  # random-walk axes: bias at t0 from the smoother
            st = state.axes[k]
            if st.q <= 0:
                continue
            mean_nb = self._mean(k, names, params, with_bias=False)
            innov, b0, vb0 = walk_filter(self.run.datos[:, k] - mean_nb, st.sigma2_eff,
                                          st.q**2 * self.run.dt_walk)
            self.innov[k] = innov
            at = names.index(f"{AXES[k]}.scale")
            names.insert(at, f"{AXES[k]}.bias")
            params = np.insert(params, at, b0)
            cov = np.insert(np.insert(cov, at, 0.0, axis=0), at, 0.0, axis=1)
            cov[at, at] = vb0
        self.names, self.params, self.cov = names, params, cov

    def value(self, name: str) -> float:
        return float(self.params[self.names.index(name)]) if name in self.names else 0.0

    def _mean(self, k: int, names: list[str], params: np.ndarray, with_bias: bool = True
              ) -> np.ndarray:
        def val(n: str) -> float:
            return float(params[names.index(n)]) if n in names else 0.0

        ax = AXES[k]
        ext, st = self.ext, self.state.axes[k]
        r = ext.reference(k, st.tau, st.limit)
        cnames, cols = ext.columns(k, st)
        mean = r * (1.0 + val(f"{ax}.scale"))
        if with_bias:
            mean = mean + val(f"{ax}.bias")
        for n, c in zip(cnames, cols, strict=True):
            mean = mean + val(f"{ax}.{n}") * c
        if self.state.tilt:
            mean = mean + val("sin_tilt") * ext.tilt_column(k, st)
        return mean

    def mean(self, k: int) -> np.ndarray:
        return self._mean(k, self.names, self.params)

    def residual_after(self, k: int) -> np.ndarray:
        """Whitened residual of axis k scaled to m/s² (variance σ²_eff under the model)."""
        st = self.state.axes[k]
        s2 = st.sigma2_eff
        if st.q > 0:
            return self.innov[k] * np.sqrt(s2)
        y, mu = self.run.datos[:, k], self.mean(k)
        if st.lsb > 2.0 * np.sqrt(st.sigma2):  # Sheppard no longer holds: exact moments
            m1, var = quantized_moments(mu, st.sigma2, st.lsb)
            return (y - m1) * np.sqrt(s2 / var)
        return y - mu

    def cov_of(self, *names: str) -> np.ndarray:
        idx = [self.names.index(n) for n in names]
        return self.cov[np.ix_(idx, idx)]


def _estimate(rep: _Reporter, name: str, axis: str, lattice: list[Lattice], q_unc: dict
              ) -> tuple[dict, dict]:
    """Catalog parameters (and std) of one named effect from the final fit.

    ``q_unc``: axis index → (std, interval) of the random-walk q (:func:`_q_uncertainty`).
    """
    run, state = rep.run, rep.state
    if name == "tilt_offset":
        s = rep.value("sin_tilt")
        sd = float(np.sqrt(rep.cov_of("sin_tilt")[0, 0]))
        d = float(np.arcsin(np.clip(s, -1, 1)))
        return {"delta": d}, {"delta": sd / np.cos(d)}
    k = AXES.index(axis)
    st = state.axes[k]
    sc = f"{axis}.scale"
    s = rep.value(sc)
    if name == "misalignment":
        cn = f"{axis}.c_mis"
        c = rep.value(cn)
        den = (1 + s) ** 2 + c * c
        grad = np.array([-c / den, (1 + s) / den])
        sd = float(np.sqrt(max(grad @ rep.cov_of(sc, cn) @ grad, 0.0)))
        return {"delta": float(np.arctan2(c, 1 + s))}, {"delta": sd}
    if name in ("nonlinearity_k2", "cross_axis"):
        cn = f"{axis}.{LINEAR_COLUMNS[name][0]}"
        key = "k2" if name == "nonlinearity_k2" else "k_ip"
        v, sd = _ratio(rep.value(cn), s, rep.cov_of(sc, cn))
        return {key: v}, {key: sd}
    if name == "bias_drift":
        cn = f"{axis}.c_drift"
        key = "rate" if run.time_unit == "s" else "rate_per_sample"
        return {key: rep.value(cn)}, {key: float(np.sqrt(rep.cov_of(cn)[0, 0]))}
    if name == "lever_arm":
        w2, al = f"{axis}.c_w2", f"{axis}.c_alpha"
        c = rep.cov_of(sc, w2, al)
        vw, sw = _ratio(rep.value(w2), s, c[np.ix_([0, 1], [0, 1])])
        va, sa = _ratio(rep.value(al), s, c[np.ix_([0, 2], [0, 2])])
        if axis == "x":  # x: -ω² pos_x + α pos_z
            return {"pos_x": -vw, "pos_z": va}, {"pos_x": sw, "pos_z": sa}
        return {"pos_x": va, "pos_z": vw}, {"pos_x": sa, "pos_z": sw}  # y: ω² pos_z + α pos_x
    if name == "lowpass_lag":
        return {"tau": st.tau}, {"tau": rep.gn_std[f"{axis}.d_tau"]}
    if name == "saturation":
        return {"limit": st.limit}, {"limit": rep.gn_std[f"{axis}.d_limit"]}
    if name == "bias_random_walk":
        key = "q" if run.time_unit == "s" else "q_per_sample"
        return {key: st.q}, {key: q_unc[k][0]}
    if name == "noise_level":
        dof = run.n - rep.ext.n_params(state, k)
        return {"sigma2": st.sigma2}, {"sigma2": st.sigma2 * float(np.sqrt(2.0 / dof))}
    if name == "quantization":
        lat = lattice[k]
        return {"lsb": lat.lsb}, {"lsb": lat.lsb_std}
    raise ValueError(name)


Q_LEVEL = 0.95
"""Level of the profile-likelihood interval reported for the random-walk intensity q."""


def _q_curvature_std(ext: Extensions, state: ModelState, k: int) -> float:
    """std of q from the curvature of the REML -2 log L at q̂ (others fixed): 2 / (d²/dq²).

    Used as the search scale of :func:`_q_profile_interval` (and measured against it in
    ``benchmarks/gap_uncertainty_mc.py``); NaN when the curvature is not positive.
    """
    st = state.axes[k]
    q = st.q
    vals = []
    for h in (0.1, 0.03):
        f = [ext.nll(state.with_axis(k, replace(st, q=q * (1 + d))), reml=True)
             for d in (-h, 0.0, h)]
        curv = (f[0] - 2 * f[1] + f[2]) / (h * q) ** 2
        if curv > 0:
            vals.append(float(np.sqrt(2.0 / curv)))
    return vals[-1] if vals else float("nan")


def _q_profile_interval(ext: Extensions, state: ModelState, k: int, level: float = Q_LEVEL
                        ) -> tuple[float, float]:
    """Profile-likelihood (REML) interval of the random-walk intensity q of axis k.

    ``{q ≥ 0 : D(q) ≤ χ²₁(level)}`` with ``D(q) = -2 log L_R(q) + 2 log L_R(q̂)`` the REML
    deviance (linear parameters integrated out; the other nonlinear parameters, and σ² when
    ``noise_level`` is named, held at their estimates: their correlation with q̂ is of order
    ``sqrt(n_eff/N)``, n_eff the few low-frequency modes where the walk beats the noise).
    The ends are found by bracketing on log q from q̂ and Brent's method (xtol 1e-5 in log q).

    Boundary q ≥ 0: when ``D(0) ≤ χ²₁(level)`` the lower end is 0. At a true q = 0 the
    deviance of q = 0 follows a mixture with at least half its mass at 0 (``½χ²₀ + ½χ²₁`` or
    more), so the interval then covers with probability ≥ 1 - (1 - level)/2: conservative.
    An effect named by :func:`analyze_gap` has ``D(0)`` far above the threshold.
    """
    st = state.axes[k]
    q_hat = st.q
    crit = float(stats.chi2.ppf(level, 1))
    f0 = ext.nll(state, reml=True)

    def dev(q: float) -> float:
        return ext.nll(state.with_axis(k, replace(st, q=float(q))), reml=True) - f0

    s = _q_curvature_std(ext, state, k) / q_hat
    s = s if np.isfinite(s) and s > 0 else 0.1
    u0 = float(np.log(q_hat))

    def end(sign: float) -> float:
        d_in, d = 0.0, 1.5 * s
        for _ in range(60):
            if dev(float(np.exp(u0 + sign * d))) > crit:
                u = optimize.brentq(lambda v: dev(float(np.exp(v))) - crit, u0 + sign * d_in,
                                    u0 + sign * d, xtol=1e-5)
                return float(np.exp(u))
            d_in, d = d, 1.6 * d
            if sign < 0 and d > 40.0:  # q < 4e-18 q̂: the root is next to the boundary
                return float(optimize.brentq(lambda q: dev(q) - crit, 0.0,
                                             q_hat * float(np.exp(-d_in)), xtol=1e-12 * q_hat))
        return float("inf")

    lo = 0.0 if dev(0.0) <= crit else end(-1.0)
    return lo, end(1.0)


def _q_uncertainty(ext: Extensions, state: ModelState, k: int
                   ) -> tuple[float, tuple[float, float]]:
    """(std, 95 % interval) reported for the random-walk intensity q of axis k.

    q is a variance component informed only by the few low-frequency modes where the walk
    beats the white noise, so q̂ is skewed (low more often than high). The honest statement is
    the REML profile-likelihood interval (:func:`_q_profile_interval`, asymmetric); the std is
    derived from it, ``std = (high - low) / (2·1.96)`` in q units (the average of its two
    half-widths over the normal quantile), so ``q̂ ± 1.96 std`` spans the same length.

    Chosen by measurement (``benchmarks/gap_uncertainty_mc.py``: analyze_gap end to end,
    static full-turn designs (uniform and 24 held positions), N = 2000-3000, q√N = 1-4 σ,
    six cases of R = 400; a 95 % coverage has the binomial tolerance ±0.044):

    * profile interval: coverage 0.940-0.958, misses 1.3-2.5 % low and 2.3-4 % high;
    * this std: sd((q̂ - q)/std) = 0.97-1.05, mean -0.06 to -0.19, ``q̂ ± 1.96 std`` covers
      0.925-0.953 (the symmetric statement inherits the skew: it misses high more often);
    * the former curvature std (:func:`_q_curvature_std`): about as good on average
      (sd 0.98-1.05; the "1.2×" once stated for it is not reproduced), but its symmetric
      interval covered 0.925-0.95 with misses 0.5-1.5 % low and 4-6 % high; the exact expected
      REML information on log q (spectral form) was no better (sd 1.00-1.07, its log-scale
      Wald interval covered 0.938-0.953; the curvature on log q, 0.943-0.959). The profile
      interval needs no quadratic approximation and handles the boundary q = 0, so it is what
      is reported.

    Falls back to the curvature std if an end of the interval is not finite.
    """
    lo, hi = _q_profile_interval(ext, state, k)
    std = (hi - lo) / (2.0 * float(stats.norm.ppf(0.5 + Q_LEVEL / 2.0)))
    if not np.isfinite(std):
        std = _q_curvature_std(ext, state, k)
    return float(std), (lo, hi)


# ------------------------------------------------------------------------- selection

def _remaining(state: ModelState, candidates: list[tuple[str, str]]) -> list[tuple[str, str]]:
    out = []
    for name, axis in candidates:
        if name == "tilt_offset":
            if not state.tilt:
                out.append((name, axis))
        elif not state.axes[AXES.index(axis)].has(name):
            out.append((name, axis))
    return out


def _try(ext: Extensions, state: ModelState, name: str, axis: str) -> Trial | None:
    try:
        return ext.test(state, name, axis)
    except NotIdentifiableError:
        return None


def _drop(state: ModelState, name: str, axis: str, stated: np.ndarray) -> ModelState:
    if name == "tilt_offset":
        return replace(state, tilt=False)
    k = AXES.index(axis)
    return state.with_axis(k, state.axes[k].remove(name, float(stated[k])))


def _n_effect_params(name: str) -> int:
    return 2 if name == "lever_arm" else 1


def _confusions(ext: Extensions, state: ModelState, stated: np.ndarray,
                candidates: list[tuple[str, str]], untestable: dict) -> list[dict]:
    """``not_identifiable`` entries (see the module docstring).

    Swap test: for each named effect, every other candidate is fitted *in its place*; when
    one explains the data within ``AMBIGUITY_LR`` of the final model (``-2 log L`` + 2 per
    extra parameter, AIC) the pair is reported: this experiment cannot tell them apart.
    """
    out: list[dict] = [{"names": ["gravity_mismatch"], "reason": REASONS["gravity_mismatch"]}]
    mis_axes = [a for k, a in enumerate(AXES) if state.axes[k].has("misalignment")]
    seen: set = set()
    if state.tilt or len(mis_axes) == 2:
        out.append({"names": ["tilt_offset", "misalignment"], "reason": REASONS["tilt_offset"]})
        seen.add(("misalignment", "tilt_offset"))  # already said, for every θ design
    nll_final = ext.nll(state)
    named = state.effects()

    def alt_nll(base: ModelState, adds: list[tuple[str, str]]) -> float:
        s = base
        for n, a in adds:
            t = _try(ext, s, n, a)
            if t is None:
                return np.inf
            s = t.state
        return ext.nll(s)

    def report(pair: tuple[str, str], axis: str, delta: float) -> None:
        key = tuple(sorted(pair))
        if key in seen:
            return
        seen.add(key)
        known = next((REASONS[n] for n in ("bias_drift", "lowpass_lag") if n in pair), None)
        why = known or ("their signatures coincide in this θ design; a wider or denser set of "
                        "angles (a full turn) separates them")
        where = "both axes" if axis == "both" else f"axis {axis}"
        out.append({"names": sorted(pair),
                    "reason": f"{where}: {why} (fitting {pair[1]} in place of {pair[0]} "
                              f"changes -2 log L by {delta:.2f}, less than 2 ln 10)"})

    for name, axis in named:
        if name in ("quantization", "noise_level"):
            continue
        base = _drop(state, name, axis, stated)
        alternatives = [(n, a) for n, a in candidates if (n, a) not in named and n != name
                        and n != "noise_level" and (a == axis or "both" in (a, axis))]
        for alt, alt_axis in alternatives:
            penalty = 2.0 * (_n_effect_params(alt) - _n_effect_params(name))
            delta = alt_nll(base, [(alt, alt_axis)]) + penalty - nll_final
            if delta < AMBIGUITY_LR:
                report((name, alt), axis, delta)
        if name == "tilt_offset" and ext.run.timed and not any(
                n == "lowpass_lag" for n, _ in named):
            delta = alt_nll(base, [("lowpass_lag", a) for a in AXES]) + 2.0 - nll_final
            if delta < AMBIGUITY_LR:
                report(("tilt_offset", "lowpass_lag"), axis, delta)
    for (name, axis), why in untestable.items():
        out.append({"names": [name], "reason": f"axis {axis}: not testable in this experiment "
                                               f"({why})"})
    return out


def analyze_gap(ensayo: Ensayo, noise_var, g: float = G, rate: float | None = None,
                family_alpha: float = 0.005) -> GapAnalysis:
    """Find where the nominal model and a measured calibration run disagree, name the effect.

    Parameters
    ----------
    ensayo : the run: ``tita`` (N,) rad, ``datos`` (N, 2) m/s², optional ``t`` (N,) s;
        samples in time order.
    noise_var : (2,) stated noise variances [σx², σy²], (m/s²)².
    g : gravity, m/s² (course convention ``A_rx = -g sin θ``, ``A_ry = -g cos θ``).
    rate : sample rate, Hz, when ``t`` is missing (``t = k / rate``); without either the
        effects that need timing are skipped (``needs_timing``) and drift / random walk are
        per sample.
    family_alpha : false-alarm probability of the whole selection on a run without any
        effect; the per-step threshold is ``family_alpha / m`` (Bonferroni over the m tests).

    Returns
    -------
    GapAnalysis

    Notes
    -----
    Criterion, reference distributions and the treatment of confusions: module docstring and
    :meth:`calib.effects.Extensions.test`. ``calib`` never sees the bench: this works on the
    measured arrays only.
    """
    if not 0 < family_alpha < 1:
        raise ValueError(f"family_alpha must be in (0, 1), got {family_alpha}")
    run = RunData.build(ensayo.tita, ensayo.datos, noise_var, g, ensayo.t, rate)
    stated = run.sigma2
    nominal = calibrate(ensayo, stated, "ols", g)
    gains = 1.0 + nominal.scale
    ext = Extensions(run, gains)

    lattice = [detect_lattice(run.datos[:, k]) for k in range(2)]
    state = ModelState(tuple(AxisState(sigma2=float(stated[k]),
                                       lsb=lattice[k].lsb if lattice[k].found else 0.0)
                             for k in range(2)))
    needs_timing = () if run.timed else NEEDS_TIMING
    candidates = [(n, a) for n in PER_AXIS_CANDIDATES if n not in needs_timing for a in AXES]
    candidates.insert(2, ("tilt_offset", "both"))

    untestable: dict[tuple[str, str], str] = {}
    first = []
    for name, axis in candidates:
        try:
            first.append(ext.test(state, name, axis))
        except NotIdentifiableError as exc:
            untestable[(name, axis)] = str(exc).split(";")[0]
    candidates = [c for c in candidates if c not in untestable]
    n_tests = len(candidates) + 2
    alpha_step = family_alpha / n_tests
    log_alpha = float(np.log(alpha_step))

    steps: list[dict] = []
    trials = first
    for _ in range(MAX_STEPS):
        if not trials:
            break
        best = min(trials, key=lambda t: t.logp)
        steps.append({"added": [best.name, best.axis] if best.logp < log_alpha else None,
                      "candidates": [[t.name, t.axis, t.lr, t.p_value]
                                     for t in sorted(trials, key=lambda t: t.logp)]})
        if best.logp >= log_alpha:
            break
        state = ext.refine(best.state)
        trials = [t for t in (_try(ext, state, n, a) for n, a in _remaining(state, candidates))
                  if t is not None]

    # One backward pass: drop what the later additions made unnecessary.
    for name, axis in state.effects():
        if name == "quantization":
            continue
        t = _try(ext, _drop(state, name, axis, stated), name, axis)
        if t is not None and t.logp >= log_alpha:
            state = ext.refine(_drop(state, name, axis, stated))
            steps.append({"removed": [name, axis], "p_value": t.p_value})

    rep = _Reporter(ext, state)
    q_unc = {k: _q_uncertainty(ext, state, k) for k in range(2) if state.axes[k].q > 0}
    effects = []
    for name, axis in state.effects():
        params, std = _estimate(rep, name, axis, lattice, q_unc)
        if name == "quantization":
            lat = lattice[AXES.index(axis)]
            stat, p = float(lat.levels), float(np.exp(lat.logp))
        else:
            t = _try(ext, _drop(state, name, axis, stated), name, axis)
            stat, p = (t.lr, t.p_value) if t is not None else (float("nan"), float("nan"))
        interval = {}
        if name == "noise_level":  # (dof·σ̂²/χ²_{0.975}, dof·σ̂²/χ²_{0.025})
            dof = run.n - ext.n_params(state, AXES.index(axis))
            lo, hi = dof * params["sigma2"] / stats.chi2.ppf([0.975, 0.025], dof)
            interval = {"sigma2": (float(lo), float(hi))}
        if name == "bias_random_walk":  # REML profile-likelihood interval (_q_uncertainty)
            interval = {next(iter(params)): q_unc[AXES.index(axis)][1]}
        effects.append(EffectEstimate(name, axis, params, std, float(stat), float(p), interval))

    resid_before = np.column_stack([nominal.fits[a].residuals for a in AXES])
    resid_after = np.column_stack([rep.residual_after(k) for k in range(2)])
    fitted = np.column_stack([rep.mean(k) for k in range(2)])
    before, after = {}, {}
    for k, a in enumerate(AXES):
        common = dict(t=run.t, other_ref=run.a_ref[:, 1 - k], own_ref=run.a_ref[:, k],
                      readings=run.datos[:, k])
        before[a] = gap_measure(resid_before[:, k], run.tita, float(stated[k]), n_params=2,
                                **common)
        st = state.axes[k]
        after[a] = gap_measure(resid_after[:, k], run.tita, st.sigma2_eff,
                               model_lsb=st.lsb if st.lsb > 0 else None,
                               n_params=ext.n_params(state, k), **common)

    nonlinear = {}
    for k, a in enumerate(AXES):
        st = state.axes[k]
        if st.tau > 0:
            nonlinear[f"{a}.tau"] = (st.tau, rep.gn_std[f"{a}.d_tau"])
        if np.isfinite(st.limit):
            nonlinear[f"{a}.limit"] = (st.limit, rep.gn_std[f"{a}.d_limit"])
        if st.q > 0:
            nonlinear[f"{a}.q"] = (st.q, q_unc[k][0])
        if st.noise_free:
            dof = run.n - ext.n_params(state, k)
            nonlinear[f"{a}.sigma2"] = (st.sigma2, st.sigma2 * float(np.sqrt(2.0 / dof)))
    final = ExtendedModel(tuple(rep.names), rep.params, rep.cov, nonlinear,
                          (state.axes[0].sigma2_eff, state.axes[1].sigma2_eff),
                          (state.axes[0].sigma2, state.axes[1].sigma2), state,
                          (float(gains[0]), float(gains[1])), run.time_unit)
    criterion = {"rule": "forward likelihood-ratio selection, Bonferroni per-step threshold",
                 "family_alpha": float(family_alpha), "alpha_step": float(alpha_step),
                 "n_tests": int(n_tests)}
    return GapAnalysis(
        effects=tuple(effects),
        not_identifiable=tuple(_confusions(ext, state, stated, candidates, untestable)),
        gap_before=before, gap_after_fit=after, nominal=nominal, final=final,
        residuals_before=resid_before, residuals_after=resid_after, fitted=fitted,
        needs_timing=tuple(needs_timing), criterion=criterion, steps=tuple(steps), g=float(g),
        noise_var=(float(stated[0]), float(stated[1])))


# ------------------------------------------------------------------------- prediction

def predict(analysis: GapAnalysis, tita: np.ndarray, t: np.ndarray | None = None,
            rate: float | None = None) -> np.ndarray:
    """Mean reading of the extended model, ``A_m_hat(θ, t)`` (N, 2), m/s².

    Parameters
    ----------
    analysis : the result of :func:`analyze_gap` (its ``final`` model).
    tita : (N,) encoder angle, rad.  t : (N,) sample times, s, or ``rate`` (Hz): needed when
        the model has a low-pass, a lever arm or a drift per second.

    Notes
    -----
    ``bias + (1 + s)·[LPF_τ(clip(A_r(θ), ±L)) + extensions] + rate·(t - t0)``; a random walk
    (zero mean) and the rounding of a quantization are not included (the rounding changes the
    mean by less than ``lsb·e^{-2π²σ²/lsb²}``). The drift starts at the first sample of
    ``tita``. On the analysed run this equals ``analysis.fitted``.
    """
    final = analysis.final
    tita = np.asarray(tita, dtype=float)
    run = RunData.build(tita, np.zeros((tita.size, 2)), analysis.noise_var, analysis.g, t,
                        rate)
    for k, a in enumerate(AXES):
        st = final.state.axes[k]
        needs = st.tau > 0 or "lever_arm" in st.linear or (
            "bias_drift" in st.linear and final.time_unit == "s")
        if needs and not run.timed:
            raise ValueError(f"axis {a}: the extended model needs sample times (t or rate) "
                             "to predict (low-pass, lever arm or drift per second)")
    ext = Extensions(run, np.asarray(final.gains))
    rep = _Reporter.__new__(_Reporter)
    rep.ext, rep.state, rep.run = ext, final.state, run
    rep.names, rep.params = list(final.names), np.asarray(final.params)
    return np.column_stack([rep.mean(k) for k in range(2)])


__all__ = ["analyze_gap", "gap_measure", "predict", "GapAnalysis", "GapMeasure",
           "EffectEstimate", "ExtendedModel", "PER_AXIS_CANDIDATES", "EFFECT_NAMES",
           "lowpass"]
