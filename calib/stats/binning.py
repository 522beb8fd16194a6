"""Binned means of a scattered signal (equal sample counts per bin).

The one implementation behind every binned-mean line: the rerun recordings
(``calibration/{axis}/residual_mean``, ``vs_ar/mean``, the gap recording) and the matplotlib
figures (residual panels, vehicle accelerations, the gap figure) all call :func:`binned_mean`.
"""

from __future__ import annotations

import numpy as np

DEFAULT_BINS = 100
"""Bins of :func:`binned_mean` when none are given."""


def binned_mean(x: np.ndarray, y: np.ndarray, bins: int = DEFAULT_BINS
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean of ``y`` over ``bins`` groups of consecutive ``x`` (equal sample counts).

    Parameters
    ----------
    x : (n,) abscissa, any unit (θ in rad, A_r in m/s², t in s); flattened.
    y : (n,) values, same length as ``x``, any unit (e.g. residuals in m/s²); flattened.
    bins : number of groups; at most ``n`` are made (empty groups are dropped).

    Returns
    -------
    centre : (m,) mean ``x`` of each bin, unit of ``x``.
    mean : (m,) mean ``y`` of each bin, unit of ``y``.
    at : (m,) int64, the sample index at the middle of each bin (its median index in the
        original order), to place the mean on a sample timeline.

    Notes
    -----
    The samples are sorted by ``x`` (stable) and split into ``m = min(bins, n)`` consecutive
    groups ``G_j`` of sizes differing by at most one (``numpy.array_split``)::

        x̄_j = (1/|G_j|) Σ_{i∈G_j} x_i,     ȳ_j = (1/|G_j|) Σ_{i∈G_j} y_i

    Equal counts make the band ``±2σ/sqrt(n/bins)`` of a white residual exact for every bin.
    The line shows a systematic signature that the raw scatter of 20001 points hides.
    """
    x, y = np.asarray(x, float).ravel(), np.asarray(y, float).ravel()
    if x.size == 0:
        return x, y, np.zeros(0, dtype=np.int64)
    order = np.argsort(x, kind="stable")
    groups = [g for g in np.array_split(order, min(bins, x.size)) if g.size]
    return (np.array([x[g].mean() for g in groups]), np.array([y[g].mean() for g in groups]),
            np.array([int(np.sort(g)[g.size // 2]) for g in groups], dtype=np.int64))
