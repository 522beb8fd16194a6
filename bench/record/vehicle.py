"""The vehicle scene: accelerations, paths, candidates, arrival ellipse and its growth.

The vehicle plane is logged under ``vehicle/plane``, a frame entity carrying
``Transform3D(scale=(1, -1, 1))`` so +y points up as on paper (rerun's 2-D space has +y
down). A course recording holds the calibration scene too (:func:`record_course`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bench.record.blueprint import plane_bounds, vehicle_blueprint
from bench.record.calibration import log_calibration, log_truth_axes
from bench.record.plot import log_grid, plane_box
from bench.record.stream import COLORS, TIME_TIMELINE, log_series, log_tree, open_recording
from bench.record.summary import (
    decision_markdown,
    parameters_markdown,
    true_arrival,
    truth_manifest,
)
from calib.conventions import AXES
from calib.vehicle.propagation import position_cov_along
from calib.vehicle.report import trajectory_tree

if TYPE_CHECKING:
    import rerun as rr

    from bench.course import CourseSet
    from bench.tilt import CalibrationRun
    from bench.vehicle import VehicleRun
    from calib.calibration.tilt_plane import Calibration
    from calib.files.course import Ensayo
    from calib.vehicle.region import ArrivalRegion
    from calib.vehicle.trajectory import Trajectory

FLIP_Y = (1.0, -1.0, 1.0)
"""Scale of the ``vehicle/plane`` frame: +y up."""
SNAPSHOTS = 10
"""Growing-ellipse snapshots drawn statically along the run."""


def _snapshot_dt(traj: Trajectory) -> float:
    return float(traj.t[-1] - traj.t[0]) / SNAPSHOTS


def _ellipse_points(center, cov, level: float, n: int = 96) -> np.ndarray:
    from calib.vehicle.region import Ellipse

    if not np.any(cov):
        return np.repeat(np.asarray(center, float)[None, :], 2, axis=0)
    return Ellipse.from_cov(center, cov, level).boundary(n)


def _log_paths(rec: rr.RecordingStream, t: np.ndarray, paths: Mapping[str, Any]) -> None:
    """Paths (static) and the position at the current time, in the path's colour."""
    import rerun as rr

    rec.log("vehicle/plane", rr.Transform3D(scale=FLIP_Y), static=True)
    tl = [rr.TimeColumn(TIME_TIMELINE, duration=t - t[0])]
    for name, p in paths.items():
        if p is None:
            continue
        p = np.asarray(p, dtype=float)
        # No labels: the names are in the view name (labels on paths overprint the others).
        rec.log(f"vehicle/plane/path/{name}", rr.LineStrips2D(
            [p], radii=rr.Radius.ui_points(1.25), colors=COLORS[name],
            draw_order={"raw": 20.0, "true": 21.0, "corrected": 22.0}[name]), static=True)
        rec.log(f"vehicle/plane/position/{name}", rr.Points2D.from_fields(
            radii=rr.Radius.ui_points(5.0), colors=COLORS[name], draw_order=40.0), static=True)
        rec.send_columns(f"vehicle/plane/position/{name}", indexes=tl,
                         columns=rr.Points2D.columns(positions=p))


def log_candidates(rec: rr.RecordingStream, candidates: Mapping[str, Any]) -> None:
    """The candidate arrival points (name → (2,) m) with their labels (static)."""
    import rerun as rr

    names = list(candidates)
    rec.log("vehicle/plane/candidates", rr.Points2D(
        np.array([candidates[k] for k in names], dtype=float), labels=names,
        radii=rr.Radius.ui_points(6.0), colors=COLORS["candidate"], show_labels=True,
        draw_order=35.0), static=True)


def _log_accelerations(rec: rr.RecordingStream, t: np.ndarray,
                       series: Mapping[str, np.ndarray | None]) -> None:
    """(M, 2) accelerations (m/s²) against time, one series per kind and axis (None: skip)."""
    tl = {TIME_TIMELINE: t - t[0]}
    for name, acc in series.items():
        if acc is None:
            continue
        for k, a in enumerate(AXES):
            # the measured samples thin and translucent, under the corrected and true lines
            log_series(rec, f"vehicle/acceleration/{name}/{a}", acc[:, k], tl, "line",
                       COLORS["raw_light" if name == "measured" else name], f"{name} {a}",
                       0.5 if name == "measured" else 1.5)


def log_arrival(rec: rr.RecordingStream, region: ArrivalRegion) -> None:
    """The corrected arrival point and its confidence ellipse (static)."""
    import rerun as rr

    pct = f"{100 * region.level:g}%"
    # One label for estimate and ellipse (two labels at the same centre overprint).
    rec.log("vehicle/plane/arrival/estimate", rr.Points2D(
        region.estimate[None, :], radii=rr.Radius.ui_points(4.0), colors=COLORS["ellipse"],
        labels=f"arrival {region.decision or 'undecided'} ({pct} ellipse)", show_labels=True,
        draw_order=45.0), static=True)
    rec.log("vehicle/plane/arrival/ellipse", rr.LineStrips2D(
        [region.ellipse.boundary(256)], radii=rr.Radius.ui_points(2.0), colors=COLORS["ellipse"],
        draw_order=32.0), static=True)  # above the moving ellipse, which ends on it


def _log_uncertainty(rec: rr.RecordingStream, traj: Trajectory, region: ArrivalRegion,
                     cal: Calibration, n_ellipses: int) -> None:
    """Error propagation over time: the ellipse around the corrected position at about
    ``n_ellipses`` times (on the ``time`` timeline), :data:`SNAPSHOTS` of them drawn
    statically, and the position standard deviation per axis."""
    import rerun as rr

    m = traj.t.shape[0]
    idx = np.unique(np.linspace(0, m - 1, min(n_ellipses, m)).round().astype(int))
    covs = position_cov_along(traj, cal, region.noise_var, idx)
    centers = traj.pos_corrected[idx]
    strips = [_ellipse_points(c, s, region.level) for c, s in zip(centers, covs, strict=True)]
    t_idx = (traj.t - traj.t[0])[idx]
    rec.log("vehicle/plane/uncertainty/ellipse", rr.LineStrips2D.from_fields(
        radii=rr.Radius.ui_points(2.0), colors=COLORS["growth"], draw_order=31.0), static=True)
    rec.send_columns("vehicle/plane/uncertainty/ellipse",
                     indexes=[rr.TimeColumn(TIME_TIMELINE, duration=t_idx)],
                     columns=rr.LineStrips2D.columns(strips=strips))
    snap = np.unique(np.linspace(0, len(idx) - 1, SNAPSHOTS + 1).round().astype(int))[1:]
    # One label, half-way (the last snapshot is the arrival ellipse, the early ones are small
    # and would stack on the start): the view name gives the spacing.
    labelled = {int(snap[len(snap) // 2 - 1])} if len(snap) > 2 else set()
    rec.log("vehicle/plane/uncertainty/snapshots", rr.LineStrips2D(
        [strips[i] for i in snap], radii=rr.Radius.ui_points(1.0), colors=COLORS["growth"],
        labels=[f"t = {t_idx[i]:.0f} s" if i in labelled else "" for i in snap],
        show_labels=True, draw_order=29.0), static=True)
    std = np.sqrt(np.clip(np.diagonal(covs, axis1=1, axis2=2), 0.0, None))
    for k, a in enumerate(AXES):
        log_series(rec, f"vehicle/position_std/{a}", std[:, k], {TIME_TIMELINE: t_idx},
                   "line", COLORS[f"std_{a}"], f"std {a}")


def log_vehicle(rec: rr.RecordingStream, traj: Trajectory, region: ArrivalRegion,
                cal: Calibration, true_path: np.ndarray | None,
                true_acc: np.ndarray | None, n_ellipses: int = 200) -> None:
    """A corrected vehicle run: accelerations, paths, candidates, arrival and its growth.

    Parameters
    ----------
    traj : raw and corrected trajectory.  region : arrival region and decision.
    cal : the calibration used (its covariance drives the ellipses along time).
    true_path : (M, 2) true positions, m, or None.  true_acc : (M, 2) true accelerations,
        m/s², or None.  n_ellipses : ellipses along the run (time-indexed).
    """
    _log_accelerations(rec, traj.t, {"measured": traj.acc_raw,
                                     "corrected": traj.acc_corrected, "true": true_acc})
    _log_paths(rec, traj.t, {"raw": traj.pos_raw, "corrected": traj.pos_corrected,
                             "true": true_path})
    log_candidates(rec, region.candidates)
    log_arrival(rec, region)
    _log_uncertainty(rec, traj, region, cal, n_ellipses)
    log_grid(rec, "vehicle/plane/grid", plane_box(*_region_points(traj, region, true_path)))


def record_vehicle_truth(run: VehicleRun, path: str | os.PathLike, force: bool = False,
                         candidates: Mapping[str, np.ndarray] | None = None,
                         calibration: CalibrationRun | None = None,
                         truth: Mapping | None = None) -> Path:
    """Record a generated vehicle run (or a whole course set) next to its truth, no estimation.

    Logs the measured and MuJoCo's true accelerations against time, the true and the raw
    (uncorrected, integrated twice) paths with the position along time, the candidate points
    when given, the calibration run's readings and true model when given (as
    :func:`record_calibration_truth`), and ``truth/`` = the ``truth.json`` object (``truth``,
    default the vehicle's own manifest; seed and versions added).
    """
    import rerun as rr

    from calib.vehicle.trajectory import integrate_twice

    manifest = truth_manifest(truth if truth is not None else run.truth_dict(), run.seed)
    raw, _ = integrate_twice(run.t, run.aerr, run.config.p0, run.config.v0)
    cand = None if candidates is None else np.array(list(candidates.values()), dtype=float)
    blueprint = vehicle_blueprint(plane_bounds(raw, run.truth.pos, cand),
                                  estimated=False,
                                  acc=("measured", "true"), paths=("raw", "true"),
                                  candidates=candidates is not None,
                                  calibration=None if calibration is None else (False, True),
                                  texts=("parameters",))
    with open_recording(path, force, blueprint, "truth") as rec:
        _log_accelerations(rec, run.t, {"measured": run.aerr, "true": run.truth.acc})
        _log_paths(rec, run.t, {"raw": raw, "true": run.truth.pos})
        log_grid(rec, "vehicle/plane/grid", plane_box(raw, run.truth.pos, cand))
        if candidates is not None:
            log_candidates(rec, candidates)
        if calibration is not None:
            log_truth_axes(rec, calibration)
        log_tree(rec, "truth", manifest)
        arrival = true_arrival(manifest) if candidates is not None else None
        rec.log("summary/parameters", rr.TextDocument(
            "# Generated run: true values\n\n"
            + (f"True arrival point: **{arrival}**\n\n" if arrival else "")
            + parameters_markdown(None, manifest), media_type=rr.MediaType.MARKDOWN),
            static=True)
    return Path(path)


def record_course_truth(course: CourseSet, path: str | os.PathLike,
                        force: bool = False) -> Path:
    """Record a generated course set next to its truth (``tiltbench generate course --rrd``)."""
    return record_vehicle_truth(course.vehicle, path, force, course.candidates,
                                course.calibration, course.truth())


def record_trajectory(traj: Trajectory, region: ArrivalRegion, cal: Calibration,
                      path: str | os.PathLike, force: bool = False,
                      truth: Mapping | None = None, true_path: np.ndarray | None = None,
                      true_acc: np.ndarray | None = None, tree: Mapping | None = None) -> Path:
    """Record a vehicle run: accelerations, paths, candidates, arrival ellipse and growth.

    Parameters
    ----------
    traj : raw and corrected trajectory (:func:`calib.vehicle.trajectory.compute_trajectory`).
    region : arrival region and decision (:func:`calib.vehicle.region.arrival_region`).
    cal : the calibration used (its covariance drives the ellipses along time).
    path : output ``.rrd``.  force : replace an existing file.
    truth : ``truth.json`` object, if known (logged under ``truth/``).
    true_path : (M, 2) true positions, m, if known.  true_acc : (M, 2) true accelerations.
    tree : the object logged under ``trajectory/`` (default :func:`trajectory_tree`).
    """
    import rerun as rr

    bp = vehicle_blueprint(_region_bounds(traj, region, true_path), estimated=True,
                           acc=_acc_kinds(true_acc), paths=_path_kinds(true_path),
                           candidates=True, calibration=None, level=region.level,
                           snapshot_dt=_snapshot_dt(traj), texts=("decision", "parameters"))
    with open_recording(path, force, bp, "vehicle") as rec:
        log_vehicle(rec, traj, region, cal, true_path, true_acc)
        log_tree(rec, "trajectory",
                 tree if tree is not None else trajectory_tree(traj, region, cal))
        log_tree(rec, "estimate", cal.to_dict())
        if truth is not None:
            log_tree(rec, "truth", truth)
        rec.log("summary/decision", rr.TextDocument(
            decision_markdown(region, true_arrival(truth)), media_type=rr.MediaType.MARKDOWN),
            static=True)
        rec.log("summary/parameters", rr.TextDocument(
            parameters_markdown(cal.to_dict(), truth), media_type=rr.MediaType.MARKDOWN),
            static=True)
    return Path(path)


def _acc_kinds(true_acc) -> tuple[str, ...]:
    return ("measured", "corrected") + (("true",) if true_acc is not None else ())


def _path_kinds(true_path) -> tuple[str, ...]:
    return ("raw", "corrected") + (("true",) if true_path is not None else ())


def _region_points(traj: Trajectory, region: ArrivalRegion, true_path) -> tuple:
    """Everything drawn on the plane (paths, candidates, arrival ellipse), m: the grid and
    the view bounds cover them."""
    return (traj.pos_raw, traj.pos_corrected, true_path,
            np.array(list(region.candidates.values()), dtype=float),
            region.ellipse.boundary(256))


def _region_bounds(traj: Trajectory, region: ArrivalRegion, true_path) -> Any:
    return plane_bounds(*_region_points(traj, region, true_path))


def record_course(path: str | os.PathLike, *, cal: Calibration, ensayo: Ensayo,
                  traj: Trajectory, region: ArrivalRegion, force: bool = False,
                  truth: Mapping | None = None, true_path: np.ndarray | None = None,
                  true_acc: np.ndarray | None = None, tree: Mapping | None = None,
                  level: float = 0.95) -> Path:
    """Record a full course set: calibration (as :func:`record_calibration`) and vehicle
    run (as :func:`record_trajectory`) in one file, with ``truth/``, ``estimate/`` and
    ``trajectory/`` trees. Parameters as in those two functions."""
    import rerun as rr

    from bench.validate import true_sensor_params

    has_true = bool(truth) and true_sensor_params(truth) is not None
    bp = vehicle_blueprint(_region_bounds(traj, region, true_path), estimated=True,
                           acc=_acc_kinds(true_acc), paths=_path_kinds(true_path),
                           candidates=True, calibration=(True, has_true),
                           level=region.level, snapshot_dt=_snapshot_dt(traj),
                           texts=("decision", "parameters"))
    with open_recording(path, force, bp, "course") as rec:
        log_calibration(rec, cal, ensayo, truth, level)
        log_vehicle(rec, traj, region, cal, true_path, true_acc)
        log_tree(rec, "trajectory",
                 tree if tree is not None else trajectory_tree(traj, region, cal))
        rec.log("summary/decision", rr.TextDocument(
            decision_markdown(region, true_arrival(truth)), media_type=rr.MediaType.MARKDOWN),
            static=True)
    return Path(path)
