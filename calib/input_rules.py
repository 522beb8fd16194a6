"""What the readers share: their exceptions, the numeric limits of file values and the first
bytes of a file (:func:`file_head`, how a reader tells a format by its signature) and the
first check of every reader (:func:`check_file`).

A module of its own, importing nothing from ``calib``, so that :mod:`calib.files.course`,
:mod:`calib.files.datos_txt` and :mod:`calib.files.degeneracy` can all use it without an import
circle.
"""

from __future__ import annotations

from typing import Any


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


# --- value rules of result files (cal.json, sensor.json): one home for both readers ---

G_RANGE = (1e-3, 1e4)
"""Gravity of the reference, m/s²: positive, not below a milli-m/s² (the Moon is 1.62) and not
above the ``--g`` option's limit (10⁴ m/s²)."""
SIGMA2_RANGE = (1e-100, 1e100)
"""Noise variances and parameter variances, (m/s²)² or their units: positive, not subnormal,
and small enough that sums of residual²/σ² and products of two of them stay finite (the
bound of the ``--noise-var`` option, ``bench.cli.options.VARIANCE_RANGE``)."""
GAIN_RANGE = (1e-3, 1e3)
"""The gain ``1 + scale`` of each axis: a sensor reading a thousandth or a thousand times the
acceleration is broken, not calibrated; commands divide by the gain, which must stay away
from 0 (the Moon-gravity case of the reader tests has a gain of 0.17)."""
CORRELATION_EIG_MIN = 1e-12
"""Smallest eigenvalue of a correlation matrix: below it the covariance is not numerically
positive definite (|ρ| ≈ 1 to 12 digits: bias and scale confounded); a strongly correlated
but real fit (θ over 0.01 rad) is at 1e-5."""

def field_error(path: Any, field: str, what: str) -> DataError:
    """``{path}: field '<field>' <what>``: a field that is missing, malformed or implausible."""
    return DataError(f"{path}: field '{field}' {what}")


def check_covariance(cov: Any, names: tuple[str, ...], field: str, path: Any,
                     rounding: float = 0.0) -> None:
    """Symmetric, variances in :data:`SIGMA2_RANGE`, |ρ| ≤ 1 for every pair (the pair is
    named), positive definite (Cholesky of the correlation matrix and its smallest eigenvalue
    ≥ :data:`CORRELATION_EIG_MIN`).

    ``rounding``: 0 (a least-squares covariance ``R⁻¹R⁻ᵀ`` is symmetric exactly, as written),
    or the relative asymmetry a product ``J C Jᵀ`` (the delta method) may carry from
    rounding, in units of ``√(C_ii C_jj)``."""
    import numpy as np  # here: this module is imported by the command line at start-up

    cov = np.asarray(cov, dtype=float)
    var = np.abs(np.diag(cov))
    off = np.abs(cov - cov.T)
    with np.errstate(over="ignore", invalid="ignore"):  # absurd entries: refused below
        allowed = rounding * np.sqrt(np.outer(var, var))
    if np.any(off > allowed) or not np.all(np.isfinite(off)):
        i, j = np.unravel_index(np.argmax(off), cov.shape)
        raise field_error(path, field, f"is not symmetric (entry [{i}][{j}] = "
                          f"{float(cov[i, j])!r}, [{j}][{i}] = {float(cov[j, i])!r})")
    var = np.diag(cov)
    for k, v in enumerate(var.tolist()):
        if not SIGMA2_RANGE[0] <= v <= SIGMA2_RANGE[1]:
            raise field_error(path, field, f"has variance {v!r} of {names[k]} (must be in "
                              f"[{SIGMA2_RANGE[0]:g}, {SIGMA2_RANGE[1]:g}])")
    sd = np.sqrt(var)
    rho = cov / np.outer(sd, sd)
    np.fill_diagonal(rho, 1.0)  # v/(√v·√v) may round to 1 ± ε; only the off-diagonal tells
    i, j = np.unravel_index(np.argmax(np.abs(rho - np.eye(len(sd)))), rho.shape)
    if abs(rho[i, j]) > 1:
        raise field_error(path, field, f"has correlation {rho[i, j]:.6g} between {names[i]} "
                          f"and {names[j]} (|ρ| > 1: not a covariance)")
    try:
        np.linalg.cholesky(rho)
        smallest = float(np.linalg.eigvalsh(rho)[0])
    except np.linalg.LinAlgError:
        smallest = -1.0
    if smallest < CORRELATION_EIG_MIN:
        raise field_error(path, field, f"is not positive definite (smallest eigenvalue of "
                          f"the correlation matrix {smallest:.3g})")


def stated_variances(noise_var: Any) -> Any:
    """The stated white-noise variances ``[σx², σy²]``, (m/s²)², as a (2,) array: the one
    check of the statement (two finite positive values; a 2×2 covariance gives its
    diagonal). ValueError otherwise. (numpy is imported here: this module imports nothing at
    its top that a reader would not need.)"""
    import numpy as np

    s2 = np.asarray(noise_var, dtype=float)
    if s2.shape == (2, 2):
        s2 = np.diag(s2)
    if s2.shape != (2,) or np.any(~np.isfinite(s2)) or np.any(s2 <= 0):
        raise ValueError(f"noise_var must be two positive variances, got {noise_var!r}")
    return s2
