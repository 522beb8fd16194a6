"""The rerun recording of the discrepancy workflow: residuals before / after, ±σ bands,
binned means, the verdict and effects text and the ``gap --json`` tree (``verdict``,
``unexplained``, ``adequacy``, ``shrink`` included), with its blueprint.

``rerun`` is imported inside the functions that log, so importing :mod:`bench.gap` does not
load it.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from bench.gap.report import GapReport
from bench.gap.writers import gap_markdown
from bench.record import (
    COLORS,
    THETA_TIMELINE,
    StaticPlot,
    log_series,
    log_tree,
    open_recording,
    plot_bounds,
    time_panel,
)
from calib.conventions import AXES
from calib.gap.drive_state import drive_state, stretches
from calib.stats.binning import binned_mean

PathLike = str | os.PathLike


def recording_blueprint(report: GapReport | None = None) -> Any:
    """Layout of the gap recording: per axis the residual before and after adding the named
    effects, each a static 2-D plot against θ in rad (``gap/{axis}/plot_{before,after}``)
    with its ±σ lines and binned mean, one per row, and the text view (verdict first, then
    the effects). An axis with unexplained structure says so in the name of its "after"
    view. ``gap_report/**`` (the JSON tree) is left out of every view."""
    import rerun.blueprint as rrb

    flagged = {} if report is None or report.verdict != "unexplained" else {
        ax: [str(u.get("description", u.get("signature", "?"))) for u in report.unexplained
             if u.get("axis") in (ax, "both")] for ax in AXES}

    timed = report is None or report.replay.t is not None
    along = "t (s)" if timed else "sample (time order)"

    def view(ax: str, which: str) -> Any:
        name = f"{ax}: residual {which} (dots), ±σ (orange), binned mean (white) vs θ (rad); m/s²"
        if which == "after" and flagged.get(ax):
            name = f"{ax}: residual after vs θ (rad) — UNEXPLAINED: {'; '.join(flagged[ax])}"
        if which == "time":
            name = (f"{ax}: residual before (dots), binned means before (white) and after "
                    f"(red), ±σ after (orange) vs {along}; grey bar: the table moves; m/s²")
        return rrb.Spatial2DView(origin=f"gap/{ax}", name=name,
                                 contents=[f"+ gap/{ax}/plot_{which}/**"],
                                 visual_bounds=plot_bounds())

    # one 3:1 plot per row (x before, x after, x in time, then y: before and after of an axis
    # share their y range), the text view wide enough for its tables
    plots = rrb.Vertical(*(view(ax, which) for ax in AXES
                           for which in ("before", "after", "time")))
    verdict = "" if report is None else f" — verdict: {report.verdict}"
    return rrb.Blueprint(
        rrb.Horizontal(plots, rrb.TextDocumentView(origin="gap/effects",
                                                   name=f"verdict and effects{verdict}"),
                       column_shares=[3, 2]),
        time_panel(THETA_TIMELINE), collapse_panels=True)


def recording_markdown(report: GapReport) -> str:
    """``gap.md`` without its image line (a path relative to the report, broken in a viewer)."""
    lines = [ln for ln in gap_markdown(report).split("\n") if not ln.startswith("![")]
    return re.sub(r"\n{3,}", "\n\n", "\n".join(lines))


def _shared_box(theta: np.ndarray, residuals, variances) -> StaticPlot:
    """One plot box for the before and after residuals of an axis (same y range), covering
    the residuals and 1.2 σ of both models, m/s²; θ in rad on x."""
    lim = max([float(np.max(np.abs(r))) for r in residuals if r.size]
              + [1.2 * float(np.sqrt(v)) for v in variances])
    return StaticPlot.around(theta, [-lim, lim], symmetric_y=True)


def _log_plot(rec: Any, entity: str, plot: StaticPlot, theta: np.ndarray, res: np.ndarray,
              sigma: float, th_mean: np.ndarray, mean: np.ndarray, xlabel: str = "θ (rad)"
              ) -> None:
    """Static 2-D plot at ``entity`` (θ in rad, or ``xlabel``'s abscissa, against the residual,
    m/s²): small translucent samples under the ±σ lines, the binned mean on top, frame and
    tick values."""
    import rerun as rr

    plot.log_frame(rec, entity, zero_line=True, xlabel=xlabel, ylabel="residual (m/s²)")
    rec.log(f"{entity}/residual", rr.Points2D(
        np.column_stack([theta, res]), radii=rr.Radius.ui_points(0.8), colors=COLORS["sample"],
        draw_order=10.0), static=True)
    t0, t1 = float(np.min(theta)), float(np.max(theta))
    rec.log(f"{entity}/band", rr.LineStrips2D(
        [np.array([[t0, sigma], [t1, sigma]]), np.array([[t0, -sigma], [t1, -sigma]])],
        radii=rr.Radius.ui_points(1.25), colors=COLORS["band"], draw_order=20.0), static=True)
    rec.log(f"{entity}/mean", rr.LineStrips2D(
        [np.column_stack([th_mean, mean])], radii=rr.Radius.ui_points(1.25),
        colors=COLORS["mean"], draw_order=30.0), static=True)


def write_recording(report: GapReport, path: PathLike, force: bool = False) -> Path:
    """Rerun recording: ``gap/{x,y}/residual_before``, ``…/residual_after`` (timelines
    ``sample`` and ``theta_urad``), ``gap/{x,y}/band_{before,after}/{plus,minus}`` (±σ),
    ``gap/{x,y}/mean_{before,after}`` (binned means), ``gap/effects`` (Markdown: the verdict
    with each unexplained signature, then the effects, gap and shrink) and the ``gap --json``
    object as a tree under ``gap_report`` (read back with ``tiltbench record read``), with a
    blueprint that shows the same residuals as static 2-D plots against θ in rad
    (``gap/{x,y}/plot_{before,after}``: translucent samples, ±σ lines, binned mean on top;
    an axis with unexplained structure names it in its "after" view) and in time order
    (``gap/{x,y}/plot_time``, :func:`_log_time_plot`)."""
    import rerun as rr

    theta = report.replay.tita
    n = theta.size
    index = {"sample": np.arange(n, dtype=np.int64),
             "theta_urad": np.round(theta * 1e6).astype(np.int64)}
    # ±σ bands span the θ range (the first and last samples of an up-then-down sweep share θ)
    ends = {tl: v[[int(np.argmin(theta)), int(np.argmax(theta))]] for tl, v in index.items()}
    plot = {ax: _shared_box(theta, (report.residual_before[:, k], report.residual_after[:, k]),
                            (report.noise_var[k], report.after[ax].sigma2))
            for k, ax in enumerate(AXES)}
    moving = drive_state(theta)  # the stretches where the table moves, for the plots in time
    with open_recording(path, force=force, blueprint=recording_blueprint(report),
                        name="tiltbench gap") as rec:
        for k, ax in enumerate(AXES):
            for which, res, s2 in (("before", report.residual_before, report.noise_var[k]),
                                   ("after", report.residual_after,
                                    report.after[ax].sigma2)):
                log_series(rec, f"gap/{ax}/residual_{which}", res[:, k], index,
                           style="points", color=COLORS[which], name=f"residual {which}",
                           size=1.0 if n < 10_000 else 0.5)
                for part, sign in (("plus", 1.0), ("minus", -1.0)):
                    log_series(rec, f"gap/{ax}/band_{which}/{part}",
                               np.full(2, sign * np.sqrt(s2)), ends, color=COLORS["band"],
                               name=f"{sign:+.0f}σ {which}")
                th, mean, at = binned_mean(theta, res[:, k], bins=min(100, max(1, n // 80)))
                log_series(rec, f"gap/{ax}/mean_{which}", mean,
                           {"sample": at, "theta_urad": np.round(th * 1e6).astype(np.int64)},
                           color=COLORS["mean"], name=f"binned mean {which}")
                _log_plot(rec, f"gap/{ax}/plot_{which}", plot[ax], theta, res[:, k],
                          float(np.sqrt(s2)), th, mean)
            _log_time_plot(rec, report, k, moving)
        rec.log("gap/effects", rr.TextDocument(recording_markdown(report),
                                               media_type=rr.MediaType.MARKDOWN), static=True)
        log_tree(rec, "gap_report", report.to_dict())
    return Path(path)


def _log_time_plot(rec: Any, report: GapReport, k: int, moving: np.ndarray | None) -> None:
    """Axis k in time order as a static 2-D plot at ``gap/{axis}/plot_time`` (t in s, or the
    sample index when the run has no times, against m/s²), as the gap figure's row in time:
    the residuals before, the binned means before (``mean``) and after (``mean_after``), the
    ±σ lines of the model after, and a thick grey bar along the bottom under each stretch
    where the table moves (``moving``: :func:`calib.gap.drive_state.drive_state` of the run;
    None when it lacks either state)."""
    import rerun as rr

    ax = AXES[k]
    entity = f"gap/{ax}/plot_time"
    t = report.replay.t
    before, after = report.residual_before[:, k], report.residual_after[:, k]
    n = before.size
    x = np.arange(n, dtype=float) if t is None else np.asarray(t, dtype=float)
    sigma = float(np.sqrt(report.after[ax].sigma2))
    bins = min(100, max(1, n // 80))
    xb, mean_before, _ = binned_mean(x, before, bins=bins)
    xa, mean_after, _ = binned_mean(x, after, bins=bins)
    plot = _shared_box(x, (before, after), (report.noise_var[k], report.after[ax].sigma2))
    _log_plot(rec, entity, plot, x, before, sigma, xb, mean_before,
              xlabel="t (s)" if t is not None else "sample")
    rec.log(f"{entity}/mean_after", rr.LineStrips2D(
        [np.column_stack([xa, mean_after])], radii=rr.Radius.ui_points(1.25),
        colors=COLORS["fit"], draw_order=31.0), static=True)
    if moving is not None:  # a thick grey bar along the bottom (2-D boxes are outlines only)
        level = plot.y0 + 0.02 * (plot.y1 - plot.y0)
        rec.log(f"{entity}/moving", rr.LineStrips2D(
            [np.array([[x[a], level], [x[b - 1], level]]) for a, b in stretches(moving)],
            radii=rr.Radius.ui_points(3.0), colors=COLORS["raw"], draw_order=25.0),
            static=True)

