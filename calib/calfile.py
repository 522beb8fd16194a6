"""The calibration file: a :class:`~calib.calibration.Calibration` that travels (``cal.json``).

``tiltbench calibrate ENSAYO --save cal.json`` writes it; ``trajectory`` and ``validate``
read it with ``--calibration cal.json`` instead of re-fitting. The format is documented in
``docs/calibration-file.md``; in short, one JSON object::

    format           "tiltbench-calibration"          (FORMAT)
    format_version   1                                (FORMAT_VERSION)
    tool             {"name": "tiltbench", "version": "0.1.0"}
    method, g        "ols" | "wls" | "multiposition", m/s²
    n                samples of the calibration run
    sigma2           [σx², σy²] (m/s²)²;  sigma2_source "given" | "datos.txt" | "estimated"
    noise_file       {"name", "sha256"} of the datos.txt the σ² came from, or null
    source           {"name", "sha256"} of the ensayo.mat the fit used
    param_names      ["bias_x", "scale_x", "bias_y", "scale_y"]
    params, std      (4,) m/s², 1, m/s², 1;   cov (4, 4), products of those units
    calibration      Calibration.to_state(): the exact rebuild (residuals included)
    units            key path → unit of every number (docs/units.md)

``params`` and ``cov`` repeat what ``calibration`` holds, for readers that are not tiltbench;
the loader checks that they agree. Floats are written with ``repr`` (shortest round trip), so
``load_calibration(path) == cal`` exactly.

The ``.mat`` export (:func:`save_calibration_mat`) holds the same numbers as plain double
variables and the text fields as char, for MATLAB/Octave, plus the whole JSON object as one
char variable ``document``: :func:`load_calibration` reads a ``.mat`` back from it exactly as
the ``.json`` (same checks, same ``format_version`` refusal) and checks that the plain
variables agree with it.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from calib.atomic import write_bytes, write_text
from calib.calibration import METHODS, Calibration
from calib.conventions import AXES, JOINT_PARAM_NAMES
from calib.input_rules import DataError
from calib.units import nest

FORMAT = "tiltbench-calibration"
"""The ``format`` value of every calibration file."""
FORMAT_VERSION = 1
"""The only ``format_version`` this reader knows; a file of another version is refused."""
SIGMA2_SOURCES = ("given", "datos.txt", "estimated")
"""Where σ² came from: ``--noise-var``, the course ``datos.txt``, or the fit's residuals."""

_PARAM_UNITS = "[m/s², 1, m/s², 1]"
_COV4_UNITS = ("[(m/s²)², m/s², (m/s²)², m/s², m/s², 1, m/s², 1, "
               "(m/s²)², m/s², (m/s²)², m/s², m/s², 1, m/s², 1]")
_FIT_UNITS = {  # FitResult.to_dict() of one axis (order [bias, scale])
    "params": "[m/s², 1]", "std": "[m/s², 1]", "cov": "[(m/s²)², m/s², m/s², 1]",
    "sigma2": "(m/s²)²", "chi2_dof": "1", "dof": "count", "cond": "1", "rank": "count",
    "chi2": "1", "residuals": "m/s²",
}
_JOINT_UNITS = {**_FIT_UNITS, "params": _PARAM_UNITS, "std": _PARAM_UNITS, "cov": _COV4_UNITS,
                "extra.noise_cov": "(m/s²)²"}

FILE_UNITS = {  # the "units" object of a calibration file (docs/units.md)
    "format_version": "—", "g": "m/s²", "n": "count", "sigma2": "(m/s²)²",
    "params": _PARAM_UNITS, "std": _PARAM_UNITS, "cov": _COV4_UNITS,
    **nest("calibration", Calibration._JSON_UNITS),
    **nest("calibration.fits.*", _FIT_UNITS),
    **nest("calibration.joint", _JOINT_UNITS),
}

_REQUIRED = ("format", "format_version", "tool", "method", "g", "n", "sigma2",
             "sigma2_source", "noise_file", "source", "param_names", "params", "cov",
             "calibration", "units")


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 (hex) of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _file_ref(path: str | os.PathLike | None) -> dict | None:
    if path is None:
        return None
    return {"name": Path(path).name, "sha256": file_sha256(path)}


def calibration_document(cal: Calibration, source: str | os.PathLike | None,
                         sigma2_source: str, noise_file: str | os.PathLike | None = None,
                         tool_version: str = "unknown") -> dict:
    """The calibration-file object (module docstring) of ``cal``.

    Parameters
    ----------
    cal : the calibration.
    source : the ensayo.mat it was fitted on (name and SHA-256 are recorded), or None.
    sigma2_source : where σ² came from, one of :data:`SIGMA2_SOURCES`.
    noise_file : the datos.txt σ² was read from (name and SHA-256), or None.
    tool_version : the version of the program writing the file (``calib`` does not know it).
    """
    if sigma2_source not in SIGMA2_SOURCES:
        raise ValueError(f"sigma2_source must be one of {SIGMA2_SOURCES}, got {sigma2_source!r}")
    return {
        "format": FORMAT, "format_version": FORMAT_VERSION,
        "tool": {"name": "tiltbench", "version": str(tool_version)},
        "method": cal.method, "g": cal.g, "n": cal.n,
        "sigma2": [cal.fits[a].sigma2.item() for a in AXES],
        "sigma2_source": sigma2_source, "noise_file": _file_ref(noise_file),
        "source": _file_ref(source),
        "param_names": list(JOINT_PARAM_NAMES), "params": cal.params.tolist(),
        "std": cal.std.tolist(), "cov": cal.cov.tolist(),
        "units": {**FILE_UNITS, **nest("calibration", cal.state_units())},
        "calibration": cal.to_state(),
    }


def save_calibration(path: str | os.PathLike, cal: Calibration,
                     source: str | os.PathLike | None = None, sigma2_source: str = "estimated",
                     noise_file: str | os.PathLike | None = None,
                     tool_version: str = "unknown", force: bool = False) -> Path:
    """Write ``cal`` as a calibration file, atomically (:func:`calib.atomic.write_text`).

    ``.mat`` in the name writes the MATLAB/Octave export (:func:`save_calibration_mat`),
    anything else the JSON file. An existing file is refused (``FileExistsError``) unless
    ``force``. Parameters as :func:`calibration_document`.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from calib import Ensayo, calibrate
    >>> th = np.linspace(0, 2 * np.pi, 100)
    >>> cal = calibrate(Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    ...                        + 0.05), noise_var=[0.25, 0.64])
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "cal.json"
    >>> _ = save_calibration(p, cal, sigma2_source="given")
    >>> load_calibration(p) == cal
    True
    """
    doc = calibration_document(cal, source, sigma2_source, noise_file, tool_version)
    if Path(path).suffix.lower() == ".mat":
        return save_calibration_mat(path, doc, force=force)
    return write_text(path, _document_json(doc), force=force)


def mat_variables(doc: dict) -> dict[str, Any]:
    """The variables of the ``.mat`` export of a calibration-file object: numbers as double
    arrays, text as char (no structs or cells: every MATLAB and Octave reads them)."""
    cal = doc["calibration"]
    out: dict[str, Any] = {
        "format": doc["format"], "format_version": float(doc["format_version"]),
        "tool_version": doc["tool"]["version"], "method": doc["method"],
        "g": float(doc["g"]), "n": float(doc["n"]),
        "sigma2": np.asarray(doc["sigma2"], float).reshape(1, 2),
        "sigma2_source": doc["sigma2_source"],
        "param_names": ",".join(doc["param_names"]),
        "params": np.asarray(doc["params"], float).reshape(1, 4),
        "std": np.asarray(doc["std"], float).reshape(1, 4),
        "cov": np.asarray(doc["cov"], float),
        "chi2_dof": np.array([[cal["axes"][a]["chi2_dof"] for a in AXES]], float),
        "source_name": (doc["source"] or {}).get("name", ""),
        "source_sha256": (doc["source"] or {}).get("sha256", ""),
        "noise_file_name": (doc["noise_file"] or {}).get("name", ""),
        "noise_file_sha256": (doc["noise_file"] or {}).get("sha256", ""),
        "units": "g m/s^2; sigma2 (m/s^2)^2; params [m/s^2, 1, m/s^2, 1]; "
                 "cov products of the params' units; chi2_dof 1",
        "document": _document_json(doc),
    }
    return out


def _document_json(doc: dict) -> str:
    from calib.io import to_jsonable

    # keys in the order of calibration_document (not sorted): the header is read first
    return json.dumps(to_jsonable(doc), indent=2) + "\n"


def save_calibration_mat(path: str | os.PathLike, doc: dict, force: bool = False) -> Path:
    """Write the ``.mat`` export of a calibration-file object (MATLAB v5, atomically)."""
    import scipy.io

    buf = io.BytesIO()
    scipy.io.savemat(buf, mat_variables(doc), format="5", oned_as="row")
    return write_bytes(path, buf.getvalue(), force=force)


# ------------------------------------------------------------------ reading
def _fail(path, field: str, what: str) -> DataError:
    return DataError(f"{path}: field '{field}' {what}")


def _number(doc: dict, key: str, path) -> float:
    v = doc[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _fail(path, key, f"must be a finite number, got {v!r}")
    return float(v)


def _matrix(doc: dict, key: str, shape: tuple[int, ...], path) -> np.ndarray:
    try:
        arr = np.asarray(doc[key], dtype=float)
    except (TypeError, ValueError):
        raise _fail(path, key, f"must be numbers of shape {shape}") from None
    if arr.shape != shape:
        raise _fail(path, key, f"must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise _fail(path, key, "holds NaN or Infinity")
    return arr


def calibration_from_document(doc: Any, path: str | os.PathLike = "<memory>") -> Calibration:
    """Check a calibration-file object and rebuild its :class:`Calibration` (exact).

    Raises
    ------
    DataError : not a calibration file (``format``), a version this reader does not know
        (``format_version``), a missing or malformed field; one line naming the file and the
        field.
    """
    if not isinstance(doc, dict):
        raise DataError(f"{path}: not a calibration file (expected a JSON object with "
                        f"'format': '{FORMAT}')")
    if "format" not in doc:
        raise _fail(path, "format", f"missing: not a {FORMAT} file (a calibrate --json "
                    "output? write the file with calibrate --save)")
    if doc["format"] != FORMAT:
        raise _fail(path, "format", f"is {doc['format']!r}, expected {FORMAT!r}")
    if "format_version" not in doc:
        raise _fail(path, "format_version", "missing")
    version = doc["format_version"]
    if version != FORMAT_VERSION or isinstance(version, bool):
        raise _fail(path, "format_version", f"is {version!r}; this tiltbench reads version "
                    f"{FORMAT_VERSION} only (written by a newer tiltbench? upgrade, or "
                    "re-run calibrate --save)")
    for key in _REQUIRED:
        if key not in doc:
            raise _fail(path, key, "missing")
    if doc["method"] not in METHODS:
        raise _fail(path, "method", f"is {doc['method']!r}, expected one of "
                    f"{', '.join(METHODS)}")
    if doc["sigma2_source"] not in SIGMA2_SOURCES:
        raise _fail(path, "sigma2_source", f"is {doc['sigma2_source']!r}, expected one of "
                    f"{', '.join(SIGMA2_SOURCES)}")
    g = _number(doc, "g", path)
    if g <= 0:
        raise _fail(path, "g", f"must be positive, got {g}")
    params = _matrix(doc, "params", (4,), path)
    cov = _matrix(doc, "cov", (4, 4), path)
    _matrix(doc, "sigma2", (2,), path)
    if list(doc["param_names"]) != list(JOINT_PARAM_NAMES):
        raise _fail(path, "param_names", f"must be {list(JOINT_PARAM_NAMES)}")
    state = doc["calibration"]
    if not isinstance(state, dict):
        raise _fail(path, "calibration", "must be an object (Calibration.to_state())")
    try:
        cal = Calibration.from_dict(state)
    except KeyError as exc:
        raise _fail(path, f"calibration.{exc.args[0]}", "missing") from None
    except (TypeError, ValueError, IndexError) as exc:
        raise _fail(path, "calibration", f"is malformed ({exc})") from None
    if cal.method != doc["method"]:
        raise _fail(path, "method", f"is {doc['method']!r} but calibration.method is "
                    f"{cal.method!r}")
    if cal.g != g:
        raise _fail(path, "g", f"is {g} but calibration.g is {cal.g}")
    if not (np.array_equal(cal.params, params) and np.array_equal(cal.cov, cov)):
        raise _fail(path, "params", "or 'cov' differs from the 'calibration' state (the file "
                    "was edited?)")
    return cal


def read_calibration_document(path: str | os.PathLike) -> dict:
    """The JSON object of a calibration file, checked (:func:`calibration_from_document`)."""
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: calibration file not found")
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected a calibration file (cal.json)")
    if path.suffix.lower() == ".mat":
        return _read_mat_document(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise DataError(f"{path}: not a JSON calibration file ({exc})") from None
    calibration_from_document(doc, path)
    return doc


def _mat_text(mat: dict, key: str, path) -> str:
    v = mat.get(key)
    if v is None:
        raise _fail(path, key, "missing (not a tiltbench calibration .mat: write one with "
                    "calibrate --save cal.mat)")
    arr = np.asarray(v)
    if arr.dtype.kind != "U" or arr.size != 1:
        raise _fail(path, key, "must be a char row")
    return str(arr.reshape(-1)[0])


def _read_mat_document(path: Path) -> dict:
    """The calibration-file object stored in a ``.mat`` export, checked like the JSON file;
    the plain variables (``format_version``, ``params``, ``cov``) must agree with it."""
    import scipy.io

    try:
        mat = scipy.io.loadmat(path)
    except (ValueError, TypeError, OSError, NotImplementedError) as exc:
        raise DataError(f"{path}: not a MATLAB .mat calibration file ({exc})") from None
    fmt = _mat_text(mat, "format", path)
    if fmt != FORMAT:
        raise _fail(path, "format", f"is {fmt!r}, expected {FORMAT!r}")
    if "format_version" not in mat:
        raise _fail(path, "format_version", "missing")
    fv = np.asarray(mat["format_version"], dtype=float).reshape(-1)
    version = int(fv[0]) if fv.size == 1 and float(fv[0]).is_integer() else fv.tolist()
    if version != FORMAT_VERSION:
        raise _fail(path, "format_version", f"is {version!r}; this tiltbench reads version "
                    f"{FORMAT_VERSION} only (written by a newer tiltbench? upgrade, or "
                    "re-run calibrate --save)")
    try:
        doc = json.loads(_mat_text(mat, "document", path))
    except (ValueError, RecursionError) as exc:
        raise _fail(path, "document", f"is not the JSON calibration object ({exc})") from None
    calibration_from_document(doc, path)
    for key, shape in (("params", (1, 4)), ("cov", (4, 4))):
        arr = np.asarray(mat.get(key, np.empty(0)), dtype=float)
        if arr.shape != shape or not np.array_equal(arr.reshape(-1),
                                                    np.asarray(doc[key]).reshape(-1)):
            raise _fail(path, key, "differs from the 'document' variable (the file was "
                        "edited? edit neither, re-run calibrate --save)")
    return doc


def load_calibration(path: str | os.PathLike) -> Calibration:
    """Read a calibration file written by :func:`save_calibration` (exact rebuild).

    Parameters
    ----------
    path : a ``.json`` calibration file or its ``.mat`` export.

    Returns
    -------
    Calibration : equal (``==``) to the one saved.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from calib import Ensayo, calibrate
    >>> th = np.linspace(0, 2 * np.pi, 100)
    >>> cal = calibrate(Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    ...                        + 0.05), noise_var=[0.25, 0.64])
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = save_calibration(d / "cal.mat", cal, sigma2_source="given")
    >>> load_calibration(d / "cal.mat") == cal
    True

    Raises
    ------
    DataError : file missing, not JSON (or a ``.mat`` export), another format, an unknown
        ``format_version``, a missing or malformed field (one line: the file and the field).
        A ``.mat`` export (:func:`save_calibration_mat`) loads exactly as the ``.json``.
    """
    return calibration_from_document(read_calibration_document(path), path)


__all__ = ["FILE_UNITS", "FORMAT", "FORMAT_VERSION", "SIGMA2_SOURCES", "calibration_document",
           "calibration_from_document", "file_sha256", "load_calibration", "mat_variables",
           "read_calibration_document", "save_calibration", "save_calibration_mat"]
