"""A small 2-D plot engine for rerun: static plots with a frame, ticks and tick labels.

rerun draws 2-D space with +y down (image convention); a :class:`StaticPlot` maps its data box
onto a fixed 3:1 box (:data:`PLOT_BOX`) with +y up through the plot entity's ``Transform3D``,
so its children are logged in data units and plots of very different ranges keep one shape.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from bench.record.stream import COLORS

if TYPE_CHECKING:
    import rerun as rr

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

    def log_frame(self, rec: rr.RecordingStream, entity: str, zero_line: bool = False,
                  xlabel: str = "", ylabel: str = "") -> None:
        """Log the transform at ``entity`` and the frame at ``entity/axes`` (+ ``/labels``).

        ``xlabel`` is written under the right end of the x axis, ``ylabel`` above the top of
        the y axis (both with their unit, e.g. ``"θ (rad)"``)."""
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
        if xlabel:  # below the tick values, at the right end
            pos.append([x1 - 0.06 * dx, y0 - 0.13 * dy])
            labels.append(xlabel)
        if ylabel:  # above the frame, at the left end
            pos.append([x0 + 0.06 * dx, y1 + 0.12 * dy])
            labels.append(ylabel)
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


def plot_bounds() -> Any:
    """View bounds of a :class:`StaticPlot` (the box plus room for the tick labels)."""
    import rerun.blueprint as rrb

    w, h = PLOT_BOX
    return rrb.VisualBounds2D(x_range=[-0.09 * w, 1.02 * w], y_range=[-0.16 * h, 1.27 * h])


def grid_lines(x0: float, x1: float, y0: float, y1: float,
               n: int = 6) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Grid over the box [x0, x1] × [y0, y1] at round values (one step for both axes, so
    squares stay squares): (strips, x ticks, y ticks). The frame is the first strip."""
    step = float(np.diff(_nice_ticks(0.0, max(x1 - x0, y1 - y0), n))[:1].sum() or 1.0)
    xt = np.arange(np.ceil(x0 / step) * step, x1 + 1e-9 * step, step)
    yt = np.arange(np.ceil(y0 / step) * step, y1 + 1e-9 * step, step)
    strips = [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])]
    strips += [np.array([[t, y0], [t, y1]]) for t in xt]
    strips += [np.array([[x0, t], [x1, t]]) for t in yt]
    return strips, xt, yt


def log_grid(rec: rr.RecordingStream, entity: str, box: tuple[float, float, float, float],
             unit: str = "m", y_up: bool = True) -> None:
    """A labelled grid (the scale of a 2-D scene in data units) at ``entity`` (frame and
    lines, drawn under everything) and its values at ``entity/labels``: x values under the
    bottom edge, y values left of the left edge, the axis names with ``unit`` at the ends.

    ``y_up``: the entity's parent flips y (+y up on screen), so "under" is −y in data."""
    import rerun as rr

    x0, x1, y0, y1 = box
    strips, xt, yt = grid_lines(x0, x1, y0, y1)
    rec.log(entity, rr.LineStrips2D(strips, radii=rr.Radius.ui_points(0.5),
                                    colors=COLORS["grid"], draw_order=1.0), static=True)
    d = max(x1 - x0, y1 - y0)
    below = y0 - 0.012 * d if y_up else y1 + 0.012 * d
    xs = [_tick_text(t, xt) for t in xt]
    ys = [_tick_text(t, yt) for t in yt]
    pos = [[t, below] for t in xt] + [[x0 - 0.03 * d, t + (0.006 if y_up else -0.006) * d]
                                      for t in yt]
    pos += [[x1 - 0.04 * d, below - (0.03 if y_up else -0.03) * d],
            [x0 + 0.04 * d, y1 + (0.02 if y_up else -0.02) * d]]
    rec.log(f"{entity}/labels", rr.Points2D(
        np.array(pos, dtype=float), radii=0.0, labels=[*xs, *ys, f"x ({unit})", f"y ({unit})"],
        colors=COLORS["axes"], show_labels=True, draw_order=2.0), static=True)


def plane_box(*arrays, margin: float = 0.06) -> tuple[float, float, float, float]:
    """Box (x0, x1, y0, y1) around all given (n, 2) plane positions (m; None skipped) with a
    margin of ``margin`` × the larger side on each side: the extent of the plane's grid."""
    pts = np.concatenate([np.asarray(a, float).reshape(-1, 2) for a in arrays if a is not None])
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = margin * max(float(np.max(hi - lo)), 1.0)
    return float(lo[0] - pad), float(hi[0] + pad), float(lo[1] - pad), float(hi[1] + pad)
