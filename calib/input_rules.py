"""What the readers share: their exceptions, the numeric limits of file values and the first
bytes of a file (:func:`file_head`, how a reader tells a format by its signature) and the
first check of every reader (:func:`check_file`).

A module of its own, importing nothing from ``calib``, so that :mod:`calib.files.course`,
:mod:`calib.files.datos_txt` and :mod:`calib.files.degeneracy` can all use it without an import
circle.
"""

from __future__ import annotations


class DataError(ValueError):
    """Input data that cannot be used as given (message names file, variable and fix)."""


def check_file(path, expected: str, what: str = "file") -> None:
    """Refuse (:class:`DataError` naming ``path``) an input that is missing ("<what> not
    found") or a directory ("is a directory; expected <expected>")."""
    if not path.exists():
        raise DataError(f"{path}: {what} not found")
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected {expected}")


def file_head(path, size: int) -> bytes | None:
    """The first ``size`` bytes of the file ``path`` (fewer when it is shorter), or None when
    it cannot be opened (missing, a directory, no permission)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(size)
    except OSError:
        return None


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
