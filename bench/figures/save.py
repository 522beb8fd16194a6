"""Writing a figure: PNG or SVG by extension, atomically, byte-reproducible."""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from calib.files.course import atomic_write_bytes

FORMATS = {".png": "png", ".svg": "svg"}
"""File extension → matplotlib format."""
DPI = 120


def save_figure(fig: Figure, path: str | Path, force: bool = False) -> Path:
    """Write ``fig`` as PNG or SVG (by extension) atomically, then close it.

    Raises ``ValueError`` for another extension and ``FileExistsError`` if ``path`` exists
    and not ``force``.
    """
    return save_figure_as(fig, [path], force)[0]


def save_figure_as(fig: Figure, paths: Sequence[str | Path], force: bool = False
                   ) -> list[Path]:
    """Write ``fig`` to each of ``paths`` (PNG or SVG by extension) atomically, then close it.

    Every path is checked (extension; exists and not ``force``) before any is written. The
    layout is solved once for all of them (:func:`_freeze_layout`, the costly part of a
    save after the drawing itself), so a figure wanted in two formats is built and laid out
    once, not twice. Raises like :func:`save_figure`.
    """
    paths = [Path(p) for p in paths]
    for path in paths:
        if FORMATS.get(path.suffix.lower()) is None:
            plt.close(fig)
            raise ValueError(f"{path}: figure format must be .png or .svg")
        if path.exists() and not force:
            plt.close(fig)
            raise FileExistsError(f"{path}: exists; pass --force to overwrite")
    _freeze_layout(fig)
    blobs = []
    for path in paths:
        fmt = FORMATS[path.suffix.lower()]
        buf = io.BytesIO()
        metadata = {"Date": None} if fmt == "svg" else {"Software": None}
        with plt.rc_context({"svg.hashsalt": "tiltbench"}):  # SVG ids without random salt
            fig.savefig(buf, format=fmt, dpi=DPI, metadata=metadata)
        blobs.append(buf.getvalue())
    plt.close(fig)
    return [atomic_write_bytes(path, blob, force=force)
            for path, blob in zip(paths, blobs, strict=True)]


def _freeze_layout(fig: Figure) -> None:
    """Run the layout engine once, then fix every axes at its position rounded to 1e-9 of
    the figure. The constrained-layout solver can differ in the last bit between the first
    figure drawn in a process and later ones; SVG clip-path ids hash the full-precision clip
    rectangle, so without rounding the same data would not always give the same bytes.

    The engine is then removed (None, not matplotlib's "none" placeholder): with any engine
    set, ``savefig`` first draws the whole figure once more into a scratch file of its format
    to let the engine run, which here would change nothing and cost as much as the save."""
    fig.set_dpi(DPI)  # the layout at the dpi it is saved with (text sizes move it)
    fig.draw_without_rendering()
    with plt.rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)
    for ax in fig.get_axes():
        ax.set_position([round(float(v), 9) for v in ax.get_position().bounds])
