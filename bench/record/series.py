"""Generic recordings of named series (the discrepancy workflow's before / after residuals)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from bench.record.blueprint import full_time_axis, time_panel
from bench.record.stream import COLORS, SAMPLE_TIMELINE, log_series, log_tree, open_recording


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
