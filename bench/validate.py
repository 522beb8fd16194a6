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

Exit codes of ``tiltbench validate``: 0 pass, 1 fail, 2 bad input.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from scipy import stats

from calib.conventions import AXES, JOINT_PARAM_NAMES, G, reference_accel
from calib.io import DataError
from calib.results import ResultMixin

StdSource = Literal["auto", "reported", "design"]


def _find_sensor(truth: Mapping) -> Mapping | None:
    """The first ``sensor`` mapping with x/y bias and scale (breadth first)."""
    queue: list[Any] = [truth]
    while queue:
        d = queue.pop(0)
        if not isinstance(d, Mapping):
            continue
        s = d.get("sensor")
        if isinstance(s, Mapping) and all(
                isinstance(s.get(a), Mapping) and "bias" in s[a] and "scale" in s[a]
                for a in AXES):
            return s
        queue.extend(v for v in d.values() if isinstance(v, Mapping))
    return None


def _find_key(truth: Mapping, key: str) -> Any:
    queue: list[Any] = [truth]
    while queue:
        d = queue.pop(0)
        if isinstance(d, Mapping):
            if key in d:
                return d[key]
            queue.extend(v for v in d.values() if isinstance(v, Mapping))
    return None


def true_sensor_params(truth: Mapping) -> dict[str, float] | None:
    """``{bias_x, scale_x, bias_y, scale_y, noise_var_x, noise_var_y}`` from a truth object.

    Looks for ``sensor.{x,y}.{bias, scale, noise_var}`` (top level first, then nested, e.g.
    the calibration part of a course truth). None when absent.
    """
    s = _find_sensor(truth)
    if s is None:
        return None
    out = {}
    for a in AXES:
        out[f"bias_{a}"] = float(s[a]["bias"])
        out[f"scale_{a}"] = float(s[a]["scale"])
        if "noise_var" in s[a]:
            out[f"noise_var_{a}"] = float(s[a]["noise_var"])
    return out


def design_theta(truth: Mapping) -> np.ndarray:
    """θ (rad) of the calibration run, rebuilt from the design recorded in ``truth.json``.

    Static runs: exact (:class:`bench.tilt.ThetaDesign` ``angles()``; the encoder reads the
    pose exactly). Sweeps: the commanded profile at the sample times (approximate: the
    encoder lags the command slightly). Raises :class:`DataError` when no design is found.
    """
    from bench.tilt import SweepProfile, ThetaDesign

    design = _find_key(truth, "theta_design")
    if isinstance(design, Mapping):
        d = dict(design)
        if "values" in d:
            d["values"] = tuple(d["values"])
        return ThetaDesign(**d).angles()
    sweep = _find_key(truth, "sweep")
    if isinstance(sweep, Mapping) and "kind" in sweep:
        prof = SweepProfile(**sweep)
        n = int(np.floor(prof.duration * prof.rate + 1e-9)) + 1
        return prof.command(np.arange(n) / prof.rate)
    raise DataError("truth.json: no 'theta_design' or 'sweep' found to rebuild θ; pass "
                    "--ensayo ENSAYO.mat (the run the estimates came from)")


def design_cov(theta: np.ndarray, noise_var, g: float = G) -> np.ndarray:
    """4×4 covariance of per-axis OLS ``[bias_x, scale_x, bias_y, scale_y]``, σ² known.

    ``σ_a² (H_aᵀH_a)⁻¹`` per axis with ``H_a = [1, A_r,a(θ)]`` (computed by
    :func:`calib.ls.fit_linear` through QR, never by inverting HᵀH); zero across axes.
    """
    from calib.ls import fit_linear

    theta = np.asarray(theta, dtype=float)
    a_r = reference_accel(theta, g)
    cov = np.zeros((4, 4))
    for k in range(2):
        H = np.column_stack([np.ones_like(a_r[:, k]), a_r[:, k]])
        fit = fit_linear(H, np.zeros(theta.size), ("bias", "scale"), float(noise_var[k]))
        cov[2 * k:2 * k + 2, 2 * k:2 * k + 2] = fit.cov
    return cov


def _num(v: Any, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise DataError(f"{where}: expected a number, got {v!r}")
    if not np.isfinite(v):
        raise DataError(f"{where}: not finite ({v})")
    return float(v)


def parse_estimates(est: Mapping, where: str = "est.json") -> dict[str, Any]:
    """Normalise an ``est.json`` object.

    Accepted forms (``docs/validate.md``): ``{"axes": {"x": {...}, "y": {...}}, ...}`` (the
    ``calibrate --json`` object), the same without the ``axes`` wrapper, or flat keys
    ``bias_x, scale_x, bias_y, scale_y`` (optionally ``*_std``). Per axis ``bias`` and
    ``scale`` are required; ``bias_std``, ``scale_std``, ``cov`` (2×2, [bias, scale]) are
    optional.

    Returns
    -------
    ``{"params": (4,), "std": (4,) or None, "cov": (4, 4) or None, "g": float}``.
    """
    if not isinstance(est, Mapping):
        raise DataError(f"{where}: expected a JSON object")
    if "axes" in est:
        axes = est["axes"]
    elif all(a in est for a in AXES):
        axes = est
    elif all(f"{p}_{a}" in est for a in AXES for p in ("bias", "scale")):
        axes = {a: {k[:-2]: v for k, v in est.items() if k.endswith(f"_{a}")} for a in AXES}
    else:
        raise DataError(f"{where}: expected 'axes': {{'x': {{'bias', 'scale'}}, 'y': ...}} "
                        "or keys bias_x, scale_x, bias_y, scale_y (see docs/validate.md)")
    params, std, cov = np.zeros(4), np.zeros(4), np.zeros((4, 4))
    have_std, have_cov = True, True
    for k, a in enumerate(AXES):
        ax = axes.get(a) if isinstance(axes, Mapping) else None
        if not isinstance(ax, Mapping):
            raise DataError(f"{where}: axis '{a}' is missing")
        for j, p in enumerate(("bias", "scale")):
            if p not in ax:
                raise DataError(f"{where}: axes.{a}.{p} is missing")
            params[2 * k + j] = _num(ax[p], f"{where}: axes.{a}.{p}")
            if f"{p}_std" in ax:
                std[2 * k + j] = _num(ax[f"{p}_std"], f"{where}: axes.{a}.{p}_std")
                if std[2 * k + j] <= 0:
                    raise DataError(f"{where}: axes.{a}.{p}_std must be positive")
            else:
                have_std = False
        if "cov" in ax:
            try:
                c = np.asarray(ax["cov"], dtype=float)
            except (TypeError, ValueError):
                c = np.full((0,), np.nan)  # reported below with the expected form
            if c.shape != (2, 2) or not np.all(np.isfinite(c)) or not np.allclose(c, c.T) \
                    or np.any(np.linalg.eigvalsh(c) <= 0):
                raise DataError(f"{where}: axes.{a}.cov must be a symmetric positive definite "
                                "2×2 [[var_bias, cov], [cov, var_scale]]")
            cov[2 * k:2 * k + 2, 2 * k:2 * k + 2] = c
        else:
            have_cov = False
    if have_cov and not have_std:
        std, have_std = np.sqrt(np.diag(cov)), True
    g = est.get("g", G)
    return {"params": params, "std": std if have_std else None,
            "cov": cov if have_cov else None, "g": _num(g, f"{where}: g")}


@dataclass(frozen=True, eq=False)
class Validation(ResultMixin):
    """Result of :func:`validate`.

    names : parameter names.  estimate, truth, std, z : (4,).  cov : (4, 4) used.
    level : L.  quantile : ``Φ⁻¹((1 + L)/2)``.  chi2 : d².  chi2_limit : ``χ²₄(L)``.
    passed_each : (4,) bool.  passed : the verdict (joint test).  std_source : "reported"
    or "design".  theta_source : where θ came from for a design covariance.
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

    def to_dict(self) -> dict:
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
        return {**self.to_dict(), "names": list(self.names),
                "cov": np.asarray(self.cov).tolist()}

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
        >>> from bench.validate import Validation, validate
        >>> truth = {"sensor": {"x": {"bias": 0.1, "scale": 0.0},
        ...                     "y": {"bias": 0.0, "scale": 0.01}}}
        >>> est = {"axes": {"x": {"bias": 0.11, "bias_std": 0.01, "scale": 0.0,
        ...                       "scale_std": 0.001},
        ...                 "y": {"bias": 0.0, "bias_std": 0.01, "scale": 0.01,
        ...                       "scale_std": 0.001}}}
        >>> v = validate(truth, est)
        >>> Validation.from_dict(v.to_state()) == v
        True
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
        return cls(names, col("estimate"), col("truth"), std, cov, col("z"), float(d["level"]),
                   float(d["z_limit"]), float(d["chi2"]), float(d["chi2_limit"]),
                   col("passed", bool), bool(d["passed"]), d["std_source"], d["theta_source"])

    def summary(self) -> str:
        pct = f"{100 * self.level:g}%"
        lines = [f"{'parameter':<10}{'estimate':>14}{'true':>14}{'std':>12}{'z':>9}"
                 f"{'|z|≤' + format(self.quantile, '.3f'):>11}"]
        for i, n in enumerate(self.names):
            lines.append(f"{n:<10}{self.estimate[i]:>14.6g}{self.truth[i]:>14.6g}"
                         f"{self.std[i]:>12.4g}{self.z[i]:>+9.2f}"
                         f"{'pass' if self.passed_each[i] else 'FAIL':>11}")
        lines.append(f"joint test: d² = {self.chi2:.3f} vs χ²₄({pct}) = {self.chi2_limit:.3f} "
                     f"→ {'PASS' if self.passed else 'FAIL'}  (std: {self.std_source}"
                     + (f", θ from {self.theta_source}" if self.theta_source else "") + ")")
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
    """
    if not 0.0 < level < 1.0:
        raise DataError(f"--level must be in (0, 1), got {level}")
    tp = true_sensor_params(truth)
    if tp is None:
        raise DataError(f"{truth_name}: no sensor.{{x,y}}.{{bias,scale}} found")
    est = parse_estimates(estimates, est_name)
    p_true = np.array([tp[n] for n in JOINT_PARAM_NAMES])
    g = float(_find_key(truth, "g") or est["g"])

    def dcov() -> tuple[np.ndarray, str]:
        nv = [tp.get(f"noise_var_{a}") for a in AXES]
        if any(v is None or v <= 0 for v in nv):
            raise DataError(f"{truth_name}: positive sensor noise variances are needed to "
                            "recompute the standard deviations from the design")
        if theta is not None:
            return design_cov(theta, nv, g), theta_source or "given θ"
        return design_cov(design_theta(truth), nv, g), "truth.json design"

    src = std_source
    if src == "auto":
        src = "reported" if est["std"] is not None else "design"
    t_src = None
    if src == "reported":
        if est["std"] is None:
            raise DataError(f"{est_name}: no bias_std/scale_std/cov reported; use the design "
                            "standard deviations (--std design)")
        if est["cov"] is not None:
            cov = est["cov"]
        else:
            s = est["std"]
            try:
                dc, t_src = dcov()
                corr = dc / np.sqrt(np.outer(np.diag(dc), np.diag(dc)))
            except DataError:
                corr, t_src = np.eye(4), None
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
    return Validation(JOINT_PARAM_NAMES, est["params"], p_true, std, cov, z, float(level), q,
                      d2, lim, np.abs(z) <= q, d2 <= lim, src, t_src)


def load_json(path: str | Path, what: str) -> Any:
    """Read a JSON file; :class:`DataError` naming the file on failure."""
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: {what} not found")
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected the {what} (JSON)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: not valid JSON ({exc})") from exc


__all__ = ["Validation", "design_cov", "design_theta", "parse_estimates",
           "true_sensor_params", "validate"]
