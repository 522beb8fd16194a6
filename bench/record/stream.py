"""Rerun primitives: the recording stream, series, JSON trees, fixed colours and sizes.

Every recording is written with its own :class:`rerun.RecordingStream` (never the global one),
so one process can write several; the recording is kept in memory and written by
:func:`calib.files.atomic.write_bytes` when complete (temporary name beside the target, fsync,
rename; an existing file is replaced only with ``force``). Large arrays go
through ``rerun.send_columns`` (one call per entity, not one per sample).
"""

from __future__ import annotations

import json
import os
import uuid
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from calib.files.atomic import write_bytes
from calib.files.course import to_jsonable

if TYPE_CHECKING:
    import rerun as rr

APP_ID = "tiltbench"

THETA_TIMELINE = "theta_urad"
SAMPLE_TIMELINE = "sample"
TIME_TIMELINE = "time"

COLORS = {
    "measured": (90, 140, 220), "fit": (230, 50, 40), "ideal": (170, 170, 170),
    "band": (240, 160, 30), "true": (40, 190, 80), "raw": (150, 150, 150),
    "corrected": (60, 120, 255), "candidate": (210, 60, 190), "ellipse": (230, 50, 40),
    "growth": (240, 160, 30), "mean": (250, 250, 250), "axes": (120, 120, 120),
    "grid": (60, 60, 60), "sample": (90, 140, 220, 160), "raw_light": (150, 150, 150, 120),
    "before": (90, 140, 220), "after": (110, 200, 140),
    "std_x": (80, 200, 220), "std_y": (230, 200, 60),
}
"""Fixed colours, so a series has the same colour in every view and every recording.
Raw samples are translucent (``sample``, ``raw_light``: RGBA) and small, so the binned means
and model lines drawn over them stay visible."""

POINT_SIZE = 0.5
"""Marker size (UI points) of raw samples: 20001 points must not hide the lines on top."""
LINE_WIDTH = 2.5
"""Width (UI points) of model lines, bands and binned means drawn over the samples."""


@contextmanager
def open_recording(path: str | os.PathLike, force: bool = False, blueprint: Any = None,
                   name: str | None = None) -> Iterator[rr.RecordingStream]:
    """A recording-scoped stream written atomically to ``path``.

    Yields a :class:`rerun.RecordingStream` whose sink is memory; on normal exit its bytes
    are written by :func:`calib.files.atomic.write_bytes` (temporary file beside ``path``, fsync,
    rename). No rerun writer thread touches the disk, so a full disk is an ``OSError``
    naming ``path`` at once (rerun's file sink could hang or fail in its flush), and an
    error leaves no file behind. Refuses to replace an existing file unless ``force``
    (checked before anything is logged).

    Parameters
    ----------
    path : target ``.rrd`` file.
    force : replace an existing file.
    blueprint : optional ``rerun.blueprint.Blueprint`` stored as the default layout.
    name : recording name shown by the viewer (default: the file stem).
    """
    import rerun as rr

    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path}: is a directory; expected an output file name")
    if path.exists() and not force:
        raise FileExistsError(f"{path}: exists; pass --force to overwrite")
    rec = rr.RecordingStream(APP_ID, recording_id=uuid.uuid4())
    try:
        memory = rec.memory_recording()
        if blueprint is not None:  # what save(path, default_blueprint=...) stores
            rec.send_blueprint(blueprint, make_active=False, make_default=True)
        rec.send_recording_name(name or path.stem)
        yield rec
        data = memory.drain_as_bytes()
    finally:
        rec.disconnect()
    write_bytes(path, data, force=True)


def json_normal(obj: Any) -> Any:
    """The object exactly as ``json.loads(calib.files.course.dumps(obj))`` gives it back."""
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

    obj = json_normal(obj)
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
