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


def plot_bounds() -> Any:
    """View bounds of a :class:`StaticPlot` (the box plus room for the tick labels)."""
    import rerun.blueprint as rrb

    w, h = PLOT_BOX
    return rrb.VisualBounds2D(x_range=[-0.09 * w, 1.02 * w], y_range=[-0.03 * h, 1.2 * h])
