"""Ground-truth validation of calibration estimates made by any tool.

Input: the ``truth.json`` of a generated set and an ``est.json`` (format in
``docs/validate.md``): the ``calibrate --json`` object, or a minimal form with only bias and
scale per axis. Output: per-parameter z-scores against the true values and a verdict.

Definitions
-----------
Parameters ``p = [bias_x, scale_x, bias_y, scale_y]``, estimates ``p̂``, true values ``p*``
(from ``truth.json``: ``sensor.{x,y}.{bias,scale}``), covariance ``Σ`` of the estimates.

* ``z_i = (p̂_i − p*_i) / sqrt(Σ_ii)``; parameter i *passes* when ``|z_i| ≤ q`` with
  ``q = Φ⁻¹((1 + L)/2)`` (two-sided normal quantile at the level L).
* The **verdict** is the joint test ``d² = (p̂ − p*)ᵀ Σ⁻¹ (p̂ − p*) ≤ χ²₄(L)``. For the
  course model with Gaussian noise and known σ², ``p̂ − p* ~ N(0, Σ)`` exactly, so ``d²`` is
  χ² with 4 degrees of freedom and an honest estimator passes with probability exactly L
  (each single parameter also with probability L). With σ² estimated from the residuals the
  statement holds asymptotically (error O(1/N)).

Where Σ comes from (``std_source``):

* ``reported`` — ``est.json`` gives ``cov`` (2×2 per axis, order [bias, scale]) or at least
  ``bias_std`` / ``scale_std``. With only the standard deviations, the correlation between
  bias and scale is taken from the design (when it can be computed) — the reported stds are
  kept.
* ``design`` — recomputed as the per-axis OLS covariance ``σ² (HᵀH)⁻¹``, ``H = [1, A_r(θ)]``,
  with the true σ² of ``truth.json`` and θ from ``--ensayo`` (the actual run) or rebuilt
  from the design in ``truth.json`` (``theta_design``; for sweeps the commanded profile at
  the sample times, an approximation of the encoder angles). The two axes are independent
  (diagonal noise). Used for the minimal form, or on request.

Exit codes of ``tiltbench validate``: 0 pass, 1 fail, 2 bad input. The JSON inputs and their
schemas: :mod:`bench.validate_inputs` (re-exported here).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import stats

from bench.limits import available_memory
from bench.validate_inputs import (
    Truth,
    check_answer_key,
    check_schema,
    json_path,
    load_json,
    parse_estimates,
    read_truth,
    short,
    true_sensor_params,
)
from calib.conventions import AXES, JOINT_PARAM_NAMES, G, reference_accel
from calib.files.course import DataError
from calib.results import ResultMixin
from calib.units import with_units

StdSource = Literal["auto", "reported", "design"]


BYTES_PER_SAMPLE = 160
"""Peak memory of rebuilding θ and its design covariance, per sample (measured with
``tracemalloc`` at N = 10⁶: 159 B for a static range, 152 B for a sweep)."""


def design_size(truth: Mapping, name: str = "truth.json") -> tuple[int, str]:
    """Sample count N of the design in ``truth.json`` and the field it comes from, computed
    without building θ. :class:`DataError` when there is no design."""
    t = read_truth(truth, name)
    if t.design is None:
        raise DataError(f"{name}: no 'theta_design' or 'sweep' found to rebuild θ; pass "
                        "--ensayo ENSAYO.mat (the run the estimates came from)")
    d, at = t.design, json_path(t.design_at)
    if t.static:
        kind = d.get("kind", "range")
        if kind == "range":
            return int(d.get("count", 20001)), f"{at}.count = {short(d.get('count', 20001))}"
        if kind == "list":
            return len(d["values"]), f"{at}.values ({len(d['values'])} angles)"
        n = int(d["positions"]) * int(d["per_position"])
        return n, f"{at}.positions × per_position = {d['positions']} × {d['per_position']}"
    samples = float(d.get("duration", 20.0)) * float(d.get("rate", 100.0))
    label = f"{at}.duration × rate = {short(d.get('duration', 20.0))} s × " \
            f"{short(d.get('rate', 100.0))} Hz"
    if not math.isfinite(samples) or samples > 2**62:
        return 2**62, label
    return int(math.floor(samples + 1e-9)) + 1, label


def _check_memory(n: int, label: str, name: str) -> None:
    need, avail = n * BYTES_PER_SAMPLE, available_memory()
    if need > avail:
        raise DataError(f"{name}: {label} means {n:,} samples; rebuilding θ and its design "
                        f"covariance needs {need / 2**30:,.1f} GiB, this machine has "
                        f"{avail / 2**30:,.1f} GiB available")


def design_theta(truth: Mapping, name: str = "truth.json") -> np.ndarray:
    """θ (rad) of the calibration run, rebuilt from the design recorded in ``truth.json``.

    Static runs: exact (:class:`bench.tilt.ThetaDesign` ``angles()``; the encoder reads the
    pose exactly). Sweeps: the commanded profile at the sample times (approximate: the
    encoder lags the command slightly). Raises :class:`DataError` when no design is found,
    when it is malformed (the message names the field) or when it needs more memory than is
    available (the size is checked before anything is allocated).
    """
    from bench.tilt import SweepProfile, ThetaDesign

    n, label = design_size(truth, name)
    _check_memory(n, label, name)
    t = read_truth(truth, name)
    d = dict(t.design)
    if t.static:
        if "values" in d:
            d["values"] = tuple(float(v) for v in d["values"])
        for k in ("count", "positions", "per_position"):
            if k in d:
                d[k] = int(d[k])
        return ThetaDesign(**d).angles()
    prof = SweepProfile(**{k: (v if k == "kind" else float(v)) for k, v in d.items()})
    return prof.command(np.arange(n) / prof.rate)


def design_cov(theta: np.ndarray, noise_var, g: float = G) -> np.ndarray:
    """4×4 covariance of per-axis OLS ``[bias_x, scale_x, bias_y, scale_y]``, σ² known.

    ``σ_a² (H_aᵀH_a)⁻¹`` per axis with ``H_a = [1, A_r,a(θ)]`` (computed by
    :func:`calib.calibration.ls.fit_linear` through QR, never by inverting HᵀH); zero across axes.
    """
    from calib.calibration.ls import fit_linear

    theta = np.asarray(theta, dtype=float)
    a_r = reference_accel(theta, g)
    cov = np.zeros((4, 4))
    for k in range(2):
        H = np.column_stack([np.ones_like(a_r[:, k]), a_r[:, k]])
        fit = fit_linear(H, np.zeros(theta.size), ("bias", "scale"), float(noise_var[k]))
        cov[2 * k:2 * k + 2, 2 * k:2 * k + 2] = fit.cov
    return cov


STD_ALPHA = 1e-6
"""False-alarm probability of the std check for an honest estimator (two-sided)."""
STD_FACTOR = 2.0
"""Smallest accepted spread of reported/design std: [1/STD_FACTOR, STD_FACTOR]."""


def std_ratio_limits(n: int, p: int = 2) -> tuple[float, float]:
    """Accepted range of (reported std)/(design std) for an honest per-axis fit of N samples.

    Notes
    -----
    With σ² known the OLS covariance is ``σ²(HᵀH)⁻¹`` exactly, the design covariance: the
    ratio is 1. With σ² estimated from the residuals, ``s²/σ² ~ χ²_ν/ν`` with ``ν = N − p``
    (p = 2: bias and scale), so the ratio ``s/σ`` lies in
    ``[sqrt(χ²_ν(α/2)/ν), sqrt(χ²_ν(1 − α/2)/ν)]`` except with probability α = 10⁻⁶
    (:data:`STD_ALPHA`). That interval is 1 ± 0.025 at N = 20001 — too tight for honest tools
    that round the std, weight the samples, use the encoder θ of a sweep instead of the
    commanded one, or absorb unmodelled effects into σ²; so the accepted range is the union
    with the fixed factor ``[1/2, 2]`` (:data:`STD_FACTOR`), which only the χ² interval widens
    (N ≲ 30). A reported std 2× too large shrinks d² by 4 (an estimate 2σ off looks 1σ off):
    the largest loss of power accepted. An honest estimator fails this check with probability
    ≤ 10⁻⁶, so the verdict still passes with probability L (to 10⁻⁶).
    """
    nu = max(int(n) - p, 1)
    lo = math.sqrt(float(stats.chi2.ppf(STD_ALPHA / 2, nu)) / nu)
    hi = math.sqrt(float(stats.chi2.ppf(1 - STD_ALPHA / 2, nu)) / nu)
    return min(lo, 1 / STD_FACTOR), max(hi, STD_FACTOR)


@dataclass(frozen=True, eq=False, kw_only=True)
class Validation(ResultMixin):
    """Result of :func:`validate`.

    names : parameter names.  estimate, truth, std, z : (4,).  cov : (4, 4) used.
    level : L.  quantile : ``Φ⁻¹((1 + L)/2)``.  chi2 : d².  chi2_limit : ``χ²₄(L)``.
    passed_each : (4,) bool.  passed : the verdict (joint test and, when it ran, the std
    check).  std_source : "reported" or "design".  theta_source : where θ came from for a
    design covariance.  std_ratio : (4,) reported/design std, or None when not checked (design
    std used, or no design to compare with).  std_limits : accepted (low, high) ratio
    (:func:`std_ratio_limits`).  std_passed : all ratios within the limits, or None.
    Units: order ``[bias_x, scale_x, bias_y, scale_y]``, bias in m/s², scale dimensionless.

    Serialisation: :meth:`to_dict` (printed by ``validate --json``) has the standard
    deviations but not the correlations; :meth:`to_state` adds ``names`` and ``cov`` and
    ``Validation.from_dict(v.to_state()) == v``. From :meth:`to_dict` alone the covariance is
    rebuilt diagonal (``std²``); the printed object is the same.
    """

    _TITLE = "Validation against the truth"
    _UNITS = ("bias, its std and error m/s²; scale and its std dimensionless; z-scores, d² and "
              "limits dimensionless; level a fraction")

    names: tuple[str, ...]
    estimate: np.ndarray
    truth: np.ndarray
    std: np.ndarray
    cov: np.ndarray
    z: np.ndarray
    level: float
    quantile: float
    chi2: float
    chi2_limit: float
    passed_each: np.ndarray
    passed: bool
    std_source: str
    theta_source: str | None
    std_ratio: np.ndarray | None = None
    std_limits: tuple[float, float] | None = None
    std_passed: bool | None = None

    def _std_check(self) -> dict:
        return {"passed": bool(self.std_passed), "limits": list(self.std_limits),
                "ratio": {n: float(self.std_ratio[i]) for i, n in enumerate(self.names)}}

    _JSON_UNITS = {  # the units of to_dict(), one home (docs/units.md)
        "level": "1", "chi2": "1", "chi2_limit": "1", "z_limit": "1",
        **{f"parameters.{n}.{k}": u for n, u in (("bias_x", "m/s²"), ("bias_y", "m/s²"),
                                                  ("scale_x", "1"), ("scale_y", "1"))
           for k in ("estimate", "truth", "std")},
        "parameters.*.z": "1", "std_check.limits": "1", "std_check.ratio.*": "1",
    }

    def to_dict(self) -> dict:
        d = self._to_dict()
        if self.std_passed is False:
            d["std_check"] = self._std_check()
        return with_units(d, self._JSON_UNITS)

    def _to_dict(self) -> dict:
        return {
            "passed": self.passed, "level": self.level, "test": "joint chi2, 4 dof",
            "chi2": self.chi2, "chi2_limit": self.chi2_limit,
            "z_limit": self.quantile, "std_source": self.std_source,
            "theta_source": self.theta_source,
            "parameters": {n: {"estimate": float(self.estimate[i]),
                               "truth": float(self.truth[i]), "std": float(self.std[i]),
                               "z": float(self.z[i]), "passed": bool(self.passed_each[i])}
                           for i, n in enumerate(self.names)},
        }

    def to_state(self) -> dict:
        """:meth:`to_dict` plus ``names`` and the (4, 4) ``cov`` used — an exact rebuild."""
        d = {**self.to_dict(), "names": list(self.names), "cov": np.asarray(self.cov).tolist()}
        if self.std_passed is not None:
            d["std_check"] = self._std_check()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Validation:
        """Rebuild from :meth:`to_state` (exact) or :meth:`to_dict` (diagonal ``cov``).

        Parameters
        ----------
        d : ``passed``, ``level``, ``chi2``, ``chi2_limit``, ``z_limit``, ``std_source``,
            ``theta_source`` and ``parameters`` → name → ``estimate``, ``truth``, ``std``
            (bias m/s², scale dimensionless), ``z``, ``passed``; optionally ``names`` and
            ``cov`` (4, 4).

        Examples
        --------
        See :func:`validate`: its example ends with the round trip
        ``Validation.from_dict(v.to_state()) == v``.
        """
        par = d["parameters"]
        if "names" in d:
            names = tuple(d["names"])
        elif set(par) == set(JOINT_PARAM_NAMES):  # JSON may have sorted the keys
            names = tuple(JOINT_PARAM_NAMES)
        else:
            names = tuple(par)

        def col(key: str, dtype: type = float) -> np.ndarray:
            return np.array([par[n][key] for n in names], dtype=dtype)

        std = col("std")
        cov = np.array(d["cov"], dtype=float) if "cov" in d else np.diag(std**2)
        sc = d.get("std_check")
        ratio = None if sc is None else np.array([sc["ratio"][n] for n in names], dtype=float)
        limits = None if sc is None else (float(sc["limits"][0]), float(sc["limits"][1]))
        return cls(names=names, estimate=col("estimate"), truth=col("truth"), std=std, cov=cov,
                   z=col("z"), level=float(d["level"]), quantile=float(d["z_limit"]),
                   chi2=float(d["chi2"]), chi2_limit=float(d["chi2_limit"]),
                   passed_each=col("passed", bool), passed=bool(d["passed"]),
                   std_source=d["std_source"], theta_source=d["theta_source"],
                   std_ratio=ratio, std_limits=limits,
                   std_passed=None if sc is None else bool(sc["passed"]))

    def summary(self) -> str:
        pct = f"{100 * self.level:g}%"
        # units on every number: bias m/s², scale dimensionless ("1"), z in std units
        lines = [f"{'parameter':<10}{'unit':>6}{'estimate':>14}{'true':>14}{'std':>12}"
                 f"{'z (σ)':>9}{'|z|≤' + format(self.quantile, '.3f'):>11}"]
        for i, n in enumerate(self.names):
            unit = "m/s²" if n.startswith("bias") else "1"
            lines.append(f"{n:<10}{unit:>6}{self.estimate[i]:>14.6g}{self.truth[i]:>14.6g}"
                         f"{self.std[i]:>12.4g}{self.z[i]:>+9.2f}"
                         f"{'pass' if self.passed_each[i] else 'FAIL':>11}")
        lines.append(f"joint test: d² = {self.chi2:.3f} vs χ²₄({pct}) = {self.chi2_limit:.3f} "
                     "(dimensionless) "
                     f"→ {'PASS' if self.chi2 <= self.chi2_limit else 'FAIL'}  (std: "
                     f"{self.std_source}"
                     + (f", θ from {self.theta_source}" if self.theta_source else "") + ")")
        if self.std_passed is False:
            lo, hi = self.std_limits
            worst = int(np.argmax(np.abs(np.log(self.std_ratio))))
            lines.append(
                "std check: reported/design std = "
                + ", ".join(f"{n} {self.std_ratio[i]:.3g}" for i, n in enumerate(self.names))
                + f"; accepted [{lo:.3g}, {hi:.3g}] → FAIL (worst: {self.names[worst]}, "
                f"{self.std_ratio[worst]:.3g}× the design std)")
            lines.append("verdict: FAIL (the reported standard deviations do not match the "
                         "design)")
        return "\n".join(lines)


def validate(truth: Mapping, estimates: Mapping, level: float = 0.99,
             std_source: StdSource = "auto", theta: np.ndarray | None = None,
             theta_source: str | None = None, truth_name: str = "truth.json",
             est_name: str = "est.json") -> Validation:
    """Compare estimates with the truth (module docstring for the definitions).

    Parameters
    ----------
    truth : the ``truth.json`` object.  estimates : the ``est.json`` object.
    level : L in (0, 1).
    std_source : "auto" (reported if ``est.json`` has stds, else design), "reported" or
        "design".
    theta : (N,) rad, the run's θ for a design covariance (default: rebuilt from truth).
    theta_source : label of where θ came from (for the report).
    truth_name, est_name : file names used in error messages.

    Returns
    -------
    Validation : per parameter (order ``[bias_x, scale_x, bias_y, scale_y]``; bias m/s²,
    scale dimensionless) estimate, truth, std, z; the joint χ²₄ verdict ``passed``.

    Examples
    --------
    >>> from bench import validate
    >>> truth = {"sensor": {"x": {"bias": 0.1, "scale": 0.0},
    ...                     "y": {"bias": 0.0, "scale": 0.01}}}
    >>> est = {"axes": {"x": {"bias": 0.11, "bias_std": 0.01, "scale": 0.0,
    ...                       "scale_std": 0.001},
    ...                 "y": {"bias": 0.0, "bias_std": 0.01, "scale": 0.01,
    ...                       "scale_std": 0.001}}}
    >>> v = validate(truth, est, level=0.99)
    >>> bool(v.passed), [round(float(z), 3) for z in v.z]
    (True, [1.0, 0.0, 0.0, 0.0])
    >>> from bench.validate import Validation
    >>> Validation.from_dict(v.to_state()) == v
    True
    """
    if not 0.0 < level < 1.0:
        raise DataError(f"--level must be in (0, 1), got {level}")
    tr = read_truth(truth, truth_name)
    tp = tr.params
    if tp is None:
        raise DataError(f"{truth_name}: no sensor.{{x,y}}.{{bias,scale}} found")
    est = parse_estimates(estimates, est_name)
    if theta is not None:
        theta = np.asarray(theta, dtype=float)
        check_run(tr, est, theta, theta_source or "the given θ", truth, truth_name, est_name)
    p_true = np.array([tp[n] for n in JOINT_PARAM_NAMES])
    g = tr.g or est["g"]

    def dcov() -> tuple[np.ndarray, str]:
        nv = [tp.get(f"noise_var_{a}") for a in AXES]
        if any(v is None or v <= 0 for v in nv):
            raise _NoDesignError(f"{truth_name}: positive sensor noise variances are needed to "
                            "recompute the standard deviations from the design")
        if theta is not None:
            return design_cov(theta, nv, g), theta_source or "given θ"
        if tr.design is None:
            raise _NoDesignError(f"{truth_name}: no 'theta_design' or 'sweep' found to rebuild "
                                 "θ; pass --ensayo ENSAYO.mat (the run the estimates came from)")
        return design_cov(design_theta(truth, truth_name), nv, g), "truth.json design"

    src = std_source
    if src == "auto":
        src = "reported" if est["std"] is not None else "design"
    t_src, dc = None, None
    if src == "reported":
        if est["std"] is None:
            raise DataError(f"{est_name}: no bias_std/scale_std/cov reported; use the design "
                            "standard deviations (--std design)")
        try:
            dc, d_src = dcov()
        except _NoDesignError:
            dc = d_src = None
        if est["cov"] is not None:
            cov = est["cov"]
        else:
            s = est["std"]
            if dc is not None:
                corr, t_src = dc / np.sqrt(np.outer(np.diag(dc), np.diag(dc))), d_src
            else:
                corr = np.eye(4)
            cov = corr * np.outer(s, s)
    elif src == "design":
        cov, t_src = dcov()
    else:
        raise DataError(f"std source must be auto, reported or design, got {std_source!r}")
    std = np.sqrt(np.diag(cov))
    e = est["params"] - p_true
    z = e / std
    d2 = float(e @ np.linalg.solve(cov, e))
    q = float(stats.norm.ppf(0.5 + level / 2))
    lim = float(stats.chi2.ppf(level, 4))
    ratio = limits = std_ok = None
    if dc is not None:  # the std check (std_ratio_limits): reported vs design std
        n = theta.size if theta is not None else design_size(truth, truth_name)[0]
        ratio = std / np.sqrt(np.diag(dc))
        limits = std_ratio_limits(n)
        std_ok = bool(np.all((ratio >= limits[0]) & (ratio <= limits[1])))
    return Validation(names=JOINT_PARAM_NAMES, estimate=est["params"], truth=p_true, std=std,
                      cov=cov, z=z, level=float(level), quantile=q, chi2=d2, chi2_limit=lim,
                      passed_each=np.abs(z) <= q, passed=d2 <= lim and std_ok is not False,
                      std_source=src, theta_source=t_src, std_ratio=ratio, std_limits=limits,
                      std_passed=std_ok)


class _NoDesignError(DataError):
    """No design covariance can be computed (no noise variances or no θ design)."""


def check_run(tr: Truth, est: Mapping, theta: np.ndarray, theta_name: str, truth: Mapping,
              truth_name: str = "truth.json", est_name: str = "est.json") -> None:
    """Refuse a θ (``--ensayo``) that is not the run of the truth and the estimates.

    Checked, where the files state them: N against the estimates' ``n`` and the truth's
    ``n``; N against the size of the truth's θ design; θ against ``theta_summary``
    (min, max to 10⁻⁶ relative — a single-precision copy passes —, the number of distinct
    angles exactly); for a static design θ against the rebuilt angles (the encoder reads a
    static pose exactly) to the same tolerance.
    """
    n = int(theta.size)
    if not np.all(np.isfinite(theta)):
        raise DataError(f"{theta_name}: θ has non-finite values")
    for field, m in est["n"].items():
        if m != n:
            raise DataError(f"{theta_name}: N = {n} samples, but {est_name} says {field} = {m}: "
                            "the estimates come from another run")
    if tr.n is not None and tr.n != n:
        raise DataError(f"{theta_name}: N = {n} samples, but {truth_name} says n = {tr.n}: "
                        "this ensayo is not the run of that truth")
    if tr.design is not None:
        m, label = design_size(truth, truth_name)
        if m != n:
            raise DataError(f"{theta_name}: N = {n} samples, but the θ design of {truth_name} "
                            f"({label}) has {m}: this ensayo is not the run of that truth")

    def close(a: float, b: float) -> bool:
        return abs(a - b) <= 1e-6 * max(1.0, abs(a), abs(b))

    if tr.summary is not None:
        sm = tr.summary
        for key, got in (("min", float(theta.min())), ("max", float(theta.max()))):
            if key in sm and not close(got, float(sm[key])):
                raise DataError(f"{theta_name}: θ {key} = {got:.9g} rad, but {truth_name} says "
                                f"theta_summary.{key} = {float(sm[key]):.9g}: this ensayo is not "
                                "the run of that truth")
        if "distinct" in sm and int(np.unique(theta).size) != int(sm["distinct"]):
            raise DataError(f"{theta_name}: {np.unique(theta).size} distinct θ, but "
                            f"{truth_name} says theta_summary.distinct = {int(sm['distinct'])}: "
                            "this ensayo is not the run of that truth")
    if tr.static and tr.design is not None:
        ref = design_theta(truth, truth_name)
        scale = max(1.0, float(np.max(np.abs(ref))))
        worst = float(np.max(np.abs(theta - ref)))
        if worst > 1e-6 * scale:
            raise DataError(f"{theta_name}: θ differs from the θ design of {truth_name} by up to "
                            f"{worst:.3g} rad: this ensayo is not the run of that truth")


__all__ = ["Validation", "check_answer_key", "check_run", "check_schema", "design_cov",
           "design_size", "design_theta", "parse_estimates", "read_truth", "std_ratio_limits",
           "true_sensor_params", "validate", "load_json"]
