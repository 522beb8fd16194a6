"""Rerun recordings of calibrations and vehicle runs, with the truth recoverable from the file.

One job per module; this package only re-exports their public names (no module here imports
from it):

* :mod:`bench.record.stream` — the atomic recording stream, series, JSON trees, colours;
* :mod:`bench.record.schema` — the documented entity table (:data:`ENTITY_DOCS`) and the
  docs generator (``python -m bench.record docs/recordings.md``);
* :mod:`bench.record.plot` — static 2-D plots with axes and ticks (:class:`StaticPlot`);
* :mod:`bench.record.blueprint` — the default layouts stored in the files;
* :mod:`bench.record.summary` — Markdown documents and the truth manifest;
* :mod:`bench.record.calibration` — the calibration scene;
* :mod:`bench.record.vehicle` — the vehicle / trajectory / course scene;
* :mod:`bench.record.series` — generic named-series recordings (discrepancy workflow);
* :mod:`bench.record.reader` — trees, entities and blueprint read back.

The equations live in calib: binned means (:func:`calib.stats.binning.binned_mean`), the
covariance along the run (:func:`calib.vehicle.propagation.position_cov_along`) and the
``trajectory --json`` object (:func:`calib.vehicle.report.trajectory_tree`).

Every recording is written with its own :class:`rerun.RecordingStream` (never the global one),
so one process can write several; the file is written to a temporary name beside the target
and renamed when complete (an existing file is replaced only with ``force``). Large arrays go
through ``rerun.send_columns`` (one call per entity, not one per sample). A default blueprint
is stored in the file so it opens in a useful layout: every view shows its content on open
(time-series views over the whole timeline, the time panel collapsed and not playing, one text
view per document, 2-D views with bounds computed from the data).

What is logged (the full entity table is :data:`ENTITY_DOCS`, rendered in
``docs/recordings.md``)
------------------------------------------------------------------------------------------
* ``calibration/{x,y}/...`` — measured points and the fitted line against θ (timelines
  ``sample`` and ``theta_urad`` = round(θ·10⁶), an integer so a time-series view plots
  against θ), residuals with a ±σ band and a binned mean; the same as the static 2-D plots
  the blueprint shows (``theta_plot``, ``residual_plot``: θ in rad, independent of the active
  timeline, which is ``time`` when a vehicle run is present), and the reading error
  ``A_m − A_r`` against ``A_r`` (``vs_ar``) with the fitted, true and ideal error lines.
* ``vehicle/...`` — acceleration time series (timeline ``time``, s), true / raw / corrected
  paths, candidate points, the confidence ellipse of the arrival point and the ellipse growing
  along the corrected trajectory.
* ``truth/...``, ``estimate/...``, ``trajectory/...`` — JSON trees (``truth.json``, the
  ``calibrate --json`` object, the trajectory/decision object) flattened to one entity per
  node: numbers as ``Scalars`` (float64, bit exact), strings as ``TextDocument``; each node
  also carries ``json_type`` and ``json_path`` components so :func:`read_recording`
  rebuilds the exact nested structure.

2-D views: rerun draws 2-D space with +y down (image convention); the vehicle plane is logged
under a frame entity carrying ``Transform3D(scale=(1, -1, 1))`` so +y points up as on paper,
and each static calibration plot under a :class:`StaticPlot` frame (translation and scale
onto a fixed 3:1 box, +y up) with its own axes and tick labels.
Positions (``Points2D``, ``LineStrips2D``) are stored as float32 by rerun: exact numbers live
in the JSON trees, never in the drawings.

Reproducibility: the same inputs give the same *content* (:func:`read_recording` returns equal
objects), but not the same bytes — rerun stamps every chunk with a time-based id (checked with
rerun-sdk 0.41 and a fixed recording id). The datasets and manifests are byte-reproducible; the
``.rrd`` is a view of them.
"""

from bench.record.blueprint import full_time_axis, plane_bounds, time_panel
from bench.record.calibration import (
    CURVE_POINTS,
    MEAN_BINS,
    record_calibration,
    record_calibration_truth,
)
from bench.record.plot import PLOT_BOX, StaticPlot, log_grid, plane_box, plot_bounds
from bench.record.reader import read_blueprint, read_recording, read_trees, recording_entities
from bench.record.schema import (
    ENTITY_DOCS,
    TREE_ROOTS,
    EntityDoc,
    documented,
    entity_table_markdown,
    update_docs,
)
from bench.record.series import record_series
from bench.record.stream import (
    APP_ID,
    COLORS,
    LINE_WIDTH,
    POINT_SIZE,
    SAMPLE_TIMELINE,
    THETA_TIMELINE,
    TIME_TIMELINE,
    log_series,
    log_tree,
    open_recording,
)
from bench.record.summary import decision_markdown, parameters_markdown, truth_manifest
from bench.record.vehicle import (
    FLIP_Y,
    SNAPSHOTS,
    record_course,
    record_course_truth,
    record_trajectory,
    record_vehicle_truth,
)

__all__ = [
    "APP_ID", "COLORS", "CURVE_POINTS", "ENTITY_DOCS", "FLIP_Y", "LINE_WIDTH", "MEAN_BINS",
    "PLOT_BOX", "POINT_SIZE", "SAMPLE_TIMELINE", "SNAPSHOTS", "THETA_TIMELINE",
    "TIME_TIMELINE", "TREE_ROOTS", "EntityDoc", "StaticPlot",
    "decision_markdown", "documented", "entity_table_markdown", "full_time_axis",
    "log_grid", "log_series", "log_tree", "open_recording", "parameters_markdown",
    "plane_box", "plane_bounds", "plot_bounds",
    "read_blueprint", "read_recording", "read_trees",
    "record_calibration", "record_calibration_truth", "record_course", "record_course_truth",
    "record_series", "record_trajectory", "record_vehicle_truth", "recording_entities",
    "time_panel", "truth_manifest", "update_docs",
]
