"""Physical constants, axis names and the course sign convention."""

from __future__ import annotations

import numpy as np

G: float = 9.8
"""Magnitude of gravity in m/s² used by the course (the user may give another)."""

AXES: tuple[str, str] = ("x", "y")
"""Column order of every (N, 2) array: x first, then y."""

PARAM_NAMES: tuple[str, str] = ("bias", "scale")
"""Order of the per-axis parameter vector: bias (m/s²), scale (dimensionless)."""

JOINT_PARAM_NAMES: tuple[str, ...] = ("bias_x", "scale_x", "bias_y", "scale_y")


def reference_accel(tita: np.ndarray, g: float = G) -> np.ndarray:
    """Reference specific force on the tilt table, course convention.

    Parameters
    ----------
    tita : (N,) array, rad
        Table angle.
    g : float, m/s²
        Magnitude of gravity.

    Returns
    -------
    (N, 2) array, m/s²
        ``[A_rx, A_ry] = [-g sin θ, -g cos θ]`` (course report, eq. 12–13). At θ = 0 the y axis
        points down the gravity vector, so it reads -g; tilting by +θ makes x read -g sin θ.
    """
    tita = np.asarray(tita, dtype=float)
    return np.column_stack([-g * np.sin(tita), -g * np.cos(tita)])


def axis_index(axis: str) -> int:
    """Column of ``axis`` ('x' or 'y') in every (N, 2) array."""
    try:
        return AXES.index(axis)
    except ValueError:
        raise ValueError(f"axis must be 'x' or 'y', got {axis!r}") from None
