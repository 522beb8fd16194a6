"""A calibration applied to a log: the corrected readings and the CSV that carries them
(``tiltbench apply``, docs/calibration-file.md).

Equations (one home each; this module only picks the one of the file's kind):

* tilt plane (bias and scale of x, y): ``A_r = (A_m − bias)/(1 + scale)`` per axis,
  :func:`calib.calibration.correct.correct` (course model; IEEE Std 1293 K0 = bias,
  K1 = 1 + scale);
* six-face (three axes with misalignment): ``a = K⁻¹ (m − b)``, ``K = (I + S)(I + M)``,
  :meth:`calib.calibration.sixface.SixFaceFit.correct` (IEEE Std 1293, linear terms).

Frames and units: the log is read into m/s² (its unit converted with 9.80665 m/s² per g) in
the calibration's frame: x and y are the log's signed axes of the calibration's ``--axes``,
z (six-face) their cross product ``x̂ × ŷ``. The corrected readings are in m/s² in the same
frame; :func:`calib.calibration.calfile.check_applies` refuses a log read through other axes
or in another unit than the calibration's.

The CSV (UTF-8, comma-separated, written atomically): two ``#`` comment lines naming the log
and the calibration file with their SHA-256, the equation and the frame; a header ``t (s),
acc_x (m/s^2), acc_y (m/s^2)[, acc_z (m/s^2)]`` (``t`` only when the log has sample times);
one row per sample, each number in Python's shortest round-trip form, so that reading the
file back gives the corrected floats exactly. tiltbench's own CSV reader reads it as a log in
m/s² with ``--axes x,y``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from calib.calibration.calfile import CalibrationFile, check_applies
from calib.calibration.calfile_fields import FORMAT, file_ref
from calib.calibration.correct import correct
from calib.calibration.sixface import AXES_3, SixFaceFit
from calib.files.atomic import write_text
from calib.logs.reader import ImuLog, file_sha256
from calib.results import readonly

EQUATIONS = {"tilt-plane": "A_r = (A_m - bias) / (1 + scale)",
             "six-face": "a = K^-1 (m - b), K = (I + S)(I + M)"}
"""The correction of each kind of calibration file, as the CSV comment states it (ASCII)."""


@dataclass(frozen=True)
class CorrectedLog:
    """A log corrected with a calibration file.

    Attributes
    ----------
    t : (N,) s, the log's sample times, or None.
    acc : (N, 2) or (N, 3) corrected specific force, m/s², columns :attr:`axes`.
    axes : the calibration's axes, ``("x", "y")`` or ``("x", "y", "z")``.
    log_axes : the log's signed axis each column was read from (``("-y", "z", "-x")``).
    kind : ``"tilt-plane"`` or ``"six-face"``: which equation (:data:`EQUATIONS`).
    log : ``{"name", "sha256"}`` of the log.
    calibration : ``{"name", "sha256", "checksum", "format_version", "method"}`` of the
        calibration file (``sha256``: of its bytes; ``checksum``: of its defining fields).
    """

    t: np.ndarray | None
    acc: np.ndarray
    axes: tuple[str, ...]
    log_axes: tuple[str, ...]
    kind: str
    log: dict[str, Any] = field(default_factory=dict)
    calibration: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "acc", readonly(self.acc))
        if self.t is not None:
            object.__setattr__(self, "t", readonly(self.t))

    @property
    def n(self) -> int:
        return int(self.acc.shape[0])

    @property
    def equation(self) -> str:
        return EQUATIONS[self.kind]

    def columns(self) -> list[str]:
        """The CSV header cells, units in brackets."""
        return ([] if self.t is None else ["t (s)"]) + [f"acc_{a} (m/s^2)" for a in self.axes]

    def to_dict(self) -> dict[str, Any]:
        """What ``apply --json`` prints (units under ``units``)."""
        return {"log": self.log, "calibration": self.calibration, "kind": self.kind,
                "equation": self.equation, "axes": list(self.axes),
                "log_axes": list(self.log_axes), "samples": self.n,
                "columns": self.columns(), "units": {"samples": "count",
                                                     "calibration.format_version": "—"}}


def _log_ref(log: ImuLog) -> dict[str, Any]:
    src = (log.provenance or {}).get("source") or {}
    sha = src.get("sha256")
    if sha is None and Path(log.source).is_file():
        sha = file_sha256(log.source)
    return {"name": src.get("name") or Path(log.source).name, "sha256": sha}


def correct_log(calfile: CalibrationFile, log: ImuLog) -> CorrectedLog:
    """The readings of ``log`` corrected with ``calfile`` (module docstring).

    Parameters
    ----------
    calfile : a checked calibration file (:func:`calib.calibration.calfile.
        load_calibration_file`), tilt-plane or six-face.
    log : the log, read with the calibration's ``--axes`` and unit.

    Returns
    -------
    CorrectedLog

    Raises
    ------
    DataError : the log's axes or unit differ from the calibration's, or a six-face file
        meets a log without a third axis (:func:`calib.calibration.calfile.check_applies`).
    """
    check_applies(calfile, log, tilt_plane=False)
    cal = calfile.calibration
    if isinstance(cal, SixFaceFit):
        acc = cal.correct(np.column_stack([log.acc, log.acc_normal]))
        axes = AXES_3
    else:
        acc = correct(log.acc, cal.bias, cal.scale)
        axes = AXES_3[:2]
    path = Path(str(calfile.path))
    ref = file_ref(path) if path.is_file() else {"name": path.name, "sha256": None}
    return CorrectedLog(
        t=log.t, acc=acc, axes=axes, log_axes=calfile.log_axes, kind=calfile.kind,
        log=_log_ref(log),
        calibration={**ref, "checksum": calfile.checksum, "format_version": calfile.version,
                     "method": cal.method if not isinstance(cal, SixFaceFit) else "six-face"})


def corrected_csv(corrected: CorrectedLog) -> str:
    """The CSV text of a corrected log (module docstring)."""
    c = corrected
    cal, log = c.calibration, c.log
    frame = ", ".join(f"{a} = log {s}" for a, s in zip(c.axes, c.log_axes, strict=True))
    lines = [f"# tiltbench apply: {log['name']} (sha256 {log['sha256']}) corrected with "
             f"{cal['name']} (sha256 {cal['sha256']}; {FORMAT} version "
             f"{cal['format_version']}, {cal['method']}, checksum {cal['checksum']})",
             f"# {c.equation} (IEEE Std 1293); axes {frame}; m/s^2",
             ",".join(c.columns())]
    cols = [c.acc] if c.t is None else [c.t[:, None], c.acc]
    rows = np.hstack(cols).tolist()
    lines += [",".join(map(repr, row)) for row in rows]  # shortest round trip: exact
    return "\n".join(lines) + "\n"


def save_corrected_log(path: str | os.PathLike, corrected: CorrectedLog,
                       force: bool = False) -> Path:
    """Write :func:`corrected_csv` atomically (:func:`calib.files.atomic.write_text`); an
    existing file is refused (``FileExistsError``) unless ``force``."""
    return write_text(path, corrected_csv(corrected), force=force)


__all__ = ["EQUATIONS", "CorrectedLog", "correct_log", "corrected_csv", "save_corrected_log"]
