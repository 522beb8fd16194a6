"""Correction of measured accelerations with a calibration (course model inverted)."""

from __future__ import annotations

import numpy as np


def apply_errors(a_r: np.ndarray, bias: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Forward sensor model without noise: ``A_m = (1 + scale) · A_r + bias`` (per column)."""
    return (1.0 + np.asarray(scale)) * np.asarray(a_r, dtype=float) + np.asarray(bias)


def correct(a_m: np.ndarray, bias: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Corrected acceleration ``A_r = (A_m - bias) / (1 + scale)``.

    Parameters
    ----------
    a_m : (M, 2) or (M,) measured acceleration, m/s² (columns x, y).
    bias : (2,) or scalar, m/s².  scale : (2,) or scalar, dimensionless (k = 1 + scale).

    Notes
    -----
    Divides by ``1 + scale`` — one of the course reports divides by ``1 - scale``, which
    doubles the scale error instead of removing it.
    """
    k = 1.0 + np.asarray(scale, dtype=float)
    if np.any(k <= 0):
        raise ValueError(f"1 + scale must be positive, got scale = {scale}")
    return (np.asarray(a_m, dtype=float) - np.asarray(bias, dtype=float)) / k
