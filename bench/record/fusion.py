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

The filter's doubts (issue 23, docs/fusion.md "Doubting the inputs"): the fixes the
innovation gate rejected are their own entity ``vehicle/plane/rejected_fixes`` (red, each
labelled with its NIS) and are not in ``vehicle/plane/fixes`` (the fixes used); on ``time``,
``fusion/nis/used|rejected`` (NIS = νᵀS⁻¹ν of each fix, dimensionless) with the gate
``fusion/nis/gate`` (c = χ²_d⁻¹(1 − α_g)), and the windowed test of
:class:`calib.fusion.innovation_check.Consistency`: ``fusion/window_nis/sum`` (T_w = Σ min(NIS, c)
at each window's mid time), its two-sided band ``fusion/window_nis/band/lo|hi`` (a step over
each window) and ``fusion/window_nis/failing`` (the windows out of band).
``summary/consistency`` holds the verdict ("consistent: …" or "INCONSISTENT: …"); an
inconsistent run has no fused region (no ``fused/arrival``, no ``fused/ellipses``), its
decision text starts with the verdict and the plane view's name says "INCONSISTENT".

A turning run (dead reckoning :class:`calib.vehicle.turning_trajectory.TurningTrajectory`, region
:class:`calib.vehicle.turning_trajectory.TurningRegion`: the no-fix extended filter's covariance)
has the same ``arrival/*`` and decision text, and the heading on ``time``: ``fusion/heading/fused``
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
from calib.vehicle.region import Ellipse
from calib.vehicle.turning_trajectory import TurningTrajectory, dead_reckoning_path, heading_error

if TYPE_CHECKING:
    from calib.fusion.innovation_check import Consistency
    from calib.fusion.linear import FusionResult
    from calib.vehicle.region import ArrivalRegion
    from calib.vehicle.trajectory import Trajectory
    from calib.vehicle.turning_trajectory import TurningRegion

FUSED_COLOR = (160, 90, 230)
FIX_COLOR = (210, 210, 210, 200)
REJECTED_COLOR = (255, 40, 40)
"""Rejected fixes and failing NIS windows: a red nothing else in the fusion scene uses."""
MAX_ELLIPSES = 20
"""Ellipses drawn along the fused path: at every k-th fix, k chosen for at most this many."""


def fusion_report(res: FusionResult, decision: Mapping, dead_reckoning_std,
                  consistency: Consistency | None = None) -> dict:
    """The small tree logged under ``fusion_report/``: final fused position and covariance
    (m, m²), the dead-reckoning std (m; None if not given), the decision, mean
    NIS, P0/Q/R (SI); with a ``consistency``, ``consistent`` and ``consistency`` (its
    :meth:`~calib.fusion.innovation_check.Consistency.to_dict`, the ``fuse --json`` object's)."""
    cov = np.asarray(res.final_position_cov, float).reshape(2, 2)
    nis = res.nis()
    doubt = ({} if consistency is None else
             {"consistent": consistency.consistent, "consistency": consistency.to_dict()})
    return {**doubt,
            "final_position": np.asarray(res.final_position, float).reshape(2).tolist(),
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
                  true_heading: tuple[np.ndarray, np.ndarray] | None = None,
                  consistency: Consistency | None = None) -> Path:
    """Record a fused vehicle run (module docstring for the entities).

    Parameters
    ----------
    traj, region : dead reckoning and its arrival region (same level); a turning run: a
        :class:`~calib.vehicle.turning_trajectory.TurningTrajectory` and its
        :class:`~calib.vehicle.turning_trajectory.TurningRegion`.
    res : the Kalman result (one run, nodes ``res.times``).  fixes : (M, 2) fixes used, m.
    decision : the fused decision (``fuse --json``'s ``decision``).  level : region level.
    truth : ``truth.json`` object, if known.  true_path : (n, 2) true positions, m, if known.
    candidates : name → (2,) m; default ``region.candidates``.
    true_heading : (t s, ψ rad) of the truth, turning run, if known.
    consistency : the windowed NIS verdict (``fuse_arrival(...).consistency``); not
        consistent: no fused region is drawn and the verdict leads the texts.
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
    inconsistent = consistency is not None and not consistency.consistent
    nodes = _fix_nodes(res)
    every = max(1, int(np.ceil(nodes.size / MAX_ELLIPSES)))
    picked = nodes[::every]
    fixes = np.asarray(fixes, float).reshape(-1, 2)
    used = np.asarray(res.fix_used, bool).reshape(-1)
    if used.shape[0] != fixes.shape[0]:  # the fixes are not the filter's: none marked
        used = np.ones(fixes.shape[0], bool)
    cand = np.array(list(cands.values()), float)
    box_pts = (dr, fixes, fused, true_path, cand, region.ellipse.boundary(128))
    bp = fusion_blueprint(plane_bounds(*box_pts), level=level, truth=true_path is not None,
                          every_s=float(np.median(np.diff(t[picked]))) if picked.size > 1
                          else None, heading=turning, inconsistent=inconsistent,
                          rejected=int(np.sum(~used)))
    with open_recording(path, force, bp, "fusion") as rec:
        rec.log("vehicle/plane", rr.Transform3D(scale=FLIP_Y), static=True)
        log_grid(rec, "vehicle/plane/grid", plane_box(*box_pts))
        for name, p, order in (("corrected", dr, 22.0), ("true", true_path, 21.0)):
            if p is not None:
                rec.log(f"vehicle/plane/path/{name}", rr.LineStrips2D(
                    [np.asarray(p, float)], radii=rr.Radius.ui_points(1.25),
                    colors=COLORS[name], draw_order=order), static=True)
        rec.log("vehicle/plane/fixes", rr.Points2D(
            fixes[used], radii=rr.Radius.ui_points(2.5), colors=FIX_COLOR, draw_order=25.0),
            static=True)
        nis = np.asarray(res.nis(), float).reshape(-1)
        if not used.all():
            rec.log("vehicle/plane/rejected_fixes", rr.Points2D(
                fixes[~used], radii=rr.Radius.ui_points(4.0), colors=REJECTED_COLOR,
                labels=[f"rejected at {t:.4g} s: NIS {v:.0f}" for t, v in
                        zip(np.asarray(res.t_gps, float)[~used] - t0, nis[~used],
                            strict=True)],
                show_labels=True,
                draw_order=45.0), static=True)
        rec.log("vehicle/plane/fused/path", rr.LineStrips2D(
            [fused], radii=rr.Radius.ui_points(1.75), colors=FUSED_COLOR, draw_order=30.0),
            static=True)
        if not inconsistent:  # an inconsistent filter's covariance is no region to show
            rec.log("vehicle/plane/fused/ellipses", rr.LineStrips2D(
                [Ellipse.from_cov(fused[j], P[j, :2, :2], level).boundary(64) for j in picked],
                radii=rr.Radius.ui_points(1.0), colors=FUSED_COLOR, draw_order=31.0),
                static=True)
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
        _log_nis(rec, nis, used, tg, res.gate_alpha, nu.shape[-1])
        if consistency is not None:
            _log_windows(rec, consistency, t0)
            rec.log("summary/consistency", rr.TextDocument(
                _consistency_text(consistency, used), media_type=rr.MediaType.MARKDOWN),
                static=True)
        if turning:
            _log_heading(rec, traj, est[:, 4], P[:, 4, 4], tn, t0, true_heading)
        log_tree(rec, "fusion_report",
                 fusion_report(res, decision, region.std, consistency))
        if truth is not None:
            log_tree(rec, "truth", truth)
        text = _decision_text(decision, None if inconsistent else final, region,
                              true_arrival(truth), consistency, used)
        rec.log("summary/decision", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN),
                static=True)
    return Path(path)


def _log_nis(rec, nis: np.ndarray, used: np.ndarray, tg: Mapping, gate_alpha: float,
             d: int) -> None:
    """NIS = νᵀS⁻¹ν of each fix on ``time`` (used grey, rejected red) and the gate
    c = χ²_d⁻¹(1 − α_g), d the fix's dimension."""
    t = np.asarray(tg[TIME_TIMELINE], float)
    if used.shape != nis.shape:  # fixes not the filter's (library use): all as used
        used = np.ones(nis.shape, bool)
    log_series(rec, "fusion/nis/used", nis[used], {TIME_TIMELINE: t[used]}, "points",
               FIX_COLOR[:3], "NIS, fix used", 3.0)
    if not used.all():
        log_series(rec, "fusion/nis/rejected", nis[~used], {TIME_TIMELINE: t[~used]},
                   "points", REJECTED_COLOR, "NIS, fix rejected", 5.0)
    if gate_alpha > 0 and t.size:
        from calib.fusion.kalman import gate_threshold

        c = float(gate_threshold(gate_alpha, d))
        log_series(rec, "fusion/nis/gate", np.array([c, c]), {TIME_TIMELINE: t[[0, -1]]},
                   "line", COLORS["band"], f"gate c = {c:.3g} (α = {gate_alpha:g})", 1.5)


def _log_windows(rec, cons: Consistency, t0: float) -> None:
    """The windowed test on ``time``: T_w at each window's mid time, its band as a step over
    the window (from its first to its last fix) and the failing windows in red."""
    ts = np.asarray(cons.t_start, float) - t0
    te = np.asarray(cons.t_end, float) - t0
    mid = {TIME_TIMELINE: 0.5 * (ts + te)}
    log_series(rec, "fusion/window_nis/sum", cons.stat, mid, "points", FUSED_COLOR,
               f"Σ min(NIS, c) over ≤ {cons.window} fixes", 5.0)
    step = {TIME_TIMELINE: np.column_stack([ts, te]).reshape(-1)}
    for name, v in (("lo", cons.lo), ("hi", cons.hi)):
        log_series(rec, f"fusion/window_nis/band/{name}", np.repeat(np.asarray(v, float), 2),
                   step, "line", COLORS["band"], f"band {name} (α_w = {cons.per_window_alpha:.2g})",
                   1.5)
    bad = np.asarray(cons.failing, bool)
    if bad.any():
        log_series(rec, "fusion/window_nis/failing", np.asarray(cons.stat)[bad],
                   {TIME_TIMELINE: mid[TIME_TIMELINE][bad]}, "points", REJECTED_COLOR,
                   "window out of band", 7.0)


def _consistency_text(cons: Consistency, used: np.ndarray) -> str:
    """The verdict (one line, as ``fuse`` prints it), the gate's count and the failing
    windows (Markdown)."""
    gate = (f"Innovation gate at α = {cons.gate_alpha:g} (NIS ≥ {cons.gate:.3g}): "
            f"{int(np.sum(~used))} of {used.size} fixes rejected."
            if cons.gate_alpha > 0 else "No innovation gate.")
    lines = [f"**{cons.verdict()}**", "", gate]
    if not cons.consistent:
        lines += ["", "No fused region: the filter's stated σ does not describe these fixes.",
                  "", "| window (s) | fixes | Σ min(NIS, c) | band | side |",
                  "|---|---|---|---|---|"]
        lines += [f"| {w['t_start']:g}–{w['t_end']:g} | {w['fixes']} | {w['nis_sum']:.3g} | "
                  f"{w['band'][0]:.3g}–{w['band'][1]:.3g} | {w['side']} |"
                  for w in cons.failing_windows]
    return "\n".join(lines)


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


def _decision_text(decision: Mapping, final: Ellipse | None,
                   region: ArrivalRegion | TurningRegion, answer: str | None,
                   consistency: Consistency | None = None,
                   used: np.ndarray | None = None) -> str:
    """The decision view: the verdict when inconsistent (``final`` None: no fused region,
    decision none), the fused decision, the truth's answer, the distances, the consistency
    text (gate count, failing windows), the dead reckoning's decision."""
    da = region.ellipse.semi_axes
    versus = f" against {da[0]:.1f} × {da[1]:.1f} m by dead reckoning."
    lines = []
    letter = decision.get("decision") or "undecided"
    if consistency is not None and not consistency.consistent:
        lines += [f"### {consistency.verdict()}", ""]
        letter = "none"
    lines += [f"### Fused arrival: {letter}", "", str(decision.get("reason", "")), ""]
    if final is not None:
        sa = final.semi_axes
        lines += [f"Fused {100 * final.level:g}% ellipse {sa[0]:.2f} × {sa[1]:.2f} m{versus}",
                  ""]
    else:
        lines += ["No fused region (inconsistent inputs).", ""]
    if answer is not None:
        lines += [f"True arrival point (truth.json): **{answer}**", ""]
    if decision.get("mahalanobis"):
        lines += ["| candidate | Mahalanobis (fused) |", "|---|---|"]
        lines += [f"| {k} | {v:.2f} |" for k, v in decision["mahalanobis"].items()]
        lines += [""]
    if consistency is not None:
        lines += ["#### Consistency", "",
                  _consistency_text(consistency, np.ones(consistency.fixes, bool)
                                    if used is None else used), ""]
    lines += ["#### Dead reckoning", "", decision_markdown(region, answer)]
    return "\n".join(lines)


__all__ = ["fusion_report", "record_fusion"]
