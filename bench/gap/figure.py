"""The gap figure: residuals against θ before and after adding the named effects, the residuals
in time order (binned means before and after) with the table's moving stretches shaded, the
verdict, the unexplained signatures and why each axis' gap shrank or did not."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.gap.report import GapReport, shrink_word
from calib.conventions import AXES, EFFECTS
from calib.gap.drive_state import drive_state
from calib.stats.binning import binned_mean

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


VERDICT_COLORS = {"explained": (0.85, 0.95, 0.85), "unexplained": (1.0, 0.87, 0.85),
                  "nothing_detected": (0.92, 0.92, 0.92)}
"""Background of the verdict box (green-ish, red-ish, grey)."""
MEAN_COLOR = (0.85, 0.2, 0.15)
"""Colour of the binned means (after, in the row in time)."""
UNEXPLAINED_EDGE = (0.8, 0.1, 0.1)
"""Frame and text colour of a panel with unexplained structure."""
SIGNATURE_WORDS = {
    "chi2": "noise level (χ²)",
    "h1_cos": "a cos θ pattern",
    "h1_sin": "a sin θ pattern",
    "h2_cos": "a cos 2θ pattern",
    "h2_sin": "a sin 2θ pattern (cross-axis)",
    "other_ref": "the other axis' reference (misalignment)",
    "trend": "a drift in time",
    "whiteness": "correlated samples",
    "lattice": "readings in equal steps (quantization)",
    "flat_top": "flat tops (saturation)",
    "rate_cos": "ω cos θ (a lag)",
    "rate_sin": "ω sin θ (a lag)",
    "rate_sq": "ω² (centripetal, lever arm)",
    "accel": "angular acceleration (lever arm)",
}
"""Signature names of :mod:`calib.stats.diagnostics` in words, as the figure shows them."""
BINS = 72
BOX_LINES = 14
"""Lines of the verdict box under the caption; the rest is counted and left to gap.md."""
PANEL_ITEMS, PANEL_CHARS = 6, 78
"""Unexplained items listed on an "after" panel, and their width in characters."""
"""Bins of the binned mean (equal sample counts)."""
CAPTION = ("Every ± in this figure is 1 std. Dots: residual data − simulation; red line: binned "
           f"mean ({BINS} bins) with its ±σ/√n band (n samples per bin); orange band: ±σ, the "
           "per-sample noise (before: the stated σ; after: the σ of the model with the "
           "effects). χ²/dof ≈ 1 and max |z| small mean noise only; max |z| is the largest "
           "z-score among the patterns tested, named after it only where it is beyond noise. "
           "Bottom row: in time order (what drifts, steps or switches, or comes only while "
           "the table moves, grey), the residuals before and the binned means before "
           "(black) and after (red).")
"""The figure's caption: what the marks and numbers in the panel titles are."""


def signature_words(text: str) -> str:
    """``text`` with every signature name of :data:`SIGNATURE_WORDS` replaced by its words."""
    import re

    pattern = r"\b(" + "|".join(sorted(SIGNATURE_WORDS, key=len, reverse=True)) + r")\b"
    return re.sub(pattern, lambda m: SIGNATURE_WORDS[m.group(1)], text)


def _param_text(name: str, key: str, value: float, std: float | None) -> str:
    """``key = value ± std unit`` in the catalog's unit (``calib.conventions.EFFECTS``)."""
    info = EFFECTS.get(name)
    units = dict(zip(info.keys, info.units, strict=True)) if info else {}
    unit = units.get(key, "")
    unit = "" if unit in ("", "1", "-") else f" {unit}"
    pm = f" ± {std:.2g}" if std is not None and np.isfinite(std) else ""
    return f"{key} = {value:.4g}{pm}{unit}"


def effects_label(report: GapReport) -> str:
    """One line naming the effects added, their estimates ± std and units (verdict box)."""
    effects = report.to_dict().get("effects", [])
    if not effects:
        return "no effect named"
    return "; ".join(
        f"{e['name']} ({e['axis']}{', tentative' if e.get('tentative') else ''}): "
        + ", ".join(_param_text(e["name"], k, float(v), e.get("std", {}).get(k))
                    for k, v in e["params"].items())
        for e in effects)


def verdict_box_text(report: GapReport) -> str:
    """The figure's bottom box: the effects added with their estimates, the verdict (and each
    unexplained signature), per axis whether the gap shrank and why not, then the pairs this
    run cannot tell apart."""
    d = report.to_dict()
    lines = [f"added: {effects_label(report)} (± 1 std)", *report.verdict_lines()]
    lines += [f"{ax}: gap {shrink_word(sh)} — {sh['reason']}" for ax, sh in d["shrink"].items()]
    lines += _untold_line(d)
    wrapped = [w for line in lines for w in _wrap(signature_words(line), 150).split("\n")]
    # the box holds about a dozen lines below the caption: the rest is in gap.md
    return "\n".join(_capped(wrapped, BOX_LINES, "lines (the whole text: gap.md, or --json)"))


def _untold_line(d: dict) -> list[str]:
    """One line naming the pairs this run cannot tell apart (``not_identifiable`` entries of
    two names or more, e.g. a lever arm and a bias while moving), or none: the figure says
    that the named effect has a rival; the reasons and what separates them are in gap.md."""
    pairs = [" / ".join(i["names"]) for i in d.get("not_identifiable", ())
             if len(i["names"]) > 1]
    if not pairs:
        return []
    return [f"not told apart on this run: {'; '.join(pairs)} (why, and what separates "
            "them: gap.md)"]


def _shorten(text: str, width: int) -> str:
    """``text`` cut to ``width`` characters with an ellipsis (the whole text is in gap.md)."""
    return text if len(text) <= width else text[:width - 1].rstrip() + "…"


def _capped(lines: list[str], most: int, more: str) -> list[str]:
    """At most ``most`` lines; the rest counted in one last line naming where they are."""
    if len(lines) <= most:
        return lines
    return lines[:most - 1] + [f"… and {len(lines) - most + 1} more {more}"]


def _wrap(line: str, width: int) -> str:
    import textwrap

    indent = " " * (len(line) - len(line.lstrip()) + 4)
    return textwrap.fill(line, width, subsequent_indent=indent)


def gap_figure(report: GapReport) -> Figure:
    """Residuals against θ before and after, per axis, with the ±σ band and binned means;
    the residuals and their binned means before and after against time
    (:func:`_time_panel`); the verdict in the title and in
    a box below, panels with unexplained structure framed in red and labelled.

    Returns a :class:`matplotlib.figure.Figure` (rows x, y: columns before, after against θ;
    a row of the residuals in time, x and y; a text row with the verdict, the
    unexplained signatures and the shrink per axis).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    theta = report.replay.tita
    fig = plt.figure(figsize=(11, 11.5), constrained_layout=True)
    grid = fig.add_gridspec(4, 2, height_ratios=[1.0, 1.0, 0.8, 0.42])
    axs = np.empty((2, 2), dtype=object)
    for k in range(2):
        for j in range(2):
            # after shares the before panel's y axis: the same scale shows what shrank
            axs[k, j] = fig.add_subplot(grid[k, j], sharex=axs[0, 0] if k or j else None,
                                        sharey=axs[k, 0] if j else None)
    unexplained = report.unexplained if report.verdict == "unexplained" else []
    moving = drive_state(theta)  # the stretches where the table moves, for the row in time
    for k, ax_name in enumerate(AXES):
        for j, (which, res, gaps) in enumerate((
                ("before", report.residual_before, report.gap_before),
                ("after", report.residual_after, report.gap_after))):
            ax = axs[k, j]
            gm = gaps[ax_name]
            sigma = np.sqrt(report.noise_var[k] if which == "before"
                            else report.after[ax_name].sigma2)
            ax.plot(theta, res[:, k], ".", ms=1.5, color=(0.35, 0.55, 0.85) if j else
                    (0.55, 0.55, 0.55), alpha=0.6, rasterized=True, label="data − simulation")
            _binned_line(ax, theta, res[:, k], sigma, MEAN_COLOR, 0.3, 1.5, "binned mean",
                         band_label="binned mean ±σ/√n (n = {n})")
            _sigma_band(ax, sigma, "±σ")
            ok = (report.consistent("before" if which == "before" else "after")[ax_name])
            chi2 = gm.chi2_dof if which == "before" else report.chi2_after(ax_name)
            # a pattern is named only where it is itself beyond noise: on a consistent panel
            # the largest z is what noise alone gives, and on a panel that a check of the
            # battery flags (a drive-state or walk check, …) the check's words say what it is
            beyond = gm.max_signature_z > gm.threshold_z(report.family_alpha)
            worst = (" (no pattern beyond noise)" if ok
                     else f": {signature_words(str(gm.worst))}" if beyond
                     else " (within noise; the finding: in the red box)")
            ax.set_title(f"{ax_name}, {which}: χ²/dof = {chi2:.3f} — "
                         f"{'consistent with noise' if ok else 'GAP: structure beyond noise'}\n"
                         f"max |z| = {gm.max_signature_z:.1f}{worst}", fontsize=9)
            ax.set_ylabel(f"residual {ax_name} (m/s²)")
            if k == 1:
                ax.set_xlabel("θ from the encoder (rad)")
            if k == 0 and j == 0:
                ax.legend(loc="upper right", fontsize=7, markerscale=4)
        mine = [u for u in unexplained if u.get("axis") in (ax_name, "both")]
        timed = fig.add_subplot(grid[2, k], sharey=axs[k, 0])
        _time_panel(timed, report, k, moving)
        if mine:
            _mark_unexplained(axs[k, 1], mine)
            _frame(timed)
    box = fig.add_subplot(grid[3, :])
    box.axis("off")
    box.text(0.0, 1.0, _wrap(CAPTION, 150) + "\n\n" + verdict_box_text(report),
             transform=box.transAxes, va="top",
             ha="left", fontsize=8, family="monospace",
             bbox={"boxstyle": "round", "facecolor": VERDICT_COLORS.get(
                 report.verdict, VERDICT_COLORS["nothing_detected"]), "edgecolor": "0.5"})
    # wrapped: several named effects with their estimates make a line wider than the page
    # two lines at most: the verdict and what was added (estimates ± std in the box and
    # gap.md; a title that grew with every named effect ran off the page)
    names = [f"{e.name} ({e.axis}{', tentative' if report.verdict == 'unexplained' else ''})"
             for e in report.effects]
    added = ", ".join(names) if names else "no effect named"
    fig.suptitle(_shorten(signature_words(report.verdict_lines()[0]), 120) + "\n"
                 + _shorten(f"gap before / after adding: {added}", 120),
                 fontsize=10,
                 color=UNEXPLAINED_EDGE if report.verdict == "unexplained" else "k")
    return fig


def _time_panel(ax: Axes, report: GapReport, k: int, moving: np.ndarray | None) -> None:
    """Axis k's residuals (m/s²) against the sample time (s; the sample index when the run has
    no times: its samples are in time order): the residuals before as dots, the binned means
    (equal sample counts) before and after, each ±σ/√n, and the ±σ band of the model after;
    shaded where the table moves (``moving``: :func:`calib.gap.drive_state.drive_state` of
    the run, not in a hold; None when the run lacks either state). Against θ a step, a
    switching bias or an effect present only while moving is spread over every angle; in
    time it stands where it happened, and the mean after shows whether the named effects
    took it."""
    ax_name = AXES[k]
    t = report.replay.t
    n = report.residual_before.shape[0]
    x = np.arange(n, dtype=float) if t is None else np.asarray(t, dtype=float)
    sigma = float(np.sqrt(report.after[ax_name].sigma2))
    if moving is not None:
        ax.fill_between(x, 0.0, 1.0, where=moving, step="mid", color="0.85", lw=0,
                        transform=ax.get_xaxis_transform(), zorder=0,
                        label="table moving")
    ax.plot(x, report.residual_before[:, k], ".", ms=1.5, color=(0.55, 0.55, 0.55), alpha=0.5,
            rasterized=True, label="data − simulation (before)")
    for which, res, s_k, color in (
            ("before", report.residual_before, float(np.sqrt(report.noise_var[k])), "k"),
            ("after", report.residual_after, sigma, MEAN_COLOR)):
        _binned_line(ax, x, res[:, k], s_k, color, 0.25, 1.3, f"binned mean {which}")
    _sigma_band(ax, sigma)
    ax.set_xlim(x[0], x[-1])
    ax.set_title(f"{ax_name}, in time: residuals before, binned means before and after"
                 + ("" if moving is None else "\n(grey: the table moves)"), fontsize=9)
    ax.set_xlabel("sample time t (s)" if t is not None
                  else "sample index (time order; the run has no sample times)")
    ax.set_ylabel(f"residual {ax_name} (m/s²)")
    if k == 0:
        ax.legend(loc="upper right", fontsize=7, markerscale=4)


def _binned_line(ax: Axes, x: np.ndarray, y: np.ndarray, sigma: float, color, alpha: float,
                 lw: float, label: str, band_label: str | None = None) -> None:
    """The binned mean of ``y`` against ``x`` (:data:`BINS` bins of equal sample counts) with
    its ±σ/√n band (1 std of a bin's mean, the figure's one level); ``band_label`` may say n
    as ``{n}``."""
    cx, cy, _ = binned_mean(x, y, BINS)
    n_bin = max(1, y.shape[0] // BINS)
    half = sigma / np.sqrt(n_bin)
    ax.fill_between(cx, cy - half, cy + half, color=color, alpha=alpha, lw=0, zorder=3.5,
                    label=None if band_label is None else band_label.format(n=n_bin))
    ax.plot(cx, cy, "-", color=color, lw=lw, zorder=4, label=label)


def _sigma_band(ax: Axes, sigma: float, label: str | None = None) -> None:
    """The ±σ band of the per-sample noise (m/s²), its dashed edges and the zero line."""
    ax.axhspan(-sigma, sigma, color=(0.95, 0.7, 0.2), alpha=0.25, zorder=1, label=label)
    for sign in (-1.0, 1.0):
        ax.axhline(sign * sigma, color=(0.85, 0.55, 0.1), lw=1.0, ls="--", zorder=3)
    ax.axhline(0.0, color="k", lw=0.6)


def _frame(ax: Axes) -> None:
    """Frame a panel in red (its axis has unexplained structure)."""
    for spine in ax.spines.values():
        spine.set_edgecolor(UNEXPLAINED_EDGE)
        spine.set_linewidth(2.0)


def _mark_unexplained(ax: Axes, signatures: list[dict]) -> None:
    """Frame a panel in red and list the unexplained signatures in its top-left corner."""
    _frame(ax)
    items = [_shorten(signature_words(f"{u.get('description', u.get('signature', '?'))}"),
                      PANEL_CHARS) for u in signatures]
    more = "(in the box below and gap.md)"
    text = "unexplained:\n" + "\n".join(_capped(items, PANEL_ITEMS, more))
    ax.text(0.01, 0.98, text, transform=ax.transAxes, va="top", ha="left", fontsize=7.5,
            color=UNEXPLAINED_EDGE, zorder=5,
            bbox={"boxstyle": "round", "facecolor": "white", "alpha": 0.85,
                  "edgecolor": UNEXPLAINED_EDGE})


def save_gap_figure(report: GapReport, paths: Sequence[str | os.PathLike]) -> list[Path]:
    """Draw :func:`gap_figure` once and write it to each of ``paths`` (format from the suffix;
    overwrites): the figure and its layout are built once for every format
    (:func:`bench.figures.save.save_figure_as`)."""
    from bench.figures.save import save_figure_as  # matplotlib: with the figure, not before

    return save_figure_as(gap_figure(report), list(paths), force=True)
