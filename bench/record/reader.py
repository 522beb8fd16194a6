"""Reading recordings back with rerun's own reader: JSON trees, entities, the blueprint.

Numbers in the JSON trees come back bit exact (float64 scalars; integers from their decimal
text); :func:`read_recording` returns the truth, the estimates and the trajectory/decision
object, :func:`read_blueprint` the stored default layout as plain data.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from bench.record.schema import TREE_ROOTS


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
