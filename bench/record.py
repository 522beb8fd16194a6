"""Rerun recordings of calibrations and vehicle runs, with the truth recoverable from the file.

Every recording is written with its own :class:`rerun.RecordingStream` (never the global one),
so one process can write several; the file is written to a temporary name beside the target
and renamed when complete (an existing file is replaced only with ``force``). Large arrays go
through ``rerun.send_columns`` (one call per entity, not one per sample). A default blueprint
is stored in the file so it opens in a useful layout.

What is logged (the full entity table is :data:`ENTITY_DOCS`, rendered in
``docs/recordings.md``)
------------------------------------------------------------------------------------------
* ``calibration/{x,y}/...`` — measured points and the fitted line against θ (timelines
  ``sample`` and ``theta_urad`` = round(θ·10⁶), an integer so the time-series views plot
  against θ), residuals with a ±σ band, and the measured points against ``A_r`` in a 2-D view
  with the fitted and the ideal line.
* ``vehicle/...`` — acceleration time series (timeline ``time``, s), true / raw / corrected
  paths, candidate points, the confidence ellipse of the arrival point and the ellipse growing
  along the corrected trajectory.
* ``truth/...``, ``estimate/...``, ``trajectory/...`` — JSON trees (``truth.json``, the
  ``calibrate --json`` object, the trajectory/decision object) flattened to one entity per
  node: numbers as ``Scalars`` (float64, bit exact), strings as ``TextDocument``; each node
  also carries ``json_type`` and ``json_path`` components so :func:`read_recording`
  rebuilds the exact nested structure.

2-D views: rerun draws 2-D space with +y down (image convention); every 2-D plot is logged
under a frame entity carrying ``Transform3D(scale=(1, -1, 1))`` so +y points up as on paper.
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
    "measured": (90, 140, 220), "fit": (220, 50, 40), "ideal": (150, 150, 150),
    "band": (240, 160, 30), "true": (40, 170, 70), "raw": (140, 140, 140),
    "corrected": (30, 90, 220), "candidate": (200, 40, 160), "ellipse": (220, 50, 40),
    "growth": (240, 160, 30),
}


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
    EntityDoc("calibration/{axis}/vs_ar", "Transform3D", "static",
              "2-D frame with +y up (scale (1, −1, 1))", _CAL),
    EntityDoc("calibration/{axis}/vs_ar/measured", "Points2D", "static",
              "(A_r, A_m) per sample, m/s² (float32)", _CAL),
    EntityDoc("calibration/{axis}/vs_ar/fit", "LineStrips2D", "static",
              "fitted line over the A_r range, m/s²", ("calibration",)),
    EntityDoc("calibration/{axis}/vs_ar/true", "LineStrips2D", "static",
              "true line (1 + scale)·A_r + bias, m/s²", _CAL, optional=True),
    EntityDoc("calibration/{axis}/vs_ar/ideal", "LineStrips2D", "static",
              "ideal sensor A_m = A_r, m/s²", _CAL),
    EntityDoc("vehicle/acceleration/{k}/{axis}", "Scalars + SeriesLines", "time",
              "acceleration: k = measured (A_m), corrected (Â_r) or true, m/s²", _VEH),
    EntityDoc("vehicle/position_std/{axis}", "Scalars + SeriesLines", "time",
              "standard deviation of the corrected position (calibration + noise), m",
              ("vehicle",)),
    EntityDoc("vehicle/plane", "Transform3D", "static", "2-D frame with +y up", _VEH),
    EntityDoc("vehicle/plane/path/{k}", "LineStrips2D", "static",
              "trajectory, k = raw (uncorrected), corrected or true, m", _VEH),
    EntityDoc("vehicle/plane/position/{k}", "Points2D", "time",
              "position at the current time, k = raw, corrected or true, m", _VEH),
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
              "the growing ellipse at 10 evenly spaced times, m", ("vehicle",)),
    EntityDoc("summary/parameters", "TextDocument (Markdown)", "static",
              "estimates with std and interval next to the true values and z-scores",
              ("calibration", "truth-run", "vehicle")),
    EntityDoc("summary/decision", "TextDocument (Markdown)", "static",
              "arrival decision, distances to the candidates", ("vehicle",)),
    EntityDoc("gap/{axis}/residual_{k}", "Scalars + SeriesPoints", "sample, theta_urad",
              "discrepancy workflow: residual before / after adding the named effects, m/s² "
              "(bench/gap.py)", ("gap",)),
    EntityDoc("gap/{axis}/band_{k}/{k}", "Scalars + SeriesLines", "sample, theta_urad",
              "±σ band of the before / after model (first and last sample), m/s²", ("gap",)),
    EntityDoc("gap/effects", "TextDocument (Markdown)", "static",
              "the named effects with their evidence", ("gap",)),
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
               style: str = "line", color=None, name: str | None = None) -> None:
    """Log a series with one ``send_columns`` call.

    Parameters
    ----------
    rec : the recording.  entity : entity path.  values : (n,) numbers.
    index : timeline name → (n,) values; names ending in ``time`` or given as float
        arrays are duration timelines in seconds, integer arrays sequence timelines.
    style : "line" (SeriesLines) or "points" (SeriesPoints), logged once as static style.
    color : RGB; name : legend label (default: last path part).
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
        rec.log(entity, rr.SeriesPoints(colors=color, names=label, marker_sizes=1.5),
                static=True)
    else:
        rec.log(entity, rr.SeriesLines(colors=color, names=label), static=True)
    rec.send_columns(entity, indexes=cols, columns=rr.Scalars.columns(scalars=values))


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
    views = [rrb.TimeSeriesView(origin=g, name=g) for g in groups]
    bp = rrb.Blueprint(rrb.Vertical(*views) if views else rrb.Vertical(),
                       rrb.TimePanel(timeline=timeline), collapse_panels=True)
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

def _axis_views(axis: str, with_vs_ar: bool = True) -> Any:
    import rerun.blueprint as rrb

    o = f"calibration/{axis}"
    parts = [
        rrb.TimeSeriesView(origin=o, contents=[f"+ {o}/measured", f"+ {o}/fit", f"+ {o}/true"],
                           name=f"{axis}: A_m and fit vs θ (µrad), m/s²"),
        rrb.TimeSeriesView(origin=o, contents=[f"+ {o}/residual", f"+ {o}/residual_band/**"],
                           name=f"{axis}: residual ±σ vs θ, m/s²"),
    ]
    if with_vs_ar:
        parts.append(rrb.Spatial2DView(origin=o, contents=[f"+ {o}/vs_ar/**"],
                                       name=f"{axis}: A_m vs A_r, m/s²"))
    return rrb.Vertical(*parts)


def _calibration_blueprint() -> Any:
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Vertical(rrb.Horizontal(_axis_views("x"), _axis_views("y")),
                     rrb.TextDocumentView(origin="summary", name="estimates vs truth"),
                     row_shares=[5, 2]),
        rrb.TimePanel(timeline=THETA_TIMELINE), collapse_panels=True)


def _line(x0: float, x1: float, b: float, s: float) -> np.ndarray:
    xs = np.array([x0, x1])
    return np.column_stack([xs, (1.0 + s) * xs + b])


def _log_axis_data(rec: rr.RecordingStream, axis: str, theta: np.ndarray, a_m: np.ndarray,
                   a_r: np.ndarray, fit_line: tuple[float, float] | None,
                   true_line: tuple[float, float] | None, a_true: np.ndarray | None,
                   sigma: float) -> None:
    """Per-axis calibration entities (see :data:`ENTITY_DOCS`)."""
    import rerun as rr

    o = f"calibration/{axis}"
    idx = {SAMPLE_TIMELINE: np.arange(theta.size, dtype=np.int64),
           THETA_TIMELINE: np.round(theta * 1e6).astype(np.int64)}
    log_series(rec, f"{o}/measured", a_m, idx, "points", COLORS["measured"], f"A_m{axis}")
    # Smooth curves are drawings: at most CURVE_POINTS samples (every k-th, ends kept).
    k = max(1, int(np.ceil(theta.size / CURVE_POINTS)))
    sub = np.unique(np.r_[np.arange(0, theta.size, k), theta.size - 1])
    sub_idx = {tl: v[sub] for tl, v in idx.items()}
    model = None
    if fit_line is not None:
        b, s = fit_line
        model = (1.0 + s) * a_r + b
        log_series(rec, f"{o}/fit", model[sub], sub_idx, "line", COLORS["fit"], "fit")
    if true_line is not None:
        b, s = true_line
        base = a_r if a_true is None else a_true
        true_model = (1.0 + s) * base + b
        log_series(rec, f"{o}/true", true_model[sub], sub_idx, "line", COLORS["true"], "true")
        if model is None:
            model = true_model
    resid = a_m - (model if model is not None else a_r)
    log_series(rec, f"{o}/residual", resid, idx, "points", COLORS["measured"], "residual")
    ends = np.array([int(np.argmin(theta)), int(np.argmax(theta))])
    end_idx = {k: v[ends] for k, v in idx.items()}
    for part, sign in (("plus", 1.0), ("minus", -1.0)):
        log_series(rec, f"{o}/residual_band/{part}", np.full(2, sign * sigma), end_idx, "line",
                   COLORS["band"], f"{'+' if sign > 0 else '−'}σ = {sign * sigma:.3g}")
    rec.log(f"{o}/vs_ar", rr.Transform3D(scale=FLIP_Y), static=True)
    rec.log(f"{o}/vs_ar/measured", rr.Points2D(np.column_stack([a_r, a_m]), radii=0.02,
                                                colors=COLORS["measured"]), static=True)
    lo, hi = float(np.min(a_r)), float(np.max(a_r))
    if fit_line is not None:
        rec.log(f"{o}/vs_ar/fit", rr.LineStrips2D([_line(lo, hi, *fit_line)], radii=0.03,
                                                  colors=COLORS["fit"], labels="fit"),
                static=True)
    if true_line is not None:
        rec.log(f"{o}/vs_ar/true", rr.LineStrips2D([_line(lo, hi, *true_line)], radii=0.02,
                                                   colors=COLORS["true"], labels="true"),
                static=True)
    rec.log(f"{o}/vs_ar/ideal", rr.LineStrips2D([_line(lo, hi, 0.0, 0.0)], radii=0.01,
                                                colors=COLORS["ideal"], labels="A_m = A_r"),
            static=True)


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
    with open_recording(path, force, _calibration_blueprint(), "calibration") as rec:
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
    with open_recording(path, force, _calibration_blueprint(), "calibration truth") as rec:
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
    blueprint = _vehicle_blueprint(calibration is not None)
    with open_recording(path, force, blueprint, "truth") as rec:
        tl = {TIME_TIMELINE: run.t - run.t[0]}
        for name, acc in (("measured", run.aerr), ("true", run.truth.acc)):
            for k, a in enumerate(AXES):
                log_series(rec, f"vehicle/acceleration/{name}/{a}", acc[:, k], tl, "line",
                           COLORS["raw" if name == "measured" else name], f"{name} {a}")
        rec.log("vehicle/plane", rr.Transform3D(scale=FLIP_Y), static=True)
        raw, _ = integrate_twice(run.t, run.aerr, run.config.p0, run.config.v0)
        for name, p in (("raw", raw), ("true", run.truth.pos)):
            p = np.asarray(p, dtype=float)
            rec.log(f"vehicle/plane/path/{name}", rr.LineStrips2D(
                [p], radii=0.6, colors=COLORS[name], labels=name), static=True)
            rec.send_columns(f"vehicle/plane/position/{name}",
                             indexes=[rr.TimeColumn(TIME_TIMELINE, duration=tl[TIME_TIMELINE])],
                             columns=rr.Points2D.columns(positions=p,
                                                         radii=np.full(len(p), 3.0)))
        if candidates is not None:
            names = list(candidates)
            rec.log("vehicle/plane/candidates", rr.Points2D(
                np.array([candidates[k] for k in names]), labels=names, radii=4.0,
                colors=COLORS["candidate"], show_labels=True), static=True)
        if calibration is not None:
            a_r = reference_accel(calibration.tita, calibration.config.g)
            for k, a in enumerate(AXES):
                err = calibration.config.sensor.axis(a)
                _log_axis_data(rec, a, calibration.tita, calibration.datos[:, k], a_r[:, k],
                               None, (err.bias, err.scale), calibration.a_true[:, k],
                               float(np.sqrt(err.noise_var)))
        log_tree(rec, "truth", manifest)
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


def _vehicle_blueprint(with_calibration: bool) -> Any:
    import rerun.blueprint as rrb

    vehicle = rrb.Horizontal(
        rrb.Spatial2DView(origin="vehicle", contents=["+ vehicle/plane/**"],
                          name="trajectories, candidates and ellipses (m)"),
        rrb.Vertical(
            *(rrb.TimeSeriesView(origin="vehicle/acceleration",
                                 contents=[f"+ vehicle/acceleration/{k}/{a}"
                                           for k in ("measured", "corrected", "true")],
                                 name=f"acceleration {a} (m/s²)") for a in AXES),
            rrb.TimeSeriesView(origin="vehicle/position_std", name="position std (m)"),
            rrb.TextDocumentView(origin="summary", name="decision and estimates")),
        column_shares=[3, 2], name="vehicle")
    tabs = [vehicle]
    if with_calibration:
        tabs.append(rrb.Horizontal(_axis_views("x"), _axis_views("y"), name="calibration"))
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(timeline=TIME_TIMELINE),
                         collapse_panels=True)


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
                       COLORS["raw" if name == "measured" else name], f"{name} {a}")
    rec.log("vehicle/plane", rr.Transform3D(scale=FLIP_Y), static=True)
    paths = {"raw": traj.pos_raw, "corrected": traj.pos_corrected, "true": true_path}
    for name, p in paths.items():
        if p is None:
            continue
        p = np.asarray(p, dtype=float)
        rec.log(f"vehicle/plane/path/{name}", rr.LineStrips2D(
            [p], radii=0.6, colors=COLORS[name], labels=name), static=True)
        rec.send_columns(f"vehicle/plane/position/{name}",
                         indexes=[rr.TimeColumn(TIME_TIMELINE, duration=tl[TIME_TIMELINE])],
                         columns=rr.Points2D.columns(positions=p, radii=np.full(len(p), 3.0)))
    names = list(region.candidates)
    rec.log("vehicle/plane/candidates", rr.Points2D(
        np.array([region.candidates[k] for k in names]), labels=names, radii=4.0,
        colors=COLORS["candidate"], show_labels=True), static=True)
    rec.log("vehicle/plane/arrival/estimate", rr.Points2D(
        region.estimate[None, :], radii=3.0, colors=COLORS["ellipse"],
        labels=f"arrival ({region.decision or 'undecided'})"), static=True)
    rec.log("vehicle/plane/arrival/ellipse", rr.LineStrips2D(
        [region.ellipse.boundary(256)], radii=0.8, colors=COLORS["ellipse"],
        labels=f"{100 * region.level:g}%"), static=True)
    m = t.shape[0]
    idx = np.unique(np.linspace(0, m - 1, min(n_ellipses, m)).round().astype(int))
    covs = position_cov_along(traj, cal, region.noise_var, idx)
    centers = traj.pos_corrected[idx]
    strips = [_ellipse_points(c, s, region.level) for c, s in zip(centers, covs, strict=True)]
    t_idx = tl[TIME_TIMELINE][idx]
    rec.send_columns("vehicle/plane/uncertainty/ellipse",
                     indexes=[rr.TimeColumn(TIME_TIMELINE, duration=t_idx)],
                     columns=rr.LineStrips2D.columns(strips=strips))
    snap = np.unique(np.linspace(0, len(idx) - 1, 11).round().astype(int))[1:]
    rec.log("vehicle/plane/uncertainty/snapshots", rr.LineStrips2D(
        [strips[i] for i in snap], radii=0.4, colors=COLORS["growth"],
        labels=[f"t = {t_idx[i]:.0f} s" for i in snap]), static=True)
    std = np.sqrt(np.clip(np.diagonal(covs, axis1=1, axis2=2), 0.0, None))
    for k, a in enumerate(AXES):
        log_series(rec, f"vehicle/position_std/{a}", std[:, k], {TIME_TIMELINE: t_idx},
                   "line", None, f"std {a}")


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

    with open_recording(path, force, _vehicle_blueprint(False), "vehicle") as rec:
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

    with open_recording(path, force, _vehicle_blueprint(True), "course") as rec:
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
