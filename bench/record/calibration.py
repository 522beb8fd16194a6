"""The calibration scene: per axis data, model, residuals ±σ, binned mean, error against A_r.

Each axis is logged twice (see :data:`bench.record.schema.ENTITY_DOCS`): as time series on
the ``sample`` and ``theta_urad`` timelines (θ·10⁶ rounded, an integer so a time-series view
plots against θ), and as static 2-D plots (:class:`~bench.record.plot.StaticPlot`, θ in rad)
that the blueprint shows whatever the active timeline.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.record.blueprint import calibration_blueprint
from bench.record.plot import StaticPlot
from bench.record.stream import (
    COLORS,
    LINE_WIDTH,
    SAMPLE_TIMELINE,
    THETA_TIMELINE,
    log_series,
    log_tree,
    open_recording,
)
from bench.record.summary import parameters_markdown, truth_manifest
from calib.calibration.correct import apply_errors
from calib.conventions import AXES, reference_accel
from calib.stats.binning import binned_mean

if TYPE_CHECKING:
    import rerun as rr

    from bench.tilt import CalibrationRun
    from calib.calibration.tilt_plane import Calibration
    from calib.files.course import Ensayo

CURVE_POINTS = 2000
"""Smooth model curves (fit, true) are logged on at most about this many samples."""
MEAN_BINS = 100
"""Binned-mean lines average the residuals over this many θ bins (equal sample counts)."""


def _line(x0: float, x1: float, b: float, s: float) -> np.ndarray:
    """The error line A_m − A_r = s·A_r + b over [x0, x1] (the model (1 + s)·A_r + b)."""
    xs = np.array([x0, x1])
    return np.column_stack([xs, s * xs + b])


def _theta_index(theta: np.ndarray) -> dict[str, np.ndarray]:
    """The two timelines of a θ series: sample number and round(θ·10⁶)."""
    return {SAMPLE_TIMELINE: np.arange(theta.size, dtype=np.int64),
            THETA_TIMELINE: np.round(theta * 1e6).astype(np.int64)}


def _curve_samples(theta: np.ndarray) -> np.ndarray:
    """Indices of the samples a smooth curve is drawn on: at most :data:`CURVE_POINTS` (every
    k-th, ends kept), sorted by θ so the curve is drawn left to right."""
    k = max(1, int(np.ceil(theta.size / CURVE_POINTS)))
    sub = np.unique(np.r_[np.arange(0, theta.size, k), theta.size - 1])
    return sub[np.argsort(theta[sub], kind="stable")]


def _model_curves(a_r: np.ndarray, fit_line: tuple[float, float] | None,
                  true_line: tuple[float, float] | None,
                  a_true: np.ndarray | None) -> dict[str, np.ndarray]:
    """The model readings ``(1 + scale)·a + bias`` (m/s²): "fit" on A_r, "true" on MuJoCo's
    true specific force when given (else on A_r)."""
    curves: dict[str, np.ndarray] = {}
    if fit_line is not None:
        b, s = fit_line
        curves["fit"] = apply_errors(a_r, b, s)
    if true_line is not None:
        b, s = true_line
        base = a_r if a_true is None else a_true
        curves["true"] = apply_errors(base, b, s)
    return curves


def _log_axis_series(rec: rr.RecordingStream, axis: str, theta: np.ndarray, a_m: np.ndarray,
                     sub: np.ndarray, curves: Mapping[str, np.ndarray], resid: np.ndarray,
                     sigma: float, mean: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
    """Time series on θ of one axis: measured, model curves, residual, ±σ band, binned mean."""
    o = f"calibration/{axis}"
    idx = _theta_index(theta)
    log_series(rec, f"{o}/measured", a_m, idx, "points", COLORS["measured"], f"A_m{axis}")
    sub_idx = {tl: v[sub] for tl, v in idx.items()}
    for name, curve in curves.items():
        log_series(rec, f"{o}/{name}", curve[sub], sub_idx, "line", COLORS[name], name)
    log_series(rec, f"{o}/residual", resid, idx, "points", COLORS["measured"], "residual")
    ends = np.array([int(np.argmin(theta)), int(np.argmax(theta))])
    end_idx = {k: v[ends] for k, v in idx.items()}
    for part, sign in (("plus", 1.0), ("minus", -1.0)):
        log_series(rec, f"{o}/residual_band/{part}", np.full(2, sign * sigma), end_idx, "line",
                   COLORS["band"], f"{'+' if sign > 0 else '−'}σ = {sign * sigma:.3g}")
    th_mean, r_mean, at = mean
    log_series(rec, f"{o}/residual_mean", r_mean,
               {SAMPLE_TIMELINE: at, THETA_TIMELINE: np.round(th_mean * 1e6).astype(np.int64)},
               "line", COLORS["mean"],
               f"binned mean ({theta.size // max(1, th_mean.size)} per bin)")


def _radii() -> dict[str, rr.Radius]:
    """Marker and line radii of the static plots (UI points)."""
    import rerun as rr

    return {"points": rr.Radius.ui_points(0.5), "line": rr.Radius.ui_points(LINE_WIDTH / 2),
            "thin": rr.Radius.ui_points(LINE_WIDTH / 4)}  # the true line, on top of the fit


def _log_theta_plot(rec: rr.RecordingStream, o: str, theta: np.ndarray, a_m: np.ndarray,
                    sub: np.ndarray, curves: Mapping[str, np.ndarray]) -> None:
    """Static plot ``o/theta_plot``: A_m and the model curves against θ (rad)."""
    import rerun as rr

    r = _radii()
    plot = StaticPlot.around(theta, np.r_[a_m, *(c[sub] for c in curves.values())])
    plot.log_frame(rec, f"{o}/theta_plot", xlabel="θ (rad)", ylabel="A_m (m/s²)")
    rec.log(f"{o}/theta_plot/measured", rr.Points2D(
        np.column_stack([theta, a_m]), radii=r["points"], colors=COLORS["sample"],
        draw_order=10.0), static=True)
    for name, curve in curves.items():
        rec.log(f"{o}/theta_plot/{name}", rr.LineStrips2D(
            [np.column_stack([theta[sub], curve[sub]])], colors=COLORS[name],
            radii=r["thin"] if name == "true" and "fit" in curves else r["line"],
            draw_order=30.0 if name == "fit" else 31.0), static=True)


def _log_residual_plot(rec: rr.RecordingStream, o: str, theta: np.ndarray, resid: np.ndarray,
                       sigma: float, th_mean: np.ndarray, r_mean: np.ndarray) -> None:
    """Static plot ``o/residual_plot``: residuals, ±σ lines and the binned mean against θ."""
    import rerun as rr

    r = _radii()
    lim = max(float(np.max(np.abs(resid))) if resid.size else 0.0, 1.2 * sigma)
    plot = StaticPlot.around(theta, [-lim, lim], symmetric_y=True)
    plot.log_frame(rec, f"{o}/residual_plot", zero_line=True, xlabel="θ (rad)",
                   ylabel="residual (m/s²)")
    rec.log(f"{o}/residual_plot/residual", rr.Points2D(
        np.column_stack([theta, resid]), radii=r["points"], colors=COLORS["sample"],
        draw_order=10.0), static=True)
    t0, t1 = float(np.min(theta)), float(np.max(theta))
    rec.log(f"{o}/residual_plot/band", rr.LineStrips2D(
        [np.array([[t0, sigma], [t1, sigma]]), np.array([[t0, -sigma], [t1, -sigma]])],
        radii=r["line"], colors=COLORS["band"], draw_order=20.0), static=True)
    rec.log(f"{o}/residual_plot/mean", rr.LineStrips2D(
        [np.column_stack([th_mean, r_mean])], radii=r["line"], colors=COLORS["mean"],
        draw_order=30.0), static=True)


def _log_vs_ar(rec: rr.RecordingStream, o: str, a_r: np.ndarray, a_m: np.ndarray,
               fit_line: tuple[float, float] | None,
               true_line: tuple[float, float] | None) -> None:
    """Static plot ``o/vs_ar``: the reading error A_m − A_r against A_r (slope = scale,
    offset = bias) with its binned mean and the fitted, true and ideal error lines."""
    import rerun as rr

    r = _radii()
    err = a_m - a_r
    lo, hi = float(np.min(a_r)), float(np.max(a_r))
    lines = {name: _line(lo, hi, *ln) for name, ln in
             (("fit", fit_line), ("true", true_line), ("ideal", (0.0, 0.0))) if ln is not None}
    plot = StaticPlot.around(a_r, np.r_[err, *(ln[:, 1] for ln in lines.values())])
    plot.log_frame(rec, f"{o}/vs_ar", xlabel="A_r (m/s²)", ylabel="A_m − A_r (m/s²)")
    rec.log(f"{o}/vs_ar/measured", rr.Points2D(np.column_stack([a_r, err]), radii=r["points"],
                                                colors=COLORS["sample"], draw_order=10.0),
            static=True)
    ar_mean, e_mean, _ = binned_mean(a_r, err, MEAN_BINS)
    rec.log(f"{o}/vs_ar/mean", rr.LineStrips2D(
        [np.column_stack([ar_mean, e_mean])], radii=r["line"], colors=COLORS["mean"],
        draw_order=25.0), static=True)
    for name, ln in lines.items():
        rec.log(f"{o}/vs_ar/{name}", rr.LineStrips2D(
            [ln], radii=r["thin"] if name == "true" and fit_line is not None else r["line"],
            colors=COLORS[name],
            draw_order={"ideal": 28.0, "fit": 30.0, "true": 31.0}[name]), static=True)


def log_axis_data(rec: rr.RecordingStream, axis: str, theta: np.ndarray, a_m: np.ndarray,
                  a_r: np.ndarray, fit_line: tuple[float, float] | None,
                  true_line: tuple[float, float] | None, a_true: np.ndarray | None,
                  sigma: float) -> None:
    """Per-axis calibration entities (see :data:`~bench.record.schema.ENTITY_DOCS`): time
    series on θ and the same content as static 2-D plots.

    Parameters
    ----------
    rec : the recording.  axis : "x" or "y".
    theta : (n,) tilt angles, rad.  a_m : (n,) readings, m/s².  a_r : (n,) reference, m/s².
    fit_line, true_line : (bias m/s², scale) of the fitted / true model, or None.
    a_true : (n,) MuJoCo's true specific force, m/s² (the true curve's base), or None.
    sigma : noise standard deviation of the ±σ band, m/s².

    The residual is ``A_m − model``, the model being the fit, else the true model, else A_r.
    """
    o = f"calibration/{axis}"
    sub = _curve_samples(theta)
    curves = _model_curves(a_r, fit_line, true_line, a_true)
    resid = a_m - curves.get("fit", curves.get("true", a_r))
    mean = binned_mean(theta, resid, MEAN_BINS)
    _log_axis_series(rec, axis, theta, a_m, sub, curves, resid, sigma, mean)
    _log_theta_plot(rec, o, theta, a_m, sub, curves)
    _log_residual_plot(rec, o, theta, resid, sigma, mean[0], mean[1])
    _log_vs_ar(rec, o, a_r, a_m, fit_line, true_line)


def log_truth_axes(rec: rr.RecordingStream, run: CalibrationRun) -> None:
    """Both axes of a generated calibration run against its true model (no fit): the true
    line with MuJoCo's true specific force, the residual against it and a true-σ band."""
    a_r = reference_accel(run.tita, run.config.g)
    for k, a in enumerate(AXES):
        err = run.config.sensor.axis(a)
        log_axis_data(rec, a, run.tita, run.datos[:, k], a_r[:, k], None,
                      (err.bias, err.scale), run.a_true[:, k], float(np.sqrt(err.noise_var)))


def log_calibration(rec: rr.RecordingStream, cal: Calibration, ensayo: Ensayo,
                    truth: Mapping | None, level: float) -> None:
    """Both axes of a calibration (fit, and the true line when the truth has the sensor
    parameters), the ``estimate/`` and ``truth/`` trees and ``summary/parameters``."""
    import rerun as rr

    from bench.validate import true_sensor_params

    a_r = reference_accel(ensayo.tita, cal.g)
    tp = true_sensor_params(truth) if truth else None
    for k, a in enumerate(AXES):
        f = cal.fits[a]
        true_line = (tp[f"bias_{a}"], tp[f"scale_{a}"]) if tp else None
        log_axis_data(rec, a, ensayo.tita, ensayo.datos[:, k], a_r[:, k],
                      (f.param("bias"), f.param("scale")), true_line, None,
                      float(np.sqrt(f.sigma2)))
    est = cal.to_dict()
    log_tree(rec, "estimate", est)
    if truth is not None:
        log_tree(rec, "truth", truth)
    rec.log("summary/parameters", rr.TextDocument(
        "# Calibration: estimates vs truth\n\n" + parameters_markdown(est, truth, level),
        media_type=rr.MediaType.MARKDOWN), static=True)


def record_calibration(cal: Calibration, ensayo: Ensayo, path: str | os.PathLike,
                       force: bool = False, truth: Mapping | None = None,
                       level: float = 0.95) -> Path:
    """Record a calibration: per axis data, fit, residuals ±σ, estimates (and truth).

    Parameters
    ----------
    cal : the calibration (:func:`calib.calibration.tilt_plane.calibrate`).
    ensayo : the run it was fitted on (θ rad, readings m/s²).
    path : output ``.rrd`` (written atomically).
    force : replace an existing file.
    truth : the ``truth.json`` object, if known; logged under ``truth/`` and drawn as the
        true line.
    level : confidence level of the intervals in the summary table.

    Returns
    -------
    The path written.
    """
    from bench.validate import true_sensor_params

    has_true = bool(truth) and true_sensor_params(truth) is not None
    with open_recording(path, force, calibration_blueprint(True, has_true),
                        "calibration") as rec:
        log_calibration(rec, cal, ensayo, truth, level)
    return Path(path)


def record_calibration_truth(run: CalibrationRun, path: str | os.PathLike,
                             force: bool = False) -> Path:
    """Record a generated calibration run next to its truth (no estimation).

    Logs the measured readings, the true model ``(1 + scale)·a + bias`` (``a`` = MuJoCo's
    true specific force; further error terms of the truth are not drawn), the residual
    readings − true model with a ±σ band (true σ), and ``truth/`` = the ``truth.json``
    object (with seed and versions).
    """
    import rerun as rr

    truth = truth_manifest(run.truth(), run.seed)
    with open_recording(path, force, calibration_blueprint(False, True),
                        "calibration truth") as rec:
        log_truth_axes(rec, run)
        log_tree(rec, "truth", truth)
        rec.log("summary/parameters", rr.TextDocument(
            "# Generated calibration run: true parameters\n\n"
            + parameters_markdown(None, truth), media_type=rr.MediaType.MARKDOWN), static=True)
    return Path(path)
