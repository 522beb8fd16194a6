"""What the readers share: their exceptions and the numeric limits of file values.

A module of its own, importing nothing from ``calib``, so that :mod:`calib.files.course`,
:mod:`calib.files.datos_txt` and :mod:`calib.files.degeneracy` can all use it without an import
circle.
"""

from __future__ import annotations


class DataError(ValueError):
    """Input data that cannot be used as given (message names file, variable and fix)."""


class DataNote(UserWarning):
    """Something about an input file the user should know that does not stop the run
    (extra variables ignored). The command line prints it on stderr as ``warning: …``."""


MAX_ABS_TIME = 1e12
"""Largest |t| accepted, s (≈ 31 700 years): beyond it integrals overflow or lose the step."""

MAX_ABS_POSITION = 1e15
"""Largest |coordinate| accepted in ``puntos.mat`` and ``datos.txt``, m."""

MAX_ABS_ACCEL = 1e9
"""Largest |acceleration| accepted in a file, m/s² (≈ 10⁸ g: no accelerometer reads that;
a units or file error)."""

MAX_ABS_VELOCITY = 1e9
"""Largest |initial velocity| accepted in ``datos.txt``, m/s."""
