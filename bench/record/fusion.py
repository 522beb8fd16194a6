"""The fusion scene (``tiltbench fuse --rrd``): dead reckoning, the fixes, the fused path with
its confidence ellipses, the truth when known, and the innovations with their ±σ bounds.

Entities (docs/recordings.md, kind ``fusion``): the plane under ``vehicle/plane`` (+y up, as
:mod:`bench.record.vehicle`) with ``path/corrected`` (dead reckoning), ``path/true``,
``fixes``, ``fused/path``, ``fused/position`` (on ``time``), ``fused/ellipses`` (every k-th
fix), ``fused/arrival`` (unlabelled: the decision view and the view name say what it is) and
the dead-reckoning ``arrival/*``; ``fusion/innovation/{axis}``
(ν = z − H x⁻, m) with ``fusion/innovation_band/{axis}/plus|minus`` (±sqrt S_ii, m) and
``fusion/position_std/{axis}`` (filtered, m) on ``time``; ``fusion_report/**`` (the tree of
:func:`fusion_report`), ``truth/**`` when known, ``summary/decision``.

A turning run (dead reckoning :class:`calib.turning_trajectory.TurningTrajectory`, region
:class:`calib.turning_trajectory.TurningRegion`: the no-fix extended filter's covariance) has
the same ``arrival/*`` and decision text, and the heading on ``time``: ``fusion/heading/fused``
(filtered ψ, rad) with ``fusion/heading_std`` (σ_ψ, rad),
``fusion/heading/dead_reckoning`` (the gyro integrated) and, when the truth is known,
``fusion/heading/true`` (truth.json, every second) and the errors at its samples
``fusion/heading_error/fused|dead_reckoning`` (ψ − ψ true, rad) with
``fusion/heading_error_band/plus|minus`` (±σ_ψ, rad).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.record.blueprint import fusion_blueprint, plane_bounds
from bench.record.plot import log_grid, plane_box
from bench.record.stream import COLORS, TIME_TIMELINE, log_series, log_tree, open_recording
from bench.record.summary import decision_markdown, true_arrival
from bench.record.vehicle import FLIP_Y, log_arrival, log_candidates
from calib.conventions import AXES
from calib.region import Ellipse
from calib.turning_trajectory import TurningTrajectory, dead_reckoning_path, heading_error

if TYPE_CHECKING:
    from calib.fusion import FusionResult
    from calib.region import ArrivalRegion
    from calib.trajectory import Trajectory
    from calib.turning_trajectory import TurningRegion

FUSED_COLOR = (160, 90, 230)
FIX_COLOR = (210, 210, 210, 200)
MAX_ELLIPSES = 20
"""Ellipses drawn along the fused path: at every k-th fix, k chosen for at most this many."""


def fusion_report(res: FusionResult, decision: Mapping, dead_reckoning_std) -> dict:
    """The small tree logged under ``fusion_report/``: final fused position and covariance
    (m, m²), the dead-reckoning std (m; None if not given), the decision, mean
    NIS, P0/Q/R (SI)."""
    cov = np.asarray(res.final_position_cov, float).reshape(2, 2)
    nis = res.nis()
    return {"final_position": np.asarray(res.final_position, float).reshape(2).tolist(),
            "final_position_cov": cov.tolist(),
            "final_std": np.sqrt(np.diag(cov)).tolist(),
            "dead_reckoning_std": (None if dead_reckoning_std is None
                                   else np.asarray(dead_reckoning_std, float).tolist()),
            "n_fixes": int(res.t_gps.shape[0]),
            "mean_nis": float(np.mean(nis)) if nis.size else None,
            "P0": res.P0.tolist(), "Q": res.Q.tolist(), "R": res.R.tolist(),
            "decision": dict(decision)}


def _fix_nodes(res: FusionResult) -> np.ndarray:
    return np.flatnonzero(res.is_fix)


def record_fusion(path: str | os.PathLike, traj: Trajectory | TurningTrajectory,
                  region: ArrivalRegion | TurningRegion, res: FusionResult, fixes: np.ndarray,
                  decision: Mapping, level: float, *, force: bool = False,
                  truth: Mapping | None = None, true_path: np.ndarray | None = None,
                  candidates: Mapping | None = None,
                  true_heading: tuple[np.ndarray, np.ndarray] | None = None) -> Path:
    """Record a fused vehicle run (module docstring for the entities).

    Parameters
    ----------
    traj, region : dead reckoning and its arrival region (same level); a turning run: a
        :class:`~calib.turning_trajectory.TurningTrajectory` and its
        :class:`~calib.turning_trajectory.TurningRegion`.
    res : the Kalman result (one run, nodes ``res.times``).  fixes : (M, 2) fixes used, m.
    decision : the fused decision (``fuse --json``'s ``decision``).  level : region level.
    truth : ``truth.json`` object, if known.  true_path : (n, 2) true positions, m, if known.
    candidates : name → (2,) m; default ``region.candidates``.
    true_heading : (t s, ψ rad) of the truth, turning run, if known.
    """
    import rerun as rr

    turning = isinstance(traj, TurningTrajectory)
    cands = region.candidates if candidates is None else candidates
    est = np.asarray(res.estimates, float)
    P = np.asarray(res.covariances, float)
    t = np.asarray(res.times, float)
    t0 = float(traj.t[0])
    dr = dead_reckoning_path(traj)
    fused = est[:, :2]
    final = Ellipse.from_cov(fused[-1], P[-1, :2, :2], level)
    nodes = _fix_nodes(res)
    every = max(1, int(np.ceil(nodes.size / MAX_ELLIPSES)))
    picked = nodes[::every]
    cand = np.array(list(cands.values()), float)
    box_pts = (dr, fixes, fused, true_path, cand, region.ellipse.boundary(128))
    bp = fusion_blueprint(plane_bounds(*box_pts), level=level, truth=true_path is not None,
                          every_s=float(np.median(np.diff(t[picked]))) if picked.size > 1
                          else None, heading=turning)
    with open_recording(path, force, bp, "fusion") as rec:
        rec.log("vehicle/plane", rr.Transform3D(scale=FLIP_Y), static=True)
        log_grid(rec, "vehicle/plane/grid", plane_box(*box_pts))
        for name, p, order in (("corrected", dr, 22.0), ("true", true_path, 21.0)):
            if p is not None:
                rec.log(f"vehicle/plane/path/{name}", rr.LineStrips2D(
                    [np.asarray(p, float)], radii=rr.Radius.ui_points(1.25),
                    colors=COLORS[name], draw_order=order), static=True)
        rec.log("vehicle/plane/fixes", rr.Points2D(
            fixes, radii=rr.Radius.ui_points(2.5), colors=FIX_COLOR, draw_order=25.0),
            static=True)
        rec.log("vehicle/plane/fused/path", rr.LineStrips2D(
            [fused], radii=rr.Radius.ui_points(1.75), colors=FUSED_COLOR, draw_order=30.0),
            static=True)
        rec.log("vehicle/plane/fused/ellipses", rr.LineStrips2D(
            [Ellipse.from_cov(fused[j], P[j, :2, :2], level).boundary(64) for j in picked],
            radii=rr.Radius.ui_points(1.0), colors=FUSED_COLOR, draw_order=31.0), static=True)
        rec.log("vehicle/plane/fused/arrival", rr.LineStrips2D(
            [final.boundary(128)], radii=rr.Radius.ui_points(2.0), colors=FUSED_COLOR,
            draw_order=33.0), static=True)  # no label: it would overprint the arrival's
        rec.log("vehicle/plane/fused/position", rr.Points2D.from_fields(
            radii=rr.Radius.ui_points(5.0), colors=FUSED_COLOR, draw_order=40.0), static=True)
        rec.send_columns("vehicle/plane/fused/position",
                         indexes=[rr.TimeColumn(TIME_TIMELINE, duration=t - t0)],
                         columns=rr.Points2D.columns(positions=fused))
        log_candidates(rec, cands)
        log_arrival(rec, region)
        tg = {TIME_TIMELINE: np.asarray(res.t_gps, float) - t0}
        nu = np.asarray(res.innovations, float)
        s = np.sqrt(np.diagonal(np.asarray(res.innovation_covs, float), axis1=-2, axis2=-1))
        tn = {TIME_TIMELINE: t - t0}
        std = np.sqrt(np.clip(np.diagonal(P[:, :2, :2], axis1=1, axis2=2), 0.0, None))
        for k, a in enumerate(AXES):
            log_series(rec, f"fusion/innovation/{a}", nu[:, k], tg, "points", FUSED_COLOR,
                       f"innovation {a}", 4.0)
            for sign, name in ((1.0, "plus"), (-1.0, "minus")):
                log_series(rec, f"fusion/innovation_band/{a}/{name}", sign * s[:, k], tg,
                           "line", COLORS["band"], f"{'+' if sign > 0 else '−'}σ {a}")
            log_series(rec, f"fusion/position_std/{a}", std[:, k], tn, "line",
                       COLORS[f"std_{a}"], f"std {a}")
        if turning:
            _log_heading(rec, traj, est[:, 4], P[:, 4, 4], tn, t0, true_heading)
        log_tree(rec, "fusion_report",
                 fusion_report(res, decision, region.std))
        if truth is not None:
            log_tree(rec, "truth", truth)
        text = _decision_text(decision, final, region, true_arrival(truth))
        rec.log("summary/decision", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN),
                static=True)
    return Path(path)


def _log_heading(rec, traj: TurningTrajectory, psi: np.ndarray, var: np.ndarray,
                 tn: Mapping, t0: float, true_heading) -> None:
    """Filtered ψ and σ_ψ, the dead-reckoned ψ and, known, the true ψ with the errors of both
    at its samples (rad) on ``time``."""
    log_series(rec, "fusion/heading/fused", psi, tn, "line", FUSED_COLOR, "ψ fused", 2.0)
    log_series(rec, "fusion/heading_std", np.sqrt(np.clip(var, 0.0, None)), tn, "line",
               FUSED_COLOR, "σ_ψ fused")
    log_series(rec, "fusion/heading/dead_reckoning", traj.heading,
               {TIME_TIMELINE: traj.t - t0}, "line", COLORS["corrected"],
               "ψ dead reckoning", 1.0)
    if true_heading is None:
        return
    tt, pt = (np.asarray(v, float) for v in true_heading)
    log_series(rec, "fusion/heading/true", pt, {TIME_TIMELINE: tt - t0}, "line",
               COLORS["true"], "ψ true", 1.5)
    keep = (tt >= traj.t[0]) & (tt <= traj.t[-1])
    tt, pt = tt[keep], pt[keep]
    times = np.asarray(tn[TIME_TIMELINE], float) + t0
    te = {TIME_TIMELINE: tt - t0}
    log_series(rec, "fusion/heading_error/fused", heading_error(times, psi, tt, pt), te,
               "points", FUSED_COLOR, "ψ − ψ true, fused", 3.0)
    log_series(rec, "fusion/heading_error/dead_reckoning",
               heading_error(traj.t, traj.heading, tt, pt), te, "points", COLORS["corrected"],
               "ψ − ψ true, dead reckoning", 3.0)
    sde = np.sqrt(np.interp(tt, times, np.clip(var, 0.0, None)))
    for sign, name in ((1.0, "plus"), (-1.0, "minus")):
        log_series(rec, f"fusion/heading_error_band/{name}", sign * sde, te, "line",
                   COLORS["band"], f"{'+' if sign > 0 else '−'}σ", 1.0)


def _decision_text(decision: Mapping, final: Ellipse, region: ArrivalRegion | TurningRegion,
                   answer: str | None) -> str:
    sa = final.semi_axes
    da = region.ellipse.semi_axes
    versus = f" against {da[0]:.1f} × {da[1]:.1f} m by dead reckoning."
    lines = [f"### Fused arrival: {decision.get('decision') or 'undecided'}", "",
             str(decision.get("reason", "")), "",
             f"Fused {100 * final.level:g}% ellipse {sa[0]:.2f} × {sa[1]:.2f} m{versus}", ""]
    if answer is not None:
        lines += [f"True arrival point (truth.json): **{answer}**", ""]
    lines += ["| candidate | Mahalanobis (fused) |", "|---|---|"]
    lines += [f"| {k} | {v:.2f} |" for k, v in decision.get("mahalanobis", {}).items()]
    lines += ["", "#### Dead reckoning", "", decision_markdown(region, answer)]
    return "\n".join(lines)


__all__ = ["fusion_report", "record_fusion"]
