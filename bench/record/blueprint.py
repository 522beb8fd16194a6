"""Default blueprints stored in the recordings: every view shows its content on open.

Time-series views span the whole timeline, the time panel is collapsed and not playing, one
text view per document, 2-D views have bounds computed from the data.
"""

from __future__ import annotations

from typing import Any

from bench.record.plot import plane_box, plot_bounds
from bench.record.stream import THETA_TIMELINE, TIME_TIMELINE
from calib.conventions import AXES


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


def axis_views(axis: str, fit: bool = True, true: bool = False) -> Any:
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
                          visual_bounds=plot_bounds()),
        rrb.Spatial2DView(origin=o, contents=[f"+ {o}/residual_plot/**"],
                          name=f"{axis}: residual, ±σ (orange), binned mean (white) vs θ "
                               "(rad); m/s²", visual_bounds=plot_bounds()),
        rrb.Spatial2DView(origin=o, contents=[f"+ {o}/vs_ar/**"],
                          name=f"{axis}: A_m − A_r vs A_r: {model}, ideal 0 (grey), binned "
                               "mean (white); m/s²", visual_bounds=plot_bounds()))


def calibration_blueprint(fit: bool = True, true: bool = False) -> Any:
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Vertical(rrb.Horizontal(axis_views("x", fit, true), axis_views("y", fit, true)),
                     rrb.TextDocumentView(origin="summary/parameters",
                                          name="estimates vs truth" if fit else "truth"),
                     row_shares=[5, 2]),
        time_panel(THETA_TIMELINE), collapse_panels=True)


def plane_bounds(*arrays, margin: float = 0.06) -> Any:
    """View bounds of the plane's grid (:func:`~bench.record.plot.plane_box` of all given
    (n, 2) positions, m) plus room for the grid's values left of and under it.

    The plane is drawn under ``vehicle/plane`` (scale (1, −1, 1)), so the view's y is −y.
    """
    import rerun.blueprint as rrb

    x0, x1, y0, y1 = plane_box(*arrays, margin=margin)
    d = max(x1 - x0, y1 - y0)
    return rrb.VisualBounds2D(x_range=[x0 - 0.07 * d, x1 + 0.01 * d],
                              y_range=[-y1 - 0.05 * d, -y0 + 0.09 * d])


def vehicle_blueprint(bounds: Any, *, estimated: bool, acc: tuple[str, ...],
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
    # the text view gets the largest share: its tables must fit without scrolling
    shares = [2.0] * (len(side) - 1) + [4.0] if docs else None
    vehicle = rrb.Horizontal(plane, rrb.Vertical(*side, row_shares=shares), column_shares=[3, 2],
                             name="vehicle")
    tabs = [vehicle]
    if calibration is not None:
        fit, true = calibration
        tabs.append(rrb.Horizontal(axis_views("x", fit, true), axis_views("y", fit, true),
                                   name="calibration"))
    return rrb.Blueprint(rrb.Tabs(*tabs) if len(tabs) > 1 else vehicle,
                         time_panel(TIME_TIMELINE, "following"), collapse_panels=True)


def fusion_blueprint(bounds: Any, *, level: float, truth: bool, every_s: float | None,
                     heading: bool = False, inconsistent: bool = False,
                     rejected: int = 0) -> Any:
    """The ``fuse --rrd`` layout: the plane (dead reckoning, fixes, fused path and ellipses,
    truth) beside the innovations of each axis with their ±σ bounds, the fused position std,
    the NIS of each fix with the gate, the windowed NIS with its band and the decision. The
    view names are the legend. ``heading`` (a turning run): a heading view is added.
    ``inconsistent``: the plane's name says so and names no fused region. ``rejected``:
    fixes the gate rejected (named in red)."""
    import rerun.blueprint as rrb

    pct = f"{100 * level:g}%"
    every = f" every {every_s:.0f} s" if every_s else ""
    parts = ["dead reckoning blue", "fixes light grey"]
    if rejected:
        parts.append(f"{rejected} rejected by the gate red")
    if inconsistent:
        parts += ["fused purple (no region)", f"{pct} arrival: dead reckoning red"]
    else:
        parts += [f"fused purple ({pct} ellipses{every})",
                  f"{pct} arrival: fused purple, dead reckoning red"]
    parts.append("candidates magenta")
    if truth:
        parts.insert(0, "true green")
    head = "INCONSISTENT inputs, no fused region — " if inconsistent else ""
    plane = rrb.Spatial2DView(origin="vehicle", contents=["+ vehicle/plane/**"],
                              name=head + "plane (m) — " + "; ".join(parts),
                              visual_bounds=bounds)
    side = [rrb.TimeSeriesView(origin="fusion", contents=[f"+ fusion/innovation/{a}",
                                                          f"+ fusion/innovation_band/{a}/**"],
                               name=f"innovation {a} (m): ν = fix − prediction, ±σ = "
                                    "±sqrt(S) orange", axis_x=full_time_axis())
            for a in AXES]
    side.append(rrb.TimeSeriesView(origin="fusion/position_std", axis_x=full_time_axis(),
                                   name="std of the fused position (m)"))
    side.append(rrb.TimeSeriesView(origin="fusion/nis", axis_x=full_time_axis(),
                                   name="NIS of each fix: used grey, rejected red, gate orange"))
    side.append(rrb.TimeSeriesView(
        origin="fusion/window_nis", axis_x=full_time_axis(),
        name=("INCONSISTENT: " if inconsistent else "")
             + "windowed NIS Σ min(NIS, c) purple, band orange, out of band red"))
    if heading:
        side.append(rrb.TimeSeriesView(
            origin="fusion/heading", axis_x=full_time_axis(),
            name="heading ψ (rad): fused purple, dead reckoning blue"
                 + (", true green" if truth else "")))
        if truth:
            side.append(rrb.TimeSeriesView(
                origin="fusion", contents=["+ fusion/heading_error/**",
                                           "+ fusion/heading_error_band/**"],
                axis_x=full_time_axis(),
                name="heading error ψ − ψ true (rad) at the truth's samples: fused purple "
                     "±σ orange, dead reckoning blue"))
        else:
            side.append(rrb.TimeSeriesView(origin="fusion/heading_std", axis_x=full_time_axis(),
                                           name="std of the fused heading (rad)"))
    side.append(rrb.TextDocumentView(origin="summary/decision",
                                     name="decision — INCONSISTENT" if inconsistent
                                     else "decision"))
    shares = [2] * (len(side) - 1) + [3]
    layout = rrb.Horizontal(plane, rrb.Vertical(*side, row_shares=shares),
                            column_shares=[3, 2], name="fusion")
    return rrb.Blueprint(layout, time_panel(TIME_TIMELINE, "following"), collapse_panels=True)
