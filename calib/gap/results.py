"""Result types of the discrepancy workflow: a named effect, the extended model, the analysis."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from calib.calibration.tilt_plane import Calibration
from calib.conventions import AXES, G
from calib.effects import ModelState
from calib.units import effect_units, format_estimate, format_p, format_stat, with_units


def _finite(x: float) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


POOLED_WORDS = " (both axes pooled)"
"""Said after the statistic of a noise level named on both axes at once."""


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
    (high - low)/(2·1.96), see :func:`q_uncertainty`)."""
    tentative: bool = False
    """True when the final model fails adequacy (verdict "unexplained"): the effect is named,
    but something not in the model remains, so its estimate may be biased by it."""
    pooled: bool = False
    """True for a noise level named on both axes at once: ``statistic`` and ``p_value`` are
    the pair's pooled test (both axes' χ² summed, :mod:`calib.effects.noise`), the same on
    both axes' lines."""

    def to_dict(self) -> dict:
        """``{"name", "axis", "params", "std", "statistic", "p_value"}`` (documented JSON),
        plus ``"interval": {key: [low, high]}`` only for an effect that has one, and
        ``"pooled": true`` only for a noise level named on both axes at once (additive)."""
        out = {"name": self.name, "axis": self.axis,
               "params": {k: float(v) for k, v in self.params.items()},
               "std": {k: float(v) for k, v in self.std.items()},
               # null when the drop-one test cannot be made in this design (not a number)
               "statistic": _finite(self.statistic), "p_value": _finite(self.p_value),
               "tentative": bool(self.tentative)}
        if self.interval:
            out["interval"] = {k: [float(lo), float(hi)] for k, (lo, hi) in self.interval.items()}
        if self.pooled:
            out["pooled"] = True
        return out

    def __str__(self) -> str:
        """``misalignment (x): delta = 0.01952 ± 0.0012 rad; statistic = 265.3, p < 1e-300``
        (units from :data:`calib.conventions.EFFECTS`; an underflowed p printed as a bound)."""
        units = effect_units()
        vals = ", ".join(f"{k} = " + format_estimate(v, self.std.get(k, float("nan")),
                                                      units.get(k, ""))
                         for k, v in self.params.items())
        ci = "".join(f"; 95% interval of {k}: [{lo:.6g}, {hi:.6g}] {units.get(k, '')}".rstrip()
                     for k, (lo, hi) in self.interval.items())
        stat = format_stat(self.statistic) + (POOLED_WORDS if self.pooled else "")
        return (f"{self.name} ({self.axis}): {vals}{ci}; statistic = {stat}, "
                f"{format_p(self.p_value)}")


def gap_units() -> dict[str, str]:
    """The ``units`` of :meth:`GapAnalysis.to_dict` (the bench's ``gap --json`` extends it):
    effect parameters in their catalog units (:data:`calib.conventions.EFFECTS`, under
    ``effects.params`` / ``std`` / ``interval``), statistics, z's, χ²/dof, α's and p-values
    dimensionless, a signature's ``size`` in the unit its entry names (``"@unit"``)."""
    out = {f"effects.*.{k}": u for k, u in effect_units().items()}
    # only alike: the units of other keys (validation/independent/cases.py has its own)
    out.update({
        "effects.statistic": "1", "effects.p_value": "1",
        "gap_before.*.chi2_dof": "1", "gap_before.*.max_signature_z": "1",
        "gap_after.*.chi2_dof": "1", "gap_after.*.max_signature_z": "1",
        "criterion.n_tests": "count", "criterion.*": "1",
        "unexplained.size": "@unit", "unexplained.statistic": "1", "unexplained.p_value": "1",
        "adequacy.family_alpha": "1", "adequacy.alpha_check": "1",
        "adequacy.checks.size": "@unit", "adequacy.checks.statistic": "1",
        "adequacy.checks.p_value": "1",
        "adequacy.walk.lr": "1", "adequacy.walk.charge": "count",
        "adequacy.walk.criterion": "1", "adequacy.walk.rivals.lr": "1",
        "adequacy.walk.rivals.charge": "count", "adequacy.walk.rivals.criterion": "1",
        "adequacy.walk.rivals.size": "m/s²",
        "adequacy.walk.cycle.gain": "1", "adequacy.walk.cycle.share": "1",
        "adequacy.walk.cycle.walk_beyond_lr": "1", "adequacy.walk.cycle.walk_beyond_p": "1",
        "adequacy.walk.cycle.size": "m/s²",
        "adequacy.walk.steps.gain": "1", "adequacy.walk.steps.share": "1",
        "adequacy.walk.steps.walk_beyond_lr": "1", "adequacy.walk.steps.walk_beyond_p": "1",
        "adequacy.walk.steps.size": "m/s²", "adequacy.walk.steps.count": "count",
        "adequacy.walk.steps.margin": "1", "adequacy.walk.steps.levels": "m/s²",
        "adequacy.walk.steps.rates_per_sample": "1/sample",
        "adequacy.sponges.statistic": "1", "adequacy.sponges.p_value": "1",
        "adequacy.asymmetry.gain": "1", "adequacy.asymmetry.asymmetry": "1",
        "adequacy.asymmetry.size": "m/s²",
        "adequacy.cubic.gain": "1", "adequacy.cubic.k3": "1/(m/s²)²",
        "adequacy.cubic.size": "m/s²",
        "adequacy.step.gain": "1", "adequacy.step.step": "m/s²", "adequacy.step.size": "m/s²",
        "adequacy.step.at": "s (the sample index without timing)",
        "adequacy.drive_bias.gain": "1", "adequacy.drive_bias.size": "m/s²",
        "adequacy.drive_bias.coefficient": "m/s² per unit of the column: rad/s (speed_bias), "
                                           "1 (move_bias), rad/s² (accel_bias)",
        "adequacy.drive_noise.gain": "1", "adequacy.drive_noise.size": "m/s²",
        "adequacy.drive_noise.moving_std": "m/s²", "adequacy.drive_noise.stated_std": "m/s²",
        "reported.change": "σ", **{f"reported.*.{k}": u for k, u in effect_units().items()},
        "criterion.profile.rate_random_walk.*.value": "m/s²/√s",
        "criterion.profile.rate_random_walk.*.interval": "m/s²/√s",
        "criterion.profile.rate_random_walk.*.level": "1",
    })
    return out


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
    verdict : "explained" (effects named and the final model passes adequacy),
        "unexplained" (adequacy fails: structure remains that the named effects do not
        explain) or "nothing_detected" (nothing named and adequacy passes, at ``alpha``).
    unexplained : one dict per failed adequacy check: ``{"axis", "signature", "size",
        "unit", "statistic", "p_value", "description"}`` (description in words a test
        engineer can act on, e.g. "a 3rd harmonic of θ on x, 0.04 m/s²").
    adequacy : ``{"family_alpha", "alpha_check", "checks": [{"name", "axis", "statistic",
        "p_value", "passed", ...}]}``: the battery run on the final model.
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
    verdict: str = "nothing_detected"
    unexplained: tuple[dict, ...] = ()
    adequacy: dict = field(default_factory=dict)
    reported: tuple[dict, ...] = ()
    """Effects seen but not named: they change the fit by less than
    :data:`calib.gap.practical.PRACTICAL_FRACTION` of σ (they stay in the model). One dict
    each: ``{"name", "axis", "params", "std", "change" (fraction of σ), "unit",
    "description"}`` ("quantized at q = … m/s² (… σ), no effect on the fit")."""

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
        replaces it by the re-simulated gap), plus ``needs_timing`` and ``criterion``, and
        ``units`` (:func:`gap_units`)."""
        return with_units({
            "effects": [e.to_dict() for e in self.effects],
            "not_identifiable": [{"names": list(d["names"]), "reason": d["reason"]}
                                 for d in self.not_identifiable],
            "gap_before": {a: self.gap_before[a].to_dict() for a in AXES},
            "gap_after": {a: self.gap_after_fit[a].to_dict() for a in AXES},
            "needs_timing": list(self.needs_timing),
            "criterion": dict(self.criterion),
            "verdict": self.verdict,
            "unexplained": [dict(u) for u in self.unexplained],
            "adequacy": dict(self.adequacy),
            "reported": [dict(r) for r in self.reported],
        }, gap_units())

    def model_lsb(self, axis: str) -> float | None:
        """The quantization step in the model of ``axis`` (named or only reported), m/s², or
        None: what the gap measures are told explains a lattice of the readings."""
        for e in (*self.effects, *self.reported):
            name = e.name if isinstance(e, EffectEstimate) else e["name"]
            ax = e.axis if isinstance(e, EffectEstimate) else e["axis"]
            params = e.params if isinstance(e, EffectEstimate) else e["params"]
            if name == "quantization" and ax == axis:
                return float(params["lsb"])
        return None

    def verdict_line(self) -> str:
        """The verdict in one sentence (first line of every report)."""
        c = self.criterion
        alpha = c.get("family_alpha", 0.005) + c.get("adequacy_alpha", 0.0)
        if self.verdict == "unexplained":
            return (f"verdict: unexplained structure remains ({len(self.unexplained)} "
                    f"signature(s)); the named effects are tentative")
        if self.verdict == "explained":
            return (f"verdict: explained: the named effects account for the gap, and no "
                    f"adequacy check fails at α = {alpha:g}")
        return (f"verdict: nothing detected at α = {alpha:g} (selection "
                f"{c.get('family_alpha', 0.005):g} + adequacy {c.get('adequacy_alpha', 0.0):g})")

    def summary(self) -> str:
        out = [self.verdict_line(),
               f"Gap analysis: N = {self.residuals_before.shape[0]}, g = {self.g} m/s², "
               f"stated σ² = {self.noise_var[0]:.4g}, {self.noise_var[1]:.4g} (m/s²)²"]
        c = self.criterion
        for line in (c.get("profile") or {}).get("terms_from_profile", []):
            out.append(f"from the sensor profile: {line}")
        out.append(f"criterion: forward LR selection, family α = {c['family_alpha']:g}, "
                   f"{c['n_tests']} tests, per-step α = {c['alpha_step']:.3g} (Bonferroni); "
                   "structured effects first, a random walk only when it beats them")
        out.append("gap before (nominal: bias + scale):")
        for a in AXES:
            m = self.gap_before[a]
            out.append(f"  {a}: χ²/dof = {m.chi2_dof:.4f}, max signature z = "
                       f"{m.max_signature_z:.2f} ({m.worst}, {format_p(m.max_signature_p)})")
        if self.effects:
            out.append("named effects" + (" (tentative)" if self.verdict == "unexplained"
                                          else "") + ":")
            out += [f"  {e}" + (" (tentative)" if e.tentative else "") for e in self.effects]
        else:
            out.append("named effects: none")
        for r in self.reported:
            out.append(f"  reported, not named: {r['description']}")
        if self.unexplained:
            out.append("unexplained structure remains:")
            for u in self.unexplained:
                p = "" if u.get("p_value") is None else f", {format_p(u['p_value'])}"
                out.append(f"  {u['description']} [{u['signature']}, statistic "
                           f"{u['statistic']:.4g}{p}]")
        for d in self.not_identifiable:
            out.append(f"  not identifiable: {' / '.join(d['names'])}: {d['reason']}")
        if self.needs_timing:
            out.append(f"  skipped (need t or --rate): {', '.join(self.needs_timing)}")
        out.append("gap after (extended model fitted here, against the stated noise):")
        for a in AXES:
            m = self.gap_after_fit[a]
            out.append(f"  {a}: χ²/dof = {m.chi2_dof:.4f}, max signature z = "
                       f"{m.max_signature_z:.2f} ({m.worst}, {format_p(m.max_signature_p)})")
        return "\n".join(out)

