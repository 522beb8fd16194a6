"""Rerun recordings of calibrations and vehicle runs, with the truth recoverable from the file.

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

from __future__ import annotations

import json
import os
import re
import tempfile
import uuid
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from calib.conventions import AXES, reference_accel
from calib.io import to_jsonable

if TYPE_CHECKING:
    import rerun as rr

    from bench.course import CourseSet
    from bench.tilt import CalibrationRun
    from bench.vehicle import VehicleRun
    from calib.calibration import Calibration
    from calib.io import Ensayo
    from calib.region import ArrivalRegion
    from calib.trajectory import Trajectory

APP_ID = "tiltbench"

TREE_ROOTS: dict[str, str] = {"truth": "truth", "estimate": "estimates",
                              "trajectory": "trajectory"}
"""Entity root of each JSON tree → key in the dict returned by :func:`read_recording`."""

THETA_TIMELINE = "theta_urad"
SAMPLE_TIMELINE = "sample"
TIME_TIMELINE = "time"
FLIP_Y = (1.0, -1.0, 1.0)
CURVE_POINTS = 2000
"""Smooth model curves (fit, true) are logged on at most about this many samples."""

COLORS = {
    "measured": (90, 140, 220), "fit": (230, 50, 40), "ideal": (170, 170, 170),
    "band": (240, 160, 30), "true": (40, 190, 80), "raw": (150, 150, 150),
    "corrected": (60, 120, 255), "candidate": (210, 60, 190), "ellipse": (230, 50, 40),
    "growth": (240, 160, 30), "mean": (250, 250, 250), "axes": (120, 120, 120),
    "before": (90, 140, 220), "after": (110, 200, 140),
    "std_x": (80, 200, 220), "std_y": (230, 200, 60),
}
"""Fixed colours, so a series has the same colour in every view and every recording."""

MEAN_BINS = 100
"""Binned-mean lines average the residuals over this many θ bins (equal sample counts)."""
POINT_SIZE = 0.5
"""Marker size (UI points) of raw samples: 20001 points must not hide the lines on top."""
LINE_WIDTH = 2.5
"""Width (UI points) of model lines, bands and binned means drawn over the samples."""


@dataclass(frozen=True)
class EntityDoc:
    """One row of the documented entity table.

    pattern : entity path; ``{axis}`` ∈ {x, y}, ``{k}`` a letter / name, ``**`` any subtree.
    archetype : rerun archetype(s) logged there.  index : timelines ("static" if none).
    content : what it holds, with units.  kinds : recordings that contain it
    ("calibration", "truth-run", "vehicle", "gap").  optional : present only when the data exist
    (e.g. the truth of a generated set).
    """

    pattern: str
    archetype: str
    index: str
    content: str
    kinds: tuple[str, ...]
    optional: bool = False

    def regex(self) -> re.Pattern:
        out = re.escape(self.pattern)
        out = out.replace(re.escape("{axis}"), "(x|y)").replace(re.escape("{k}"), "[^/]+?")
        out = out.replace(re.escape("/**"), "(/.*)?")
        return re.compile("^" + out + "$")


_CAL = ("calibration", "truth-run")
_VEH = ("vehicle", "truth-run")
ENTITY_DOCS: tuple[EntityDoc, ...] = (
    EntityDoc("calibration/{axis}/measured", "Scalars + SeriesPoints", "sample, theta_urad",
              "measured A_m, m/s²", _CAL),
    EntityDoc("calibration/{axis}/fit", "Scalars + SeriesLines", "sample, theta_urad",
              "fitted model (1 + scale)·A_r + bias, m/s² (≤ 2001 samples)", ("calibration",)),
    EntityDoc("calibration/{axis}/true", "Scalars + SeriesLines", "sample, theta_urad",
              "true model (1 + scale)·a + bias with the true parameters and MuJoCo's true "
              "specific force a, m/s² (≤ 2001 samples)", _CAL, optional=True),
    EntityDoc("calibration/{axis}/residual", "Scalars + SeriesPoints", "sample, theta_urad",
              "residual A_m − fit, m/s² (truth-run: A_m − true model)", _CAL),
    EntityDoc("calibration/{axis}/residual_band/plus", "Scalars + SeriesLines",
              "sample, theta_urad", "+σ (first and last θ), m/s²", _CAL),
    EntityDoc("calibration/{axis}/residual_band/minus", "Scalars + SeriesLines",
              "sample, theta_urad", "−σ (first and last θ), m/s²", _CAL),
    EntityDoc("calibration/{axis}/residual_mean", "Scalars + SeriesLines",
              "sample, theta_urad", "binned mean of the residual (100 θ bins of equal counts, "
              "at the bins' mean θ), m/s²", _CAL),
    EntityDoc("calibration/{axis}/theta_plot", "Transform3D", "static",
              "static 2-D plot against θ (rad), shown by the blueprint: maps its data box onto "
              "a 300 × 100 box with +y up (translation, scale)", _CAL),
    EntityDoc("calibration/{axis}/theta_plot/measured", "Points2D", "static",
              "(θ rad, A_m m/s²) per sample (float32)", _CAL),
    EntityDoc("calibration/{axis}/theta_plot/fit", "LineStrips2D", "static",
              "fitted model against θ (≤ 2001 points)", ("calibration",)),
    EntityDoc("calibration/{axis}/theta_plot/true", "LineStrips2D", "static",
              "true model against θ (≤ 2001 points)", _CAL, optional=True),
    EntityDoc("calibration/{axis}/residual_plot", "Transform3D", "static",
              "static 2-D plot of the residuals (as `theta_plot`)", _CAL),
    EntityDoc("calibration/{axis}/residual_plot/residual", "Points2D", "static",
              "(θ rad, residual m/s²) per sample", _CAL),
    EntityDoc("calibration/{axis}/residual_plot/band", "LineStrips2D", "static",
              "±σ lines over the θ range, m/s²", _CAL),
    EntityDoc("calibration/{axis}/residual_plot/mean", "LineStrips2D", "static",
              "binned mean of the residual (as `residual_mean`), m/s²", _CAL),
    EntityDoc("calibration/{axis}/vs_ar", "Transform3D", "static",
              "static 2-D plot of the reading error against the reference (as `theta_plot`)",
              _CAL),
    EntityDoc("calibration/{axis}/vs_ar/measured", "Points2D", "static",
              "(A_r, A_m − A_r) per sample, m/s² (float32)", _CAL),
    EntityDoc("calibration/{axis}/vs_ar/mean", "LineStrips2D", "static",
              "binned mean of A_m − A_r over 100 A_r bins, m/s²", _CAL),
    EntityDoc("calibration/{axis}/vs_ar/fit", "LineStrips2D", "static",
              "fitted error line scale·A_r + bias over the A_r range, m/s²", ("calibration",)),
    EntityDoc("calibration/{axis}/vs_ar/true", "LineStrips2D", "static",
              "true error line scale·A_r + bias, m/s²", _CAL, optional=True),
    EntityDoc("calibration/{axis}/vs_ar/ideal", "LineStrips2D", "static",
              "ideal sensor A_m − A_r = 0, m/s²", _CAL),
    EntityDoc("calibration/{axis}/{k}/axes", "LineStrips2D", "static",
              "frame and ticks (and the zero line) of the static plot k = theta_plot, "
              "residual_plot or vs_ar, in its data units", _CAL),
    EntityDoc("calibration/{axis}/{k}/axes/labels", "Points2D (labels)", "static",
              "tick values of the static plot k", _CAL),
    EntityDoc("vehicle/acceleration/{k}/{axis}", "Scalars + SeriesLines", "time",
              "acceleration: k = measured (A_m), corrected (Â_r) or true, m/s²", _VEH),
    EntityDoc("vehicle/position_std/{axis}", "Scalars + SeriesLines", "time",
              "standard deviation of the corrected position (calibration + noise), m",
              ("vehicle",)),
    EntityDoc("vehicle/plane", "Transform3D", "static", "2-D frame with +y up", _VEH),
    EntityDoc("vehicle/plane/path/{k}", "LineStrips2D", "static",
              "trajectory, k = raw (uncorrected), corrected or true, m", _VEH),
    EntityDoc("vehicle/plane/position/{k}", "Points2D", "time",
              "position at the current time, k = raw, corrected or true, m (static colour and "
              "radius: those of the path)", _VEH),
    EntityDoc("vehicle/plane/candidates", "Points2D (labels)", "static",
              "candidate arrival points (puntos.mat), m", _VEH),
    EntityDoc("vehicle/plane/arrival/estimate", "Points2D", "static",
              "corrected arrival point, m", ("vehicle",)),
    EntityDoc("vehicle/plane/arrival/ellipse", "LineStrips2D", "static",
              "confidence ellipse of the arrival point at the stated level, m", ("vehicle",)),
    EntityDoc("vehicle/plane/uncertainty/ellipse", "LineStrips2D", "time",
              "ellipse at the same level around the corrected position at each time (error "
              "propagation over time), m", ("vehicle",)),
    EntityDoc("vehicle/plane/uncertainty/snapshots", "LineStrips2D", "static",
              "the growing ellipse at 10 evenly spaced times (the half-way one labelled), m",
              ("vehicle",)),
    EntityDoc("summary/parameters", "TextDocument (Markdown)", "static",
              "estimates with std and interval next to the true values and z-scores "
              "(truth-run: the true values)",
              ("calibration", "truth-run", "vehicle")),
    EntityDoc("summary/decision", "TextDocument (Markdown)", "static",
              "arrival decision, distances to the candidates", ("vehicle",)),
    EntityDoc("gap/{axis}/residual_{k}", "Scalars + SeriesPoints", "sample, theta_urad",
              "discrepancy workflow: residual before / after adding the named effects, m/s² "
              "(bench/gap.py)", ("gap",)),
    EntityDoc("gap/{axis}/band_{k}/{k}", "Scalars + SeriesLines", "sample, theta_urad",
              "±σ band of the before / after model (smallest and largest θ), m/s²", ("gap",)),
    EntityDoc("gap/{axis}/mean_{k}", "Scalars + SeriesLines", "sample, theta_urad",
              "binned mean of the residual before / after (≈ 80 samples per θ bin, at most 100 "
              "bins), m/s²", ("gap",)),
    EntityDoc("gap/effects", "TextDocument (Markdown)", "static",
              "the named effects with their evidence (`gap.md` without its image)", ("gap",)),
    EntityDoc("gap_report/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of the `gap --json` object (read back under \"gap_report\")",
              ("gap",)),
    EntityDoc("truth/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of truth.json (path = JSON keys, list items by index)",
              ("calibration", "truth-run", "vehicle"), optional=True),
    EntityDoc("estimate/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of the `calibrate --json` object", ("calibration", "vehicle")),
    EntityDoc("trajectory/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of the trajectory/decision object (`trajectory` and `region`)",
              ("vehicle",)),
)
"""The documented entities; ``docs/recordings.md`` holds :func:`entity_table_markdown`."""


def entity_table_markdown() -> str:
    """The entity table of ``docs/recordings.md`` (generated from :data:`ENTITY_DOCS`)."""
    lines = ["| entity path | archetype | timelines | content | recordings |",
             "|---|---|---|---|---|"]
    for d in ENTITY_DOCS:
        kinds = ", ".join(d.kinds) + (" (if available)" if d.optional else "")
        lines.append(f"| `{d.pattern}` | {d.archetype} | {d.index} | {d.content} | {kinds} |")
    return "\n".join(lines)


def documented(entity: str) -> EntityDoc | None:
    """The :class:`EntityDoc` whose pattern matches ``entity`` (leading '/' optional)."""
    e = entity.lstrip("/")
    for d in ENTITY_DOCS:
        if d.regex().match(e):
            return d
    return None


# --------------------------------------------------------------------------- writing

@contextmanager
def open_recording(path: str | os.PathLike, force: bool = False, blueprint: Any = None,
                   name: str | None = None) -> Iterator[rr.RecordingStream]:
    """A recording-scoped stream writing atomically to ``path``.

    Yields a :class:`rerun.RecordingStream` saving to a temporary file in the target
    directory; on normal exit the stream is flushed, closed and the file renamed to
    ``path``. On error the temporary file is removed. Refuses to replace an existing file
    unless ``force`` (checked before anything is logged).

    Parameters
    ----------
    path : target ``.rrd`` file.
    force : replace an existing file.
    blueprint : optional ``rerun.blueprint.Blueprint`` stored as the default layout.
    name : recording name shown by the viewer (default: the file stem).
    """
    import rerun as rr

    path = Path(path)
    if path.exists() and not force:
        raise FileExistsError(f"{path}: exists; pass --force to overwrite")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a recording is an ordinary file
    rec = rr.RecordingStream(APP_ID, recording_id=uuid.uuid4())
    try:
        rec.save(tmp, default_blueprint=blueprint)
        rec.send_recording_name(name or path.stem)
        yield rec
        rec.flush()
        rec.disconnect()
        os.replace(tmp, path)
    except BaseException:
        try:
            rec.disconnect()
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
        raise


def _json_normal(obj: Any) -> Any:
    """The object exactly as ``json.loads(calib.io.dumps(obj))`` gives it back."""
    return json.loads(json.dumps(to_jsonable(obj)))


def _node_type(v: Any) -> str:
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, int):
        return "int"
    if isinstance(v, float):
        return "float"
    if isinstance(v, str):
        return "str"
    if v is None:
        return "null"
    if isinstance(v, dict):
        return "dict"
    if isinstance(v, list):
        return "list"
    raise TypeError(f"cannot record JSON value of type {type(v).__name__}")


def _entity(root: str, keys: list) -> str:
    """Entity path of a tree node. Keys are escaped for rerun; an empty key (which rerun would
    drop) and keys starting with '~' get a '~' prefix, which keeps the map one to one."""
    import rerun as rr

    def part(k: object) -> str:
        k = str(k)
        return rr.escape_entity_path_part("~" + k if k == "" or k.startswith("~") else k)

    return "/".join([root] + [part(k) for k in keys])


def log_tree(rec: rr.RecordingStream, root: str, obj: Mapping | list) -> int:
    """Log a JSON-like tree under ``root``, one static entity per node; return the count.

    Numbers go to ``Scalars`` (float64: exact; integers also as decimal text in
    ``json_int``), booleans to ``Scalars`` 0/1, strings to ``TextDocument``; every node
    carries ``json_type`` (dict, list, float, int, bool, str, null) and ``json_path`` (the
    JSON-encoded list of keys from the root), which :func:`read_recording` uses to rebuild
    the tree. The tree is first normalised through JSON (tuples become lists, numpy
    scalars Python numbers), so what comes back equals the JSON file.
    """
    import rerun as rr

    obj = _json_normal(obj)
    count = 0
    stack: list[tuple[list, Any]] = [([], obj)]
    while stack:
        keys, v = stack.pop()
        kind = _node_type(v)
        parts: list = [rr.AnyValues(json_type=kind, json_path=json.dumps(keys))]
        if kind == "dict":
            stack.extend((keys + [k], v[k]) for k in sorted(v, reverse=True))
        elif kind == "list":
            parts.append(rr.AnyValues(json_len=str(len(v))))
            stack.extend((keys + [i], v[i]) for i in reversed(range(len(v))))
        elif kind in ("float", "bool"):
            parts.append(rr.Scalars(float(v)))
        elif kind == "int":
            parts.append(rr.AnyValues(json_int=str(v)))
            if abs(v) < 2**53:
                parts.append(rr.Scalars(float(v)))
        elif kind == "str":
            parts.append(rr.TextDocument(v))
        rec.log(_entity(root, keys), *parts, static=True)
        count += 1
    return count


def log_series(rec: rr.RecordingStream, entity: str, values, index: Mapping[str, Any],
               style: str = "line", color=None, name: str | None = None,
               size: float | None = None) -> None:
    """Log a series with one ``send_columns`` call.

    Parameters
    ----------
    rec : the recording.  entity : entity path.  values : (n,) numbers.
    index : timeline name → (n,) values; names ending in ``time`` or given as float
        arrays are duration timelines in seconds, integer arrays sequence timelines.
    style : "line" (SeriesLines) or "points" (SeriesPoints), logged once as static style.
    color : RGB; name : legend label (default: last path part).
    size : marker size (points, default :data:`POINT_SIZE`) or line width (lines, default
        :data:`LINE_WIDTH`), UI points.
    """
    import rerun as rr

    values = np.asarray(values, dtype=float).ravel()
    cols = []
    for tl, x in index.items():
        x = np.asarray(x)
        if x.shape != values.shape:
            raise ValueError(f"{entity}: timeline {tl} has {x.shape}, values {values.shape}")
        if np.issubdtype(x.dtype, np.integer):
            cols.append(rr.TimeColumn(tl, sequence=x.astype(np.int64)))
        else:
            cols.append(rr.TimeColumn(tl, duration=x.astype(float)))
    label = name or entity.rsplit("/", 1)[-1]
    if style == "points":
        rec.log(entity, rr.SeriesPoints(colors=color, names=label,
                                        marker_sizes=POINT_SIZE if size is None else size),
                static=True)
    else:
        rec.log(entity, rr.SeriesLines(colors=color, names=label,
                                       widths=LINE_WIDTH if size is None else size),
                static=True)
    rec.send_columns(entity, indexes=cols, columns=rr.Scalars.columns(scalars=values))


def full_time_axis() -> Any:
    """X axis of a time-series view showing the whole timeline, not the cursor ± 1000 default
    (which shows 3–6 samples on ``theta_urad``, where samples are ~314 µrad apart)."""
    import rerun.blueprint as rrb

    return rrb.TimeAxis(view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.infinite(),
                                                 end=rrb.TimeRangeBoundary.infinite()))


def time_panel(timeline: str, play_state: str = "paused") -> Any:
    """Collapsed time panel on ``timeline`` that does not play (the viewer would otherwise
    start playing and give the panel a quarter of the screen). ``"following"`` puts the time
    cursor at the end of the timeline (a vehicle run opens at its arrival, not at t = 0)."""
    import rerun.blueprint as rrb

    return rrb.TimePanel(timeline=timeline, play_state=play_state, state="collapsed")


def binned_mean(x: np.ndarray, y: np.ndarray, bins: int = MEAN_BINS
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean of ``y`` over ``bins`` groups of consecutive ``x`` (equal sample counts).

    Returns (bin centre = mean x, mean y, the sample index at the middle of each bin); the
    line it draws shows a systematic signature that the raw scatter of 20001 points hides.
    Equal counts make the band ``±2σ/sqrt(N/bins)`` exact for every bin. The recordings and
    the figures (:mod:`bench.figures`, the gap figure) draw their binned means with it.
    """
    x, y = np.asarray(x, float).ravel(), np.asarray(y, float).ravel()
    if x.size == 0:
        return x, y, np.zeros(0, dtype=np.int64)
    order = np.argsort(x, kind="stable")
    groups = [g for g in np.array_split(order, min(bins, x.size)) if g.size]
    return (np.array([x[g].mean() for g in groups]), np.array([y[g].mean() for g in groups]),
            np.array([int(np.sort(g)[g.size // 2]) for g in groups], dtype=np.int64))


def record_series(path: str | os.PathLike, series: Mapping[str, Any], *,
                  index: Any = None, timeline: str = SAMPLE_TIMELINE,
                  bands: Mapping[str, float] | None = None,
                  trees: Mapping[str, Any] | None = None, force: bool = False,
                  title: str = "tiltbench series") -> Path:
    """A recording of named series (e.g. residuals before/after a model change).

    Generic helper for the discrepancy workflow: every entry of ``series`` becomes one
    time-series entity; each top-level group (first path part) gets its own view.

    Parameters
    ----------
    path : output ``.rrd``.
    series : entity path → (n,) values, e.g. ``{"gap/x/residual/before": r0,
        "gap/x/residual/after": r1}``. All series share the index.
    index : (n,) x values: integers → sequence timeline, floats → duration (seconds), or
        None → the sample number. A θ index (rad) is better given as
        ``np.round(theta * 1e6).astype(int)`` with ``timeline="theta_urad"``.
    timeline : name of the timeline.
    bands : entity path → σ: a ±σ band (``<path>_band/plus`` and ``/minus``) drawn at the
        first and last index of that series.
    trees : root → JSON-like object logged with :func:`log_tree` (e.g. ``{"gap": report}``);
        :func:`read_recording` returns them under their root name.
    force : replace an existing file.
    """
    import rerun.blueprint as rrb

    groups = sorted({k.split("/", 1)[0] for k in series})
    views = [rrb.TimeSeriesView(origin=g, name=g, axis_x=full_time_axis()) for g in groups]
    bp = rrb.Blueprint(rrb.Vertical(*views) if views else rrb.Vertical(),
                       time_panel(timeline), collapse_panels=True)
    with open_recording(path, force, bp, title) as rec:
        for name, vals in series.items():
            vals = np.asarray(vals, dtype=float).ravel()
            x = np.arange(vals.size) if index is None else np.asarray(index)
            log_series(rec, name, vals, {timeline: x}, style="points")
            if bands and name in bands:
                s = float(bands[name])
                ends = x[[0, -1]] if x.size else x
                for part, sign in (("plus", 1.0), ("minus", -1.0)):
                    log_series(rec, f"{name}_band/{part}", np.full(ends.shape, sign * s),
                               {timeline: ends}, color=COLORS["band"], name=f"{sign:+.0f}σ")
        for root, tree in (trees or {}).items():
            log_tree(rec, root, tree)
    return Path(path)


# ----------------------------------------------------------------------- calibration

PLOT_BOX = (300.0, 100.0)
"""Width and height (view units) of every static 2-D plot: its data box is mapped onto this
box by the plot's ``Transform3D``, so plots of very different ranges keep a 3:1 shape."""


@dataclass(frozen=True)
class StaticPlot:
    """A data box [x0, x1] × [y0, y1] drawn as a static 2-D plot (timeline-independent).

    The plot entity carries ``Transform3D(translation, scale)`` mapping the data box onto
    [0, W] × [0, H] of the view with +y up (rerun's 2-D space has +y down); its children are
    logged in data units. ``axes`` and ``axes/labels`` draw the frame, ticks and tick values.
    """

    x0: float
    x1: float
    y0: float
    y1: float

    @classmethod
    def around(cls, x, y, pad: float = 0.04, symmetric_y: bool = False) -> StaticPlot:
        x, y = np.asarray(x, float), np.asarray(y, float)
        x0, x1 = float(np.min(x)), float(np.max(x))
        y0, y1 = float(np.min(y)), float(np.max(y))
        if symmetric_y:
            y1 = max(abs(y0), abs(y1))
            y0 = -y1
        if x1 == x0:  # a degenerate box would make the transform singular
            x0, x1 = x0 - 0.5, x1 + 0.5
        dy = (y1 - y0) or 1.0
        return cls(x0, x1, y0 - pad * dy, y1 + pad * dy)

    def transform(self) -> Any:
        import rerun as rr

        w, h = PLOT_BOX
        sx, sy = w / (self.x1 - self.x0), h / (self.y1 - self.y0)
        # rerun applies scale, then translation: X = sx·x − sx·x0, Y = −sy·y + h + sy·y0
        return rr.Transform3D(translation=(-sx * self.x0, h + sy * self.y0, 0.0),
                              scale=(sx, -sy, 1.0))

    def log_frame(self, rec: rr.RecordingStream, entity: str, zero_line: bool = False) -> None:
        """Log the transform at ``entity`` and the frame at ``entity/axes`` (+ ``/labels``)."""
        import rerun as rr

        rec.log(entity, self.transform(), static=True)
        dx, dy = self.x1 - self.x0, self.y1 - self.y0
        x0, x1, y0, y1 = self.x0, self.x1, self.y0, self.y1
        strips = [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])]
        xt, yt = _nice_ticks(x0, x1), _nice_ticks(y0, y1)
        strips += [np.array([[t, y0], [t, y0 - 0.03 * dy]]) for t in xt]
        strips += [np.array([[x0, t], [x0 - 0.01 * dx, t]]) for t in yt]
        if zero_line and y0 < 0 < y1:
            strips.append(np.array([[x0, 0.0], [x1, 0.0]]))
        rec.log(f"{entity}/axes", rr.LineStrips2D(strips, radii=rr.Radius.ui_points(0.75),
                                                  colors=COLORS["axes"], draw_order=5.0),
                static=True)
        # rerun draws a point's label below the point: x labels just under the ticks
        pos = [[t, y0 - 0.05 * dy] for t in xt] + [[x0 - 0.045 * dx, t + 0.04 * dy] for t in yt]
        labels = [_tick_text(t, xt) for t in xt] + [_tick_text(t, yt) for t in yt]
        rec.log(f"{entity}/axes/labels", rr.Points2D(
            np.array(pos, dtype=float), radii=0.0, labels=labels, colors=COLORS["axes"],
            show_labels=True, draw_order=40.0), static=True)


def _nice_ticks(lo: float, hi: float, n: int = 5) -> np.ndarray:
    """About ``n`` round tick values inside [lo, hi]."""
    span = hi - lo
    if not np.isfinite(span) or span <= 0:
        return np.array([lo])
    raw = span / n
    mag = 10.0 ** np.floor(np.log10(raw))
    step = mag * min((1.0, 2.0, 2.5, 5.0, 10.0), key=lambda m: abs(m * mag - raw))
    ticks = np.arange(np.ceil(lo / step) * step, hi + 1e-9 * span, step)
    return ticks[(ticks >= lo - 1e-9 * span) & (ticks <= hi + 1e-9 * span)]


def _tick_text(t: float, ticks: np.ndarray) -> str:
    step = float(np.min(np.diff(ticks))) if ticks.size > 1 else 1.0
    digits = max(0, -int(np.floor(np.log10(step) + 1e-9)))
    return f"{0.0 if abs(t) < 1e-12 * step else t:.{digits}f}"


def _plot_bounds() -> Any:
    """View bounds of a :class:`StaticPlot` (the box plus room for the tick labels)."""
    import rerun.blueprint as rrb

    w, h = PLOT_BOX
    return rrb.VisualBounds2D(x_range=[-0.09 * w, 1.02 * w], y_range=[-0.03 * h, 1.2 * h])


def _axis_views(axis: str, fit: bool = True, true: bool = False) -> Any:
    """The three views of one axis: data and model, residual ±σ, error against A_r.

    All three are static 2-D plots (θ in rad on the x axis, readable whatever the active
    timeline: a recording with a vehicle run has ``time``, on which θ series are empty). The
    same data are also logged as series on ``theta_urad`` for custom time-series views.
    """
    import rerun.blueprint as rrb

    o = f"calibration/{axis}"
    model = ", ".join([*(["fit (red)"] if fit else []), *(["true (green)"] if true else [])])
    return rrb.Vertical(
        rrb.Spatial2DView(origin=o, contents=[f"+ {o}/theta_plot/**"],
                          name=f"{axis}: A_m (blue), {model} vs θ (rad); m/s²",
                          visual_bounds=_plot_bounds()),
        rrb.Spatial2DView(origin=o, contents=[f"+ {o}/residual_plot/**"],
                          name=f"{axis}: residual, ±σ (orange), binned mean (white) vs θ "
                               "(rad); m/s²", visual_bounds=_plot_bounds()),
        rrb.Spatial2DView(origin=o, contents=[f"+ {o}/vs_ar/**"],
                          name=f"{axis}: A_m − A_r vs A_r: {model}, ideal 0 (grey), binned "
                               "mean (white); m/s²", visual_bounds=_plot_bounds()))


def _calibration_blueprint(fit: bool = True, true: bool = False) -> Any:
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Vertical(rrb.Horizontal(_axis_views("x", fit, true), _axis_views("y", fit, true)),
                     rrb.TextDocumentView(origin="summary/parameters",
                                          name="estimates vs truth" if fit else "truth"),
                     row_shares=[5, 2]),
        time_panel(THETA_TIMELINE), collapse_panels=True)


def _line(x0: float, x1: float, b: float, s: float) -> np.ndarray:
    """The error line A_m − A_r = s·A_r + b over [x0, x1] (the model (1 + s)·A_r + b)."""
    xs = np.array([x0, x1])
    return np.column_stack([xs, s * xs + b])


def _log_axis_data(rec: rr.RecordingStream, axis: str, theta: np.ndarray, a_m: np.ndarray,
                   a_r: np.ndarray, fit_line: tuple[float, float] | None,
                   true_line: tuple[float, float] | None, a_true: np.ndarray | None,
                   sigma: float) -> None:
    """Per-axis calibration entities (see :data:`ENTITY_DOCS`): time series on θ and the same
    content as static 2-D plots."""
    import rerun as rr

    o = f"calibration/{axis}"
    idx = {SAMPLE_TIMELINE: np.arange(theta.size, dtype=np.int64),
           THETA_TIMELINE: np.round(theta * 1e6).astype(np.int64)}
    log_series(rec, f"{o}/measured", a_m, idx, "points", COLORS["measured"], f"A_m{axis}")
    # Smooth curves are drawings: at most CURVE_POINTS samples (every k-th, ends kept).
    k = max(1, int(np.ceil(theta.size / CURVE_POINTS)))
    sub = np.unique(np.r_[np.arange(0, theta.size, k), theta.size - 1])
    sub = sub[np.argsort(theta[sub], kind="stable")]  # drawn left to right in θ
    sub_idx = {tl: v[sub] for tl, v in idx.items()}
    curves: dict[str, np.ndarray] = {}
    if fit_line is not None:
        b, s = fit_line
        curves["fit"] = (1.0 + s) * a_r + b
    if true_line is not None:
        b, s = true_line
        base = a_r if a_true is None else a_true
        curves["true"] = (1.0 + s) * base + b
    for name, curve in curves.items():
        log_series(rec, f"{o}/{name}", curve[sub], sub_idx, "line", COLORS[name], name)
    model = curves.get("fit", curves.get("true", a_r))
    resid = a_m - model
    log_series(rec, f"{o}/residual", resid, idx, "points", COLORS["measured"], "residual")
    ends = np.array([int(np.argmin(theta)), int(np.argmax(theta))])
    end_idx = {k: v[ends] for k, v in idx.items()}
    for part, sign in (("plus", 1.0), ("minus", -1.0)):
        log_series(rec, f"{o}/residual_band/{part}", np.full(2, sign * sigma), end_idx, "line",
                   COLORS["band"], f"{'+' if sign > 0 else '−'}σ = {sign * sigma:.3g}")
    th_mean, r_mean, at = binned_mean(theta, resid)
    log_series(rec, f"{o}/residual_mean", r_mean,
               {SAMPLE_TIMELINE: at, THETA_TIMELINE: np.round(th_mean * 1e6).astype(np.int64)},
               "line", COLORS["mean"],
               f"binned mean ({theta.size // max(1, th_mean.size)} per bin)")

    # The same as static 2-D plots (θ in rad), readable whatever the active timeline.
    pts = rr.Radius.ui_points(0.6)
    line = rr.Radius.ui_points(LINE_WIDTH / 2)
    plot = StaticPlot.around(theta, np.r_[a_m, *(c[sub] for c in curves.values())])
    plot.log_frame(rec, f"{o}/theta_plot")
    rec.log(f"{o}/theta_plot/measured", rr.Points2D(
        np.column_stack([theta, a_m]), radii=pts, colors=COLORS["measured"], draw_order=10.0),
        static=True)
    thin = rr.Radius.ui_points(LINE_WIDTH / 4)  # the true line, thinner, on top of the fit
    for name, curve in curves.items():
        rec.log(f"{o}/theta_plot/{name}", rr.LineStrips2D(
            [np.column_stack([theta[sub], curve[sub]])], colors=COLORS[name],
            radii=thin if name == "true" and "fit" in curves else line,
            draw_order=30.0 if name == "fit" else 31.0), static=True)
    lim = max(float(np.max(np.abs(resid))) if resid.size else 0.0, 1.2 * sigma)
    plot = StaticPlot.around(theta, [-lim, lim], symmetric_y=True)
    plot.log_frame(rec, f"{o}/residual_plot", zero_line=True)
    rec.log(f"{o}/residual_plot/residual", rr.Points2D(
        np.column_stack([theta, resid]), radii=pts, colors=COLORS["measured"],
        draw_order=10.0), static=True)
    t0, t1 = float(np.min(theta)), float(np.max(theta))
    rec.log(f"{o}/residual_plot/band", rr.LineStrips2D(
        [np.array([[t0, sigma], [t1, sigma]]), np.array([[t0, -sigma], [t1, -sigma]])],
        radii=line, colors=COLORS["band"], draw_order=20.0), static=True)
    rec.log(f"{o}/residual_plot/mean", rr.LineStrips2D(
        [np.column_stack([th_mean, r_mean])], radii=line, colors=COLORS["mean"],
        draw_order=30.0), static=True)

    # Error of the raw reading against the reference: slope = scale, offset = bias.
    err = a_m - a_r
    lo, hi = float(np.min(a_r)), float(np.max(a_r))
    lines = {name: _line(lo, hi, *ln) for name, ln in
             (("fit", fit_line), ("true", true_line), ("ideal", (0.0, 0.0))) if ln is not None}
    plot = StaticPlot.around(a_r, np.r_[err, *(ln[:, 1] for ln in lines.values())])
    plot.log_frame(rec, f"{o}/vs_ar")
    rec.log(f"{o}/vs_ar/measured", rr.Points2D(np.column_stack([a_r, err]), radii=pts,
                                                colors=COLORS["measured"], draw_order=10.0),
            static=True)
    ar_mean, e_mean, _ = binned_mean(a_r, err)
    rec.log(f"{o}/vs_ar/mean", rr.LineStrips2D(
        [np.column_stack([ar_mean, e_mean])], radii=line, colors=COLORS["mean"],
        draw_order=25.0), static=True)
    for name, ln in lines.items():
        rec.log(f"{o}/vs_ar/{name}", rr.LineStrips2D(
            [ln], radii=thin if name == "true" and fit_line is not None else line,
            colors=COLORS[name],
            draw_order={"ideal": 28.0, "fit": 30.0, "true": 31.0}[name]), static=True)


def parameters_markdown(estimates: Mapping | None, truth: Mapping | None,
                        level: float = 0.95) -> str:
    """Markdown table: estimate, std, interval at ``level``, true value, z per parameter."""
    from scipy import stats

    from bench.validate import true_sensor_params

    tp = true_sensor_params(truth) if truth else None
    q = float(stats.norm.ppf(0.5 + level / 2))
    pct = f"{100 * level:g}%"
    lines = [f"| parameter | estimate | std | {pct} interval | true | z |",
             "|---|---|---|---|---|---|"]
    for a in AXES:
        for p, unit in (("bias", " (m/s²)"), ("scale", "")):
            est = std = None
            if estimates:
                ax = estimates.get("axes", {}).get(a, {})
                est, std = ax.get(p), ax.get(f"{p}_std")
            true = tp.get(f"{p}_{a}") if tp else None
            cells = [f"{p}_{a}{unit}"]
            cells.append("—" if est is None else f"{est:.6g}")
            cells.append("—" if std is None else f"{std:.3g}")
            cells.append("—" if est is None or std is None else
                         f"[{est - q * std:.6g}, {est + q * std:.6g}]")
            cells.append("—" if true is None else f"{true:.6g}")
            cells.append("—" if None in (est, std, true) or not std else
                         f"{(est - true) / std:+.2f}")
            lines.append("| " + " | ".join(cells) + " |")
    note = ("Intervals use normal quantiles (±" + f"{q:.3f}σ); z = (estimate − true)/std.")
    return "\n".join(lines) + "\n\n" + note + "\n"


def _log_calibration(rec: rr.RecordingStream, cal: Calibration, ensayo: Ensayo,
                     truth: Mapping | None, level: float) -> None:
    from bench.validate import true_sensor_params

    a_r = reference_accel(ensayo.tita, cal.g)
    tp = true_sensor_params(truth) if truth else None
    for k, a in enumerate(AXES):
        f = cal.fits[a]
        true_line = (tp[f"bias_{a}"], tp[f"scale_{a}"]) if tp else None
        _log_axis_data(rec, a, ensayo.tita, ensayo.datos[:, k], a_r[:, k],
                       (f.param("bias"), f.param("scale")), true_line, None,
                       float(np.sqrt(f.sigma2)))
    est = cal.to_dict()
    log_tree(rec, "estimate", est)
    if truth is not None:
        log_tree(rec, "truth", truth)
    import rerun as rr

    rec.log("summary/parameters", rr.TextDocument(
        "# Calibration: estimates vs truth\n\n" + parameters_markdown(est, truth, level),
        media_type=rr.MediaType.MARKDOWN), static=True)


def record_calibration(cal: Calibration, ensayo: Ensayo, path: str | os.PathLike,
                       force: bool = False, truth: Mapping | None = None,
                       level: float = 0.95) -> Path:
    """Record a calibration: per axis data, fit, residuals ±σ, estimates (and truth).

    Parameters
    ----------
    cal : the calibration (:func:`calib.calibration.calibrate`).
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
    with open_recording(path, force, _calibration_blueprint(True, has_true),
                        "calibration") as rec:
        _log_calibration(rec, cal, ensayo, truth, level)
    return Path(path)


def truth_manifest(truth: Mapping, seed: int) -> dict:
    """``truth.json`` as :func:`bench.dataset.write_truth` writes it (seed and versions)."""
    from bench.dataset import versions

    manifest = dict(truth)
    manifest["seed"] = int(seed)
    manifest["versions"] = versions()
    return _json_normal(manifest)


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
    a_r = reference_accel(run.tita, run.config.g)
    with open_recording(path, force, _calibration_blueprint(False, True),
                        "calibration truth") as rec:
        for k, a in enumerate(AXES):
            err = run.config.sensor.axis(a)
            _log_axis_data(rec, a, run.tita, run.datos[:, k], a_r[:, k], None,
                           (err.bias, err.scale), run.a_true[:, k], float(np.sqrt(err.noise_var)))
        log_tree(rec, "truth", truth)
        rec.log("summary/parameters", rr.TextDocument(
            "# Generated calibration run: true parameters\n\n"
            + parameters_markdown(None, truth), media_type=rr.MediaType.MARKDOWN), static=True)
    return Path(path)


# --------------------------------------------------------------------------- vehicle

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

    from calib.trajectory import integrate_twice

    manifest = truth_manifest(truth if truth is not None else run.truth_dict(), run.seed)
    raw, _ = integrate_twice(run.t, run.aerr, run.config.p0, run.config.v0)
    cand = None if candidates is None else np.array(list(candidates.values()), dtype=float)
    blueprint = _vehicle_blueprint(plane_bounds(raw, run.truth.pos, cand), estimated=False,
                                   acc=("measured", "true"), paths=("raw", "true"),
                                   candidates=candidates is not None,
                                   calibration=None if calibration is None else (False, True),
                                   texts=("parameters",))
    with open_recording(path, force, blueprint, "truth") as rec:
        tl = {TIME_TIMELINE: run.t - run.t[0]}
        for name, acc in (("measured", run.aerr), ("true", run.truth.acc)):
            for k, a in enumerate(AXES):
                log_series(rec, f"vehicle/acceleration/{name}/{a}", acc[:, k], tl, "line",
                           COLORS["raw" if name == "measured" else name], f"{name} {a}", 1.0)
        _log_paths(rec, run.t, {"raw": raw, "true": run.truth.pos})
        if candidates is not None:
            _log_candidates(rec, candidates)
        if calibration is not None:
            a_r = reference_accel(calibration.tita, calibration.config.g)
            for k, a in enumerate(AXES):
                err = calibration.config.sensor.axis(a)
                _log_axis_data(rec, a, calibration.tita, calibration.datos[:, k], a_r[:, k],
                               None, (err.bias, err.scale), calibration.a_true[:, k],
                               float(np.sqrt(err.noise_var)))
        log_tree(rec, "truth", manifest)
        arrival = _true_arrival(manifest) if candidates is not None else None
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


def position_cov_along(traj: Trajectory, cal: Calibration, noise_var,
                       indices) -> np.ndarray:
    """Covariance (len(indices), 2, 2) of the corrected position at the given samples, m².

    Error propagation over time: for sample k the trajectory truncated at ``t_k`` is a
    trajectory of its own, so :func:`calib.region.position_jacobian` and
    :func:`calib.region.noise_position_cov` give ``Σ_P(t_k) = J_k Σ_c J_kᵀ + Σ_noise,k``
    (same model as the arrival point). Samples 0 and 1 have zero covariance (P0, V0 exact;
    the quadrature needs three samples).
    """
    from calib.region import noise_cov_matrix, noise_position_cov, position_jacobian
    from calib.trajectory import Trajectory

    C = noise_cov_matrix(noise_var)
    out = np.zeros((len(indices), 2, 2))
    for i, k in enumerate(indices):
        k = int(k)
        if k < 2:
            continue
        sl = slice(0, k + 1)
        sub = Trajectory(traj.t[sl], traj.acc_raw[sl], traj.acc_corrected[sl],
                         traj.pos_raw[sl], traj.vel_raw[sl], traj.pos_corrected[sl],
                         traj.vel_corrected[sl], traj.p0, traj.v0, traj.bias, traj.scale,
                         traj.integrator)
        J = position_jacobian(sub)
        cov = J @ cal.cov @ J.T + noise_position_cov(sub, C)
        out[i] = 0.5 * (cov + cov.T)
    return out


def _ellipse_points(center, cov, level: float, n: int = 96) -> np.ndarray:
    from calib.region import Ellipse

    if not np.any(cov):
        return np.repeat(np.asarray(center, float)[None, :], 2, axis=0)
    return Ellipse.from_cov(center, cov, level).boundary(n)


def plane_bounds(*arrays, margin: float = 0.06) -> Any:
    """View bounds around all given (n, 2) plane positions (m) with a margin on each side.

    The plane is drawn under ``vehicle/plane`` (scale (1, −1, 1)), so the view's y is −y.
    """
    import rerun.blueprint as rrb

    pts = np.concatenate([np.asarray(a, float).reshape(-1, 2) for a in arrays if a is not None])
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = margin * max(float(np.max(hi - lo)), 1.0)
    return rrb.VisualBounds2D(x_range=[lo[0] - pad, hi[0] + pad],
                              y_range=[-hi[1] - pad, -lo[1] + pad])


def _vehicle_blueprint(bounds: Any, *, estimated: bool, acc: tuple[str, ...],
                       paths: tuple[str, ...], candidates: bool,
                       calibration: tuple[bool, bool] | None, level: float | None = None,
                       snapshot_dt: float | None = None, texts: tuple[str, ...] = ()) -> Any:
    """Vehicle tab (and a static calibration tab when ``calibration`` = (fit, true) is given).

    ``estimated``: a corrected run (position std view); ``acc``: the acceleration series
    logged (measured, corrected, true); ``paths``: the paths drawn; ``texts``: the
    ``summary/*`` documents, one view each (a text view shows one document). The view name
    is the legend (labels on the paths overprinted the other labels).
    """
    import rerun.blueprint as rrb

    hue = {"true": "green", "corrected": "blue", "raw": "grey"}
    parts = ["paths: " + ", ".join(f"{k} {hue[k]}" for k in ("true", "corrected", "raw")
                                   if k in paths)]
    if candidates:
        parts.append("candidates magenta")
    if estimated:
        pct = f"{100 * level:g}%" if level is not None else ""
        every = f" every {snapshot_dt:.0f} s" if snapshot_dt else ""
        parts.append(f"{pct} ellipses: arrival red, along the run orange{every}")
    plane = rrb.Spatial2DView(origin="vehicle", contents=["+ vehicle/plane/**"],
                              name="plane (m) — " + "; ".join(parts), visual_bounds=bounds)
    names = {"decision": "decision", "parameters": "estimates" if estimated else "truth"}
    side = [rrb.TimeSeriesView(origin="vehicle/acceleration",
                               contents=[f"+ vehicle/acceleration/{k}/{a}" for k in acc],
                               name=f"acceleration {a} (m/s²): " + ", ".join(acc),
                               axis_x=full_time_axis()) for a in AXES]
    if estimated:
        side.append(rrb.TimeSeriesView(origin="vehicle/position_std", axis_x=full_time_axis(),
                                       name="std of the corrected position (m)"))
    docs = [rrb.TextDocumentView(origin=f"summary/{t}", name=names.get(t, t)) for t in texts]
    if len(docs) > 1:
        side.append(rrb.Tabs(*docs))
    else:
        side += docs
    vehicle = rrb.Horizontal(plane, rrb.Vertical(*side), column_shares=[3, 2], name="vehicle")
    tabs = [vehicle]
    if calibration is not None:
        fit, true = calibration
        tabs.append(rrb.Horizontal(_axis_views("x", fit, true), _axis_views("y", fit, true),
                                   name="calibration"))
    return rrb.Blueprint(rrb.Tabs(*tabs) if len(tabs) > 1 else vehicle,
                         time_panel(TIME_TIMELINE, "following"), collapse_panels=True)


def decision_markdown(region: ArrivalRegion, true_arrival: str | None = None) -> str:
    """Markdown summary of the arrival decision (and the truth, when known)."""
    lines = [f"# Arrival: {region.decision or 'undecided'}", "", region.reason, "",
             f"Estimate ({region.estimate[0]:.2f}, {region.estimate[1]:.2f}) m, std "
             f"({region.std[0]:.2f}, {region.std[1]:.2f}) m; {100 * region.level:g}% ellipse "
             f"semi-axes {region.ellipse.semi_axes[0]:.2f} × {region.ellipse.semi_axes[1]:.2f} m.",
             ""]
    if true_arrival is not None:
        lines += [f"True arrival point (truth.json): **{true_arrival}**", ""]
    lines += ["| candidate | x (m) | y (m) | Mahalanobis | inside |", "|---|---|---|---|---|"]
    for k, c in region.candidates.items():
        lines.append(f"| {k} | {c[0]:.2f} | {c[1]:.2f} | {region.mahalanobis[k]:.3f} | "
                     f"{'yes' if k in region.inside else 'no'} |")
    return "\n".join(lines) + "\n"


SNAPSHOTS = 10
"""Growing-ellipse snapshots drawn statically along the run."""


def _snapshot_dt(traj: Trajectory) -> float:
    return float(traj.t[-1] - traj.t[0]) / SNAPSHOTS


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


def _log_candidates(rec: rr.RecordingStream, candidates: Mapping[str, Any]) -> None:
    import rerun as rr

    names = list(candidates)
    rec.log("vehicle/plane/candidates", rr.Points2D(
        np.array([candidates[k] for k in names], dtype=float), labels=names,
        radii=rr.Radius.ui_points(6.0), colors=COLORS["candidate"], show_labels=True,
        draw_order=35.0), static=True)


def _log_vehicle(rec: rr.RecordingStream, traj: Trajectory, region: ArrivalRegion,
                 cal: Calibration, true_path: np.ndarray | None,
                 true_acc: np.ndarray | None, n_ellipses: int = 200) -> None:
    import rerun as rr

    t = traj.t
    tl = {TIME_TIMELINE: t - t[0]}
    for name, acc in (("measured", traj.acc_raw), ("corrected", traj.acc_corrected),
                      ("true", true_acc)):
        if acc is None:
            continue
        for k, a in enumerate(AXES):
            log_series(rec, f"vehicle/acceleration/{name}/{a}", acc[:, k], tl, "line",
                       COLORS["raw" if name == "measured" else name], f"{name} {a}", 1.0)
    _log_paths(rec, t, {"raw": traj.pos_raw, "corrected": traj.pos_corrected,
                        "true": true_path})
    _log_candidates(rec, region.candidates)
    pct = f"{100 * region.level:g}%"
    # One label for estimate and ellipse (two labels at the same centre overprint).
    rec.log("vehicle/plane/arrival/estimate", rr.Points2D(
        region.estimate[None, :], radii=rr.Radius.ui_points(4.0), colors=COLORS["ellipse"],
        labels=f"arrival {region.decision or 'undecided'} ({pct} ellipse)", show_labels=True,
        draw_order=45.0), static=True)
    rec.log("vehicle/plane/arrival/ellipse", rr.LineStrips2D(
        [region.ellipse.boundary(256)], radii=rr.Radius.ui_points(2.0), colors=COLORS["ellipse"],
        draw_order=32.0), static=True)  # above the moving ellipse, which ends on it
    m = t.shape[0]
    idx = np.unique(np.linspace(0, m - 1, min(n_ellipses, m)).round().astype(int))
    covs = position_cov_along(traj, cal, region.noise_var, idx)
    centers = traj.pos_corrected[idx]
    strips = [_ellipse_points(c, s, region.level) for c, s in zip(centers, covs, strict=True)]
    t_idx = tl[TIME_TIMELINE][idx]
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


def trajectory_tree(traj: Trajectory, region: ArrivalRegion, cal: Calibration | None = None,
                    method: str = "ols", noise_var_source: str = "given") -> dict:
    """The trajectory/decision object logged under ``trajectory/``.

    The same object as ``tiltbench trajectory --json`` (``bench/cli_trajectory.py``): the
    trajectory and region dictionaries merged, with ``level``, ``method``,
    ``noise_var_source`` and ``calibration``.
    """
    out = {**traj.to_dict(), **region.to_dict()}
    out.update(level=region.level, method=method, noise_var_source=noise_var_source)
    if cal is not None:
        out["calibration"] = cal.to_dict()
    out["ellipse"] = {k: region.ellipse.to_dict()[k]
                      for k in ("level", "semi_axes", "angle_rad", "area", "center")}
    return out


def record_trajectory(traj: Trajectory, region: ArrivalRegion, cal: Calibration,
                      path: str | os.PathLike, force: bool = False,
                      truth: Mapping | None = None, true_path: np.ndarray | None = None,
                      true_acc: np.ndarray | None = None, tree: Mapping | None = None) -> Path:
    """Record a vehicle run: accelerations, paths, candidates, arrival ellipse and growth.

    Parameters
    ----------
    traj : raw and corrected trajectory (:func:`calib.trajectory.compute_trajectory`).
    region : arrival region and decision (:func:`calib.region.arrival_region`).
    cal : the calibration used (its covariance drives the ellipses along time).
    path : output ``.rrd``.  force : replace an existing file.
    truth : ``truth.json`` object, if known (logged under ``truth/``).
    true_path : (M, 2) true positions, m, if known.  true_acc : (M, 2) true accelerations.
    tree : the object logged under ``trajectory/`` (default :func:`trajectory_tree`).
    """
    import rerun as rr

    bp = _vehicle_blueprint(_region_bounds(traj, region, true_path), estimated=True,
                            acc=_acc_kinds(true_acc), paths=_path_kinds(true_path),
                            candidates=True, calibration=None, level=region.level,
                            snapshot_dt=_snapshot_dt(traj), texts=("decision", "parameters"))
    with open_recording(path, force, bp, "vehicle") as rec:
        _log_vehicle(rec, traj, region, cal, true_path, true_acc)
        log_tree(rec, "trajectory",
                 tree if tree is not None else trajectory_tree(traj, region, cal))
        log_tree(rec, "estimate", cal.to_dict())
        if truth is not None:
            log_tree(rec, "truth", truth)
        rec.log("summary/decision", rr.TextDocument(
            decision_markdown(region, _true_arrival(truth)), media_type=rr.MediaType.MARKDOWN),
            static=True)
        rec.log("summary/parameters", rr.TextDocument(
            parameters_markdown(cal.to_dict(), truth), media_type=rr.MediaType.MARKDOWN),
            static=True)
    return Path(path)


def _acc_kinds(true_acc) -> tuple[str, ...]:
    return ("measured", "corrected") + (("true",) if true_acc is not None else ())


def _path_kinds(true_path) -> tuple[str, ...]:
    return ("raw", "corrected") + (("true",) if true_path is not None else ())


def _region_bounds(traj: Trajectory, region: ArrivalRegion, true_path) -> Any:
    return plane_bounds(traj.pos_raw, traj.pos_corrected, true_path,
                        np.array(list(region.candidates.values()), dtype=float),
                        region.ellipse.boundary(256))


def _true_arrival(truth: Mapping | None) -> str | None:
    """The true arrival letter from a course truth, if present (searched by key name)."""
    if not truth:
        return None
    stack: list[Any] = [truth]
    while stack:
        d = stack.pop()
        if isinstance(d, Mapping):
            for key in ("answer", "true_arrival", "arrival"):
                v = d.get(key)
                if isinstance(v, str):
                    return v
            stack.extend(d.values())
    return None


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
    bp = _vehicle_blueprint(_region_bounds(traj, region, true_path), estimated=True,
                            acc=_acc_kinds(true_acc), paths=_path_kinds(true_path),
                            candidates=True, calibration=(True, has_true),
                            level=region.level, snapshot_dt=_snapshot_dt(traj),
                            texts=("decision", "parameters"))
    with open_recording(path, force, bp, "course") as rec:
        _log_calibration(rec, cal, ensayo, truth, level)
        _log_vehicle(rec, traj, region, cal, true_path, true_acc)
        log_tree(rec, "trajectory",
                 tree if tree is not None else trajectory_tree(traj, region, cal))
        rec.log("summary/decision", rr.TextDocument(
            decision_markdown(region, _true_arrival(truth)), media_type=rr.MediaType.MARKDOWN),
            static=True)
    return Path(path)


# --------------------------------------------------------------------------- reading

def _first(batch, name: str):
    if name not in batch.schema.names:
        return None
    v = batch.column(name).to_pylist()[-1]
    if isinstance(v, list):
        return v[-1] if v else None
    return v


def recording_entities(path: str | os.PathLike) -> list[str]:
    """Sorted entity paths of the first recording store (without ``/__properties``)."""
    from rerun.chunk import RrdReader

    if not Path(path).exists():
        raise FileNotFoundError(f"{path}: file not found")
    try:
        ents = {ch.entity_path for ch in RrdReader(str(path)).stream().to_chunks()}
    except Exception as exc:
        raise ValueError(f"{path}: not a readable rerun recording ({exc})") from exc
    return sorted(e for e in ents if not e.startswith("/__properties"))


def read_trees(path: str | os.PathLike) -> dict[str, Any]:
    """Every JSON tree in a recording: root entity → rebuilt object (see :func:`log_tree`)."""
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: file not found")
    try:
        chunks = RrdReader(str(path)).stream().to_chunks()
    except Exception as exc:
        raise ValueError(f"{path}: not a readable rerun recording ({exc})") from exc
    nodes: dict[str, dict[tuple, tuple[str, Any, int]]] = {}
    for ch in chunks:
        b = ch.to_record_batch()
        kind = _first(b, "json_type")
        if kind is None:
            continue
        keys = tuple(json.loads(_first(b, "json_path")))
        root = ch.entity_path.lstrip("/").split("/", 1)[0]
        if kind in ("float", "bool"):
            val: Any = float(_first(b, "Scalars:scalars"))
            if kind == "bool":
                val = bool(val)
        elif kind == "int":
            val = int(_first(b, "json_int"))
        elif kind == "str":
            val = _first(b, "TextDocument:text")
        elif kind == "null":
            val = None
        else:
            val = None
        length = int(_first(b, "json_len")) if kind == "list" else 0
        nodes.setdefault(root, {})[keys] = (kind, val, length)
    return {root: _rebuild(tree, path, root) for root, tree in nodes.items()}


def _rebuild(nodes: dict[tuple, tuple[str, Any, int]], path: Path, root: str) -> Any:
    def build(keys: tuple) -> Any:
        if keys not in nodes:
            raise ValueError(f"{path}: tree '{root}' lacks node {list(keys)}")
        kind, val, length = nodes[keys]
        if kind == "dict":
            kids = sorted(k[-1] for k in nodes if len(k) == len(keys) + 1 and k[:-1] == keys)
            return {k: build(keys + (k,)) for k in kids}
        if kind == "list":
            return [build(keys + (i,)) for i in range(length)]
        return val

    return build(())


def read_recording(path: str | os.PathLike) -> dict[str, Any]:
    """Truth and estimates back from a recording, with rerun's own reader.

    Returns
    -------
    dict with ``"truth"`` (the ``truth.json`` object or None), ``"estimates"`` (the
    ``calibrate --json`` object or None), ``"trajectory"`` (trajectory/decision object or
    None) and any further tree under its root name (e.g. ``"gap"``). Numbers come back bit
    exact (float64 scalars; integers from their decimal text).
    """
    trees = read_trees(path)
    out: dict[str, Any] = {v: trees.pop(k, None) for k, v in TREE_ROOTS.items()}
    out.update(trees)
    return out


_PLAY_STATES = {1: "paused", 2: "playing", 3: "following"}
_PANEL_STATES = {1: "hidden", 2: "collapsed", 3: "expanded"}


def read_blueprint(path: str | os.PathLike) -> dict[str, Any]:
    """The default blueprint stored in a recording, as plain data (for checks and tests).

    Returns
    -------
    dict with ``"time_panel"`` (``timeline``, ``play_state`` "paused" / "playing" /
    "following", ``state`` "hidden" / "collapsed" / "expanded"; absent keys are unset) and
    ``"views"``: one dict per view with ``class`` ("TimeSeries", "2D", "TextDocument", ...),
    ``name``, ``origin``, ``contents`` (query expressions), ``time_axis`` ((start, end)
    boundary kinds, e.g. ("Infinite", "Infinite"), or None when unset) and ``visual_bounds``
    (True when set).
    """
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    stores = reader.blueprints()
    if not stores:
        raise ValueError(f"{path}: no blueprint in the recording")
    views: dict[str, dict[str, Any]] = {}
    panel: dict[str, Any] = {}

    def last(batch, name):
        v = batch.column(name).to_pylist()[-1]
        return v[-1] if isinstance(v, list) and len(v) == 1 else v

    for ch in reader.stream(store=stores[0]).to_chunks():
        b = ch.to_record_batch()
        names = b.schema.names
        ent = ch.entity_path.lstrip("/")
        if ent == "time_panel":
            if "TimePanelBlueprint:timeline" in names:
                panel["timeline"] = last(b, "TimePanelBlueprint:timeline")
            if "TimePanelBlueprint:play_state" in names:
                panel["play_state"] = _PLAY_STATES.get(last(b, "TimePanelBlueprint:play_state"))
            if "TimePanelBlueprint:state" in names:
                panel["state"] = _PANEL_STATES.get(last(b, "TimePanelBlueprint:state"))
            continue
        parts = ent.split("/")
        if parts[0] != "view" or len(parts) < 2:
            continue
        v = views.setdefault(parts[1], {"class": None, "name": None, "origin": None,
                                        "contents": None, "time_axis": None,
                                        "visual_bounds": False})
        if len(parts) == 2:
            v["class"] = last(b, "ViewBlueprint:class_identifier")
            if "ViewBlueprint:display_name" in names:
                v["name"] = last(b, "ViewBlueprint:display_name")
            v["origin"] = last(b, "ViewBlueprint:space_origin")
        elif parts[2] == "ViewContents":
            v["contents"] = b.column("ViewContents:query").to_pylist()[-1]
        elif parts[2] == "TimeAxis" and "TimeAxis:view_range" in names:
            rng = b.column("TimeAxis:view_range").flatten()
            kinds = []
            for field in ("start", "end"):
                union = rng.field(field)
                kinds.append(union.type.field(union.type_codes[-1].as_py()).name)
            v["time_axis"] = tuple(kinds)
        elif parts[2] == "VisualBounds2D":
            v["visual_bounds"] = True
    return {"time_panel": panel, "views": list(views.values())}


def update_docs(doc: str | os.PathLike) -> bool:
    """Rewrite the entity table between the markers in ``doc``; True if it changed."""
    doc = Path(doc)
    text = doc.read_text(encoding="utf-8")
    start, end = "<!-- entity-table:start -->", "<!-- entity-table:end -->"
    i, j = text.index(start) + len(start), text.index(end)
    new = text[:i] + "\n" + entity_table_markdown() + "\n" + text[j:]
    if new != text:
        doc.write_text(new, encoding="utf-8")
    return new != text


if __name__ == "__main__":  # python -m bench.record docs/recordings.md
    import sys

    for arg in sys.argv[1:] or ["docs/recordings.md"]:
        print(f"{arg}: {'updated' if update_docs(arg) else 'up to date'}")
