"""The calibration file: a :class:`~calib.calibration.tilt_plane.Calibration` that travels
(``cal.json``).

``tiltbench calibrate ENSAYO --save cal.json`` writes it; ``trajectory``, ``nmin``, ``fuse`` and
``validate`` read it with ``--calibration cal.json`` instead of re-fitting, all through
:func:`load_calibration_file` (one reader, one set of checks). The format is documented in
``docs/calibration-file.md``; in short, one JSON object::

    format           "tiltbench-calibration"          (FORMAT)
    format_version   2                                (FORMAT_VERSION)
    tool             {"name": "tiltbench", "version": "0.1.0"}   (cosmetic: never checked)
    method, g        "ols" | "wls" | "multiposition", m/s²
    n                samples of the calibration run
    sigma2           [σx², σy²] (m/s²)²;  sigma2_source "given" | "datos.txt" | "estimated"
    noise_file       {"name", "sha256"} of the datos.txt the σ² came from, or null
    source           {"name", "sha256"} of the ensayo.mat the fit used
    param_names      ["bias_x", "scale_x", "bias_y", "scale_y"]
    params, std      (4,) m/s², 1, m/s², 1;   cov (4, 4), products of those units
    units            key path → unit of every number (docs/units.md)
    checksum         {"algorithm": "sha256", "covers": CHECKSUM_FIELDS, "value": hex}
    calibration      Calibration.to_state(): the exact rebuild (residuals included)

**One calibration, stored once.** The estimate is *defined* by the fields the
:class:`Calibration` is rebuilt from (:data:`DEFINING_FIELDS`: ``method``, ``g``, ``n`` and
``calibration.fits`` / ``joint`` / ``lack_of_fit``, plus the provenance ``sigma2_source``,
``source``, ``noise_file``). Every other readable number — ``params``, ``std``, ``cov``,
``sigma2``, ``units`` at the top, the ``calibrate --json`` block ``calibration.axes``, each
fit's ``std`` and ``chi2_dof``, and for WLS / multi-position the per-axis ``fits`` (blocks of
``joint``) — is *derived*: on load it is re-derived from the rebuilt calibration and must be
equal, exactly (floats are written with ``repr``, the shortest round trip). The defining
fields carry a SHA-256 of their canonical JSON (:func:`defining_checksum`), so a hand edit that
keeps the copies consistent is refused too. Every check names the file and the field and asks
to re-run ``calibrate --save``; a file that passes gives ``load_calibration(path) == cal``.

Before the consistency and checksum checks, the loader checks what the numbers must be for any
command to use them (:func:`check_calibration`): shapes, finite values, ``n`` an integer in
:data:`N_RANGE` and equal to the residual count, σ² > 0 within :data:`SIGMA2_RANGE` and equal
to what the residuals give, symmetric positive definite covariances with |ρ| ≤ 1, a plausible
g (:data:`G_RANGE`), bias and gain within :data:`MAX_ABS_BIAS` / :data:`GAIN_RANGE`.
:func:`save_calibration` runs the same checks and writes nothing when they fail.

Version 1 files (no checksum) are refused with a one-line "re-run calibrate --save": a
self-consistent hand edit of a version-1 file cannot be told from an original.

The ``.mat`` export (:func:`save_calibration_mat`) holds the same numbers as plain double
variables and the text fields as char, for MATLAB/Octave, plus the whole JSON object as one
char variable ``document``: :func:`load_calibration` reads a ``.mat`` back from it exactly as
the ``.json`` (same checks) and checks that every plain variable equals the one derived from
it (only ``tool_version`` is cosmetic).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from calib.calibration.lackoffit import LackOfFit
from calib.calibration.ls import FitResult
from calib.calibration.tilt_plane import METHODS, Calibration
from calib.conventions import AXES, JOINT_PARAM_NAMES, PARAM_NAMES
from calib.files.atomic import write_bytes, write_text
from calib.input_rules import MAX_ABS_ACCEL, DataError, check_file
from calib.units import nest

FORMAT = "tiltbench-calibration"
"""The ``format`` value of every calibration file."""
FORMAT_VERSION = 2
"""The only ``format_version`` this reader knows; a file of another version is refused
(version 1, before the checksum: re-run ``calibrate --save``)."""
SIGMA2_SOURCES = ("given", "datos.txt", "estimated")
"""Where σ² came from: ``--noise-var``, the course ``datos.txt``, or the fit's residuals."""

DEFINING_FIELDS = ("format", "format_version", "method", "g", "n", "sigma2_source",
                   "noise_file", "source", "calibration.fits", "calibration.joint",
                   "calibration.lack_of_fit")
"""The fields the calibration is rebuilt from; the ``checksum`` covers exactly these."""
CHECKSUM_FIELDS = DEFINING_FIELDS
"""The ``checksum.covers`` list of every version-2 file."""
COSMETIC_FIELDS = ("tool",)
"""Fields never checked nor used: editing them changes no number any command prints."""

N_RANGE = (3, 10_000_000)
"""Samples of a calibration run: at least 3 (two parameters per axis and one dof for σ²), at
most 10⁷ (the residuals alone would make a 600 MB file; no course or bench run is near)."""
G_RANGE = (1e-3, 1e4)
"""Gravity of the reference, m/s²: positive, not below a milli-m/s² (the Moon is 1.62) and not
above the ``--g`` option's limit (10⁴ m/s²)."""
SIGMA2_RANGE = (1e-100, 1e100)
"""Noise variances and parameter variances, (m/s²)² or their units: positive, not subnormal,
and small enough that sums of residual²/σ² and products of two of them stay finite (the
bound of the ``--noise-var`` option, ``bench.cli.options.VARIANCE_RANGE``)."""
MAX_ABS_BIAS = MAX_ABS_ACCEL
"""Largest |bias|, m/s²: the largest reading any file may hold (:data:`calib.input_rules.
MAX_ABS_ACCEL`); a bias above it is not a calibration of a sensor."""
GAIN_RANGE = (1e-3, 1e3)
"""The gain ``1 + scale`` of each axis: a sensor reading a thousandth or a thousand times the
acceleration is broken, not calibrated; commands divide by the gain, which must stay away
from 0 (the Moon-gravity case of the reader tests has a gain of 0.17)."""
CORRELATION_EIG_MIN = 1e-12
"""Smallest eigenvalue of a correlation matrix: below it the covariance is not numerically
positive definite (|ρ| ≈ 1 to 12 digits: bias and scale confounded); a strongly correlated
but real fit (θ over 0.01 rad) is at 1e-5."""
RELATIVE_TOLERANCE = 1e-9
"""Relative tolerance of the recomputed sums (χ², σ² from the residuals): a sum of N terms
recomputed in another order differs by ~N·ε ≈ 1e-12 for N = 20001; an edit differs by more."""

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

_REQUIRED = ("format", "format_version", "method", "g", "n", "sigma2", "sigma2_source",
             "noise_file", "source", "param_names", "params", "std", "cov", "units",
             "checksum", "calibration")
_RERUN = "re-run `tiltbench calibrate … --save`"


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


def _get(doc: dict, dotted: str) -> Any:
    """``doc["a"]["b"]`` for ``"a.b"`` (None where a level is missing)."""
    out: Any = doc
    for key in dotted.split("."):
        out = out.get(key) if isinstance(out, dict) else None
    return out


def defining_checksum(doc: dict) -> str:
    """SHA-256 (hex) of the canonical JSON of the :data:`DEFINING_FIELDS` of ``doc``.

    Canonical: ``{dotted field: value}``, keys sorted, no spaces, floats in ``repr`` (the
    shortest round trip), so the same numbers give the same hash whether ``doc`` was just
    built or read back from the file."""
    part = {f: _get(doc, f) for f in DEFINING_FIELDS}
    text = json.dumps(part, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      default=_plain)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _plain(obj: Any) -> Any:
    """``json.dumps`` hook for what a result holds besides plain Python: numpy arrays and
    scalars (numpy floats are ``float`` already and print the same ``repr``)."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f"not JSON: {type(obj).__name__}")


def _document(cal: Calibration, source: dict | None, sigma2_source: str,
              noise_file: dict | None, tool: Any, checksum: bool = True) -> dict:
    """The calibration-file object of ``cal`` given its provenance (references, not paths):
    what :func:`calibration_document` writes and what the loader re-derives to compare."""
    doc = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "tool": tool,
        "method": cal.method, "g": cal.g, "n": cal.n,
        "sigma2": [cal.fits[a].sigma2.item() for a in AXES],
        "sigma2_source": sigma2_source, "noise_file": noise_file, "source": source,
        "param_names": list(JOINT_PARAM_NAMES), "params": cal.params.tolist(),
        "std": cal.std.tolist(), "cov": cal.cov.tolist(),
        "units": {**FILE_UNITS, **nest("calibration", cal.state_units())},
        "checksum": None,
        "calibration": cal.to_state(),
    }
    if checksum:  # the reader compares the checksum with the file's own fields instead
        doc["checksum"] = {"algorithm": "sha256", "covers": list(CHECKSUM_FIELDS),
                           "value": defining_checksum(doc)}
    return doc


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
    return _document(cal, _file_ref(source), sigma2_source, _file_ref(noise_file),
                     {"name": "tiltbench", "version": str(tool_version)})


def save_calibration(path: str | os.PathLike, cal: Calibration,
                     source: str | os.PathLike | None = None, sigma2_source: str = "estimated",
                     noise_file: str | os.PathLike | None = None,
                     tool_version: str = "unknown", force: bool = False) -> Path:
    """Write ``cal`` as a calibration file, atomically (:func:`calib.files.atomic.write_text`).

    ``.mat`` in the name writes the MATLAB/Octave export (:func:`save_calibration_mat`),
    anything else the JSON file. An existing file is refused (``FileExistsError``) unless
    ``force``. Parameters as :func:`calibration_document`. A calibration the loader would
    refuse (:func:`check_calibration`: σ² = 0 from noiseless data, a gain near 0, …) raises
    :class:`DataError` and nothing is written.

    Examples
    --------
    Saved and read back, as JSON and as ``.mat``: :func:`load_calibration`.
    """
    doc = calibration_document(cal, source, sigma2_source, noise_file, tool_version)
    # the document goes through JSON before the check, as the reader will see it
    calibration_from_document(json.loads(_document_json(doc)), f"{path} (not written)")
    if Path(path).suffix.lower() == ".mat":
        return save_calibration_mat(path, doc, force=force)
    return write_text(path, _document_json(doc), force=force)


def mat_variables(doc: dict) -> dict[str, Any]:
    """The variables of the ``.mat`` export of a calibration-file object: numbers as double
    arrays, text as char (no structs or cells: every MATLAB and Octave reads them)."""
    cal = doc["calibration"]
    tool = doc.get("tool")
    out: dict[str, Any] = {
        "format": doc["format"], "format_version": float(doc["format_version"]),
        "tool_version": str(tool.get("version", "")) if isinstance(tool, dict) else "",
        "method": doc["method"],
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
        "checksum": doc["checksum"]["value"],
        "units": "g m/s^2; sigma2 (m/s^2)^2; params [m/s^2, 1, m/s^2, 1]; "
                 "cov products of the params' units; chi2_dof 1",
        "document": _document_json(doc),
    }
    return out


_MAT_COSMETIC = ("tool_version",)


def _document_json(doc: dict) -> str:
    # keys in the order of calibration_document (not sorted): the header is read first
    return json.dumps(doc, indent=2, default=_plain) + "\n"


def save_calibration_mat(path: str | os.PathLike, doc: dict, force: bool = False) -> Path:
    """Write the ``.mat`` export of a calibration-file object (MATLAB v5, atomically)."""
    import scipy.io

    buf = io.BytesIO()
    scipy.io.savemat(buf, mat_variables(doc), format="5", oned_as="row")
    return write_bytes(path, buf.getvalue(), force=force)


# ------------------------------------------------------------------ reading
def _fail(path, field: str, what: str) -> DataError:
    return DataError(f"{path}: field '{field}' {what}")


def _inconsistent(path, field: str, what: str) -> DataError:
    """Two parts of the file disagree: it was edited (or damaged) after calibrate wrote it."""
    return DataError(f"{path}: checksum/consistency failed: '{field}' {what}; {_RERUN}")


def _short(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _number(v: Any, field: str, path) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _fail(path, field, f"must be a finite number, got {_short(v)}")
    return float(v)


def _array(v: Any, field: str, shape: tuple[int | None, ...], path) -> np.ndarray:
    """``v`` as a finite float array of ``shape`` (None: any length)."""
    if isinstance(v, (str, bytes, dict, bool)):
        raise _fail(path, field, f"must be numbers of shape {shape}, got {_short(v)}")
    try:
        arr = np.asarray(v, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise _fail(path, field, f"must be numbers of shape {shape}") from None
    if arr.ndim != len(shape) or any(s is not None and s != a
                                     for s, a in zip(shape, arr.shape, strict=True)):
        raise _fail(path, field, f"must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise _fail(path, field, "holds NaN or Infinity")
    return arr


def _ref(doc: dict, key: str, path) -> None:
    v = doc[key]
    if v is None:
        return
    if (not isinstance(v, dict) or set(v) != {"name", "sha256"}
            or not isinstance(v["name"], str) or not isinstance(v["sha256"], str)
            or len(v["sha256"]) != 64 or any(c not in "0123456789abcdef" for c in v["sha256"])):
        raise _fail(path, key, "must be null or {\"name\": file name, \"sha256\": 64 hex "
                    f"digits}}, got {_short(v)}")


def _fit_from(d: Any, field: str, names: tuple[str, ...], path) -> FitResult:
    """One fit of the state (``FitResult.to_dict()``), its types and shapes checked."""
    if not isinstance(d, dict):
        raise _fail(path, field, f"must be an object (FitResult.to_dict()), got {_short(d)}")
    for key in ("param_names", "params", "cov", "residuals", "sigma2", "sigma2_source", "dof",
                "rank", "cond", "chi2", "extra"):
        if key not in d:
            raise _fail(path, f"{field}.{key}", "missing")
    p, joint = len(names), len(names) == 4
    if d["param_names"] != list(names):
        raise _fail(path, f"{field}.param_names", f"must be {list(names)}")
    _array(d["params"], f"{field}.params", (p,), path)
    _array(d["cov"], f"{field}.cov", (p, p), path)
    _array(d["residuals"], f"{field}.residuals", (None, 2) if joint else (None,), path)
    _array(d["sigma2"], f"{field}.sigma2", (2,) if joint else (), path)
    if d["sigma2_source"] not in ("given", "estimated"):
        raise _fail(path, f"{field}.sigma2_source", "must be 'given' or 'estimated', got "
                    f"{_short(d['sigma2_source'])}")
    for key in ("dof", "rank"):
        if not _is_int(d[key]) or d[key] < 1:
            raise _fail(path, f"{field}.{key}", f"must be a positive integer, got "
                        f"{_short(d[key])}")
    _number(d["cond"], f"{field}.cond", path)
    if _number(d["chi2"], f"{field}.chi2", path) < 0:
        raise _fail(path, f"{field}.chi2", f"must not be negative, got {d['chi2']!r}")
    if not isinstance(d["extra"], dict):
        raise _fail(path, f"{field}.extra", "must be an object")
    if "sigma2_dof" in d["extra"] and (not _is_int(d["extra"]["sigma2_dof"])
                                       or d["extra"]["sigma2_dof"] < 1):
        raise _fail(path, f"{field}.extra.sigma2_dof", "must be a positive integer")
    if "noise_cov" in d["extra"]:
        _array(d["extra"]["noise_cov"], f"{field}.extra.noise_cov", (2, 2), path)
    try:
        return FitResult.from_dict(d)
    except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise _fail(path, field, f"is malformed ({exc})") from None


def _check_cov(cov: np.ndarray, names: tuple[str, ...], field: str, path) -> None:
    """Symmetric, variances in :data:`SIGMA2_RANGE`, |ρ| ≤ 1, positive definite."""
    if not np.array_equal(cov, cov.T):  # the writer's covariances are exactly symmetric
        i, j = np.unravel_index(np.argmax(np.abs(cov - cov.T)), cov.shape)
        raise _fail(path, field, f"is not symmetric (entry [{i}][{j}] = {cov[i, j]!r}, "
                    f"[{j}][{i}] = {cov[j, i]!r})")
    var = np.diag(cov)
    for k, v in enumerate(var.tolist()):
        if not SIGMA2_RANGE[0] <= v <= SIGMA2_RANGE[1]:
            raise _fail(path, field, f"has variance {v!r} of {names[k]} (must be in "
                        f"[{SIGMA2_RANGE[0]:g}, {SIGMA2_RANGE[1]:g}])")
    sd = np.sqrt(var)
    rho = cov / np.outer(sd, sd)
    np.fill_diagonal(rho, 1.0)  # v/(√v·√v) may round to 1 ± ε; only the off-diagonal tells
    i, j = np.unravel_index(np.argmax(np.abs(rho - np.eye(len(sd)))), rho.shape)
    if abs(rho[i, j]) > 1:
        raise _fail(path, field, f"has correlation {rho[i, j]:.6g} between {names[i]} and "
                    f"{names[j]} (|ρ| > 1: not a covariance)")
    try:
        np.linalg.cholesky(rho)
        smallest = float(np.linalg.eigvalsh(rho)[0])
    except np.linalg.LinAlgError:
        smallest = -1.0
    if smallest < CORRELATION_EIG_MIN:
        raise _fail(path, field, f"is not positive definite (smallest eigenvalue of the "
                    f"correlation matrix {smallest:.3g})")


def _close(a: float, b: float) -> bool:
    return abs(a - b) <= RELATIVE_TOLERANCE * max(abs(a), abs(b))


def _check_fit(f: FitResult, field: str, path) -> None:
    """The numbers of one fit: variances, covariance, bias and gain, χ² against residuals."""
    for k, s2 in enumerate(np.atleast_1d(f.sigma2).tolist()):
        if not SIGMA2_RANGE[0] <= s2 <= SIGMA2_RANGE[1]:
            raise _fail(path, f"{field}.sigma2", f"is {s2!r}: a noise variance must be in "
                        f"[{SIGMA2_RANGE[0]:g}, {SIGMA2_RANGE[1]:g}] (m/s²)²"
                        + (f" (axis {AXES[k]})" if f.sigma2.ndim else ""))
    _check_cov(f.cov, f.param_names, f"{field}.cov", path)
    for k, name in enumerate(f.param_names):
        v = float(f.params[k])
        if name.startswith("bias") and abs(v) > MAX_ABS_BIAS:
            raise _fail(path, f"{field}.params", f"has {name} = {v!r} m/s² (|bias| at most "
                        f"{MAX_ABS_BIAS:g})")
        if name.startswith("scale") and not GAIN_RANGE[0] <= 1 + v <= GAIN_RANGE[1]:
            raise _fail(path, f"{field}.params", f"has {name} = {v!r}: the gain 1 + scale "
                        f"must be in [{GAIN_RANGE[0]:g}, {GAIN_RANGE[1]:g}]")
    if "noise_cov" in f.extra:
        _check_cov(np.asarray(f.extra["noise_cov"], float), ("x", "y"),
                   f"{field}.extra.noise_cov", path)


def _chi2(f: FitResult) -> float:
    """χ² of a fit recomputed from its residuals and σ² (the joint WLS with its noise cov)."""
    r = f.residuals
    if r.ndim == 1:
        return float(r @ r / f.sigma2)
    c = np.asarray(f.extra.get("noise_cov", np.diag(f.sigma2)), float)
    white = np.linalg.solve(np.linalg.cholesky(c), r.T)  # L⁻¹ rᵀ, never C⁻¹
    return float(np.sum(white**2))


def check_calibration(cal: Calibration, sigma2_source: str, path: Any = "<memory>") -> None:
    """Check that ``cal`` holds numbers every command may use, and that they agree.

    ``n`` an integer in :data:`N_RANGE`; σ² in :data:`SIGMA2_RANGE`; each covariance
    symmetric, positive definite, |ρ| ≤ 1 (:func:`_check_cov`); |bias| ≤ :data:`MAX_ABS_BIAS`,
    gain in :data:`GAIN_RANGE`; g in :data:`G_RANGE`. Against each other: for ``ols``/``wls``
    each axis has N residuals and N − 2 dof (the joint fit N × 2 and 2N − 4), for
    ``multiposition`` N = dof + P (P pose means); ``χ² = Σ r²/σ²`` (joint: ``Σ ‖L⁻¹r‖²``, C =
    LLᵀ) to :data:`RELATIVE_TOLERANCE`; an OLS σ² estimated from the residuals equals
    ``RSS/dof``; a pure-error σ² has ``sigma2_dof`` < N (its value comes from the scatter of
    the readings within poses, which the file does not hold: the checksum guards it); the
    per-axis fits of a joint fit are its blocks (equal, exactly).

    Raises
    ------
    DataError : one line, ``{path}: field '<field>' <what is wrong>``.
    """
    if not G_RANGE[0] <= cal.g <= G_RANGE[1]:
        raise _fail(path, "g", f"is {cal.g!r} m/s²: gravity must be in [{G_RANGE[0]:g}, "
                    f"{G_RANGE[1]:g}]")
    n = cal.n
    if not _is_int(n) or not N_RANGE[0] <= n <= N_RANGE[1]:
        raise _fail(path, "n", f"is {_short(n)}: the samples of a calibration run must be an "
                    f"integer in [{N_RANGE[0]}, {N_RANGE[1]:,}]")
    estimated = sigma2_source == "estimated"
    fits = [(f"calibration.fits.{a}", cal.fits[a]) for a in AXES]
    if cal.joint is not None:
        fits.append(("calibration.joint", cal.joint))
    elif cal.method != "ols":
        raise _fail(path, "calibration.joint", f"is null but a {cal.method} calibration has "
                    "its joint fit there")
    if cal.method == "ols" and cal.joint is not None:
        raise _fail(path, "calibration.joint", "must be null for an ols calibration")
    for field, f in fits:
        _check_fit(f, field, path)
        if (f.sigma2_source == "estimated") != estimated:
            raise _inconsistent(path, f"{field}.sigma2_source", f"is {f.sigma2_source!r} but "
                                f"the file's sigma2_source is {sigma2_source!r}")
        joint = f.residuals.ndim == 2
        m = f.residuals.shape[0]
        if cal.method == "multiposition":
            want_rows, want_dof = m, (2 if joint else 1) * (n - m)
            if m > n:
                raise _inconsistent(path, f"{field}.residuals", f"has {m} pose means for "
                                    f"n = {n} samples")
        else:
            want_rows, want_dof = n, (2 * n - 4) if joint else n - 2
            if "sigma2_dof" in f.extra and not f.extra["sigma2_dof"] < n:
                raise _inconsistent(path, f"{field}.extra.sigma2_dof", f"is "
                                    f"{f.extra['sigma2_dof']} for n = {n} samples (pure-error "
                                    "dof N − c < N)")
        if m != want_rows:
            raise _inconsistent(path, f"{field}.residuals", f"has {m} rows but n = {n}")
        if f.dof != want_dof:
            raise _inconsistent(path, f"{field}.dof", f"is {f.dof}, expected {want_dof} for "
                                f"n = {n}")
        if cal.method != "multiposition":  # its χ² adds the scatter within poses
            got = _chi2(f)
            if not _close(f.chi2, got):
                raise _inconsistent(path, f"{field}.chi2", f"is {f.chi2!r} but the residuals "
                                    f"and σ² give {got!r}")
        if estimated and cal.method == "ols" and "sigma2_dof" not in f.extra:
            got = float(f.residuals @ f.residuals / f.dof)
            if not _close(float(f.sigma2), got):
                raise _inconsistent(path, f"{field}.sigma2", f"is {float(f.sigma2)!r} but the "
                                    f"residuals give RSS/dof = {got!r}")
    if cal.joint is not None:
        for k, a in enumerate(AXES):
            sl, f = slice(2 * k, 2 * k + 2), cal.fits[a]
            for name, got, want in (("params", f.params, cal.joint.params[sl]),
                                    ("cov", f.cov, cal.joint.cov[sl, sl]),
                                    ("sigma2", f.sigma2, cal.joint.sigma2[k]),
                                    ("residuals", f.residuals, cal.joint.residuals[:, k])):
                if not np.array_equal(got, want):
                    raise _inconsistent(path, f"calibration.fits.{a}.{name}",
                                        "differs from its block of calibration.joint")


def _first_difference(got: Any, want: Any, where: str) -> str | None:
    """The dotted path of the first place ``got`` differs from ``want`` (exact), or None."""
    if isinstance(want, dict):
        if not isinstance(got, dict):
            return where
        for k in want:
            if k not in got:
                return f"{where}.{k}".lstrip(".")
            d = _first_difference(got[k], want[k], f"{where}.{k}".lstrip("."))
            if d is not None:
                return d
        extra = [k for k in got if k not in want]
        return f"{where}.{extra[0]}".lstrip(".") if extra else None
    if isinstance(want, list):
        if not isinstance(got, list) or len(got) != len(want):
            return where
        if (want and type(want[0]) is float and all(type(x) is float for x in got)
                and got == want):  # residuals: 20001 floats compared at C speed
            return None
        for i, (u, v) in enumerate(zip(got, want, strict=True)):
            d = _first_difference(u, v, f"{where}[{i}]")
            if d is not None:
                return d
        return None
    if isinstance(got, bool) != isinstance(want, bool) or isinstance(got, (list, dict)):
        return where
    if isinstance(want, float) and isinstance(got, (int, float)):
        return None if float(got) == want else where
    return None if got == want else where


@dataclass(frozen=True, eq=False)
class CalibrationFile:
    """A checked calibration file: the calibration and its provenance.

    Attributes
    ----------
    calibration : the :class:`Calibration` every command uses.
    sigma2_source : "given", "datos.txt" or "estimated".
    source : ``{"name", "sha256"}`` of the ensayo.mat the fit used, or None.
    noise_file : ``{"name", "sha256"}`` of the datos.txt σ² came from, or None.
    checksum : the SHA-256 of the defining fields (``checksum.value``).
    """

    calibration: Calibration
    sigma2_source: str
    source: dict | None
    noise_file: dict | None
    checksum: str


def calibration_file_from_document(doc: Any, path: Any = "<memory>") -> CalibrationFile:
    """Check a calibration-file object completely and rebuild its calibration (exact).

    In order: the header (``format``, ``format_version``), every required field present and
    no unknown one; the defining fields' types and shapes; :func:`check_calibration`; every
    derived field equal to its re-derivation; the ``checksum`` of the defining fields.

    Raises
    ------
    DataError : one line naming the file and the field; an edited file says
        "checksum/consistency failed" and to re-run ``calibrate --save``.
    """
    if not isinstance(doc, dict):
        raise DataError(f"{path}: not a calibration file (expected a JSON object with "
                        f"'format': '{FORMAT}')")
    if "format" not in doc:
        raise _fail(path, "format", f"missing: not a {FORMAT} file (a calibrate --json "
                    "output? write the file with calibrate --save)")
    if doc["format"] != FORMAT:
        raise _fail(path, "format", f"is {_short(doc['format'])}, expected {FORMAT!r}")
    if "format_version" not in doc:
        raise _fail(path, "format_version", "missing")
    version = doc["format_version"]
    if version != FORMAT_VERSION or not _is_int(version):
        old = _is_int(version) and 1 <= version < FORMAT_VERSION
        raise _fail(path, "format_version", f"is {_short(version)}; this tiltbench reads "
                    f"version {FORMAT_VERSION} only ("
                    + ("an older file without a checksum: " if old else
                       "written by a newer tiltbench? upgrade, or ") + f"{_RERUN})")
    for key in _REQUIRED:
        if key not in doc:
            raise _fail(path, key, f"missing; {_RERUN}")
    unknown = [k for k in doc if k not in _REQUIRED and k not in COSMETIC_FIELDS]
    if unknown:
        raise _fail(path, unknown[0], f"is not part of format version {FORMAT_VERSION} "
                    f"(the file was edited?); {_RERUN}")
    if doc["method"] not in METHODS:
        raise _fail(path, "method", f"is {_short(doc['method'])}, expected one of "
                    f"{', '.join(METHODS)}")
    if doc["sigma2_source"] not in SIGMA2_SOURCES:
        raise _fail(path, "sigma2_source", f"is {_short(doc['sigma2_source'])}, expected one "
                    f"of {', '.join(SIGMA2_SOURCES)}")
    g = _number(doc["g"], "g", path)
    if not _is_int(doc["n"]):
        raise _fail(path, "n", f"must be an integer (samples), got {_short(doc['n'])}")
    _ref(doc, "source", path)
    _ref(doc, "noise_file", path)
    state = doc["calibration"]
    if not isinstance(state, dict):
        raise _fail(path, "calibration", "must be an object (Calibration.to_state())")
    for key in ("fits", "joint"):
        if key not in state:
            raise _fail(path, f"calibration.{key}", f"missing; {_RERUN}")
    if not isinstance(state["fits"], dict):
        raise _fail(path, "calibration.fits", "must be an object with fits 'x' and 'y'")
    fits = {a: _fit_from(state["fits"].get(a), f"calibration.fits.{a}", PARAM_NAMES, path)
            for a in AXES}
    joint = (None if state["joint"] is None else
             _fit_from(state["joint"], "calibration.joint", JOINT_PARAM_NAMES, path))
    lof = state.get("lack_of_fit")
    if lof is not None:
        if not isinstance(lof, dict) or set(lof) != set(AXES):
            raise _fail(path, "calibration.lack_of_fit", "must be null or the tests of axes "
                        f"{' and '.join(AXES)}")
        try:
            lof = {str(a): LackOfFit.from_dict(v) for a, v in lof.items()}
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as exc:
            raise _fail(path, "calibration.lack_of_fit", f"is malformed ({exc})") from None
    cal = Calibration(doc["method"], g, fits, doc["n"], joint, lof)
    check_calibration(cal, doc["sigma2_source"], path)
    try:
        want = json.loads(json.dumps(_document(cal, doc["source"], doc["sigma2_source"],
                                               doc["noise_file"], doc.get("tool"), False),
                                     default=_plain))
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        # a defining field that passed the checks yet does not re-serialise (a malformed
        # lack-of-fit test): the file is not one this tiltbench wrote
        raise _fail(path, "calibration", f"is malformed ({exc}); {_RERUN}") from None
    stored = doc["checksum"]
    for key in ("checksum", *COSMETIC_FIELDS):
        want.pop(key, None)
    field = _first_difference({k: v for k, v in doc.items() if k in want}, want, "")
    if field is not None:
        raise DataError(f"{path}: checksum/consistency failed: '{field}' is "
                        f"{_short(_at(doc, field))}, not the {_short(_at(want, field))} "
                        f"derived from the calibration (the file was edited); {_RERUN}")
    value = defining_checksum(doc)
    if (not isinstance(stored, dict) or stored.get("algorithm") != "sha256"
            or stored.get("covers") != list(CHECKSUM_FIELDS) or stored.get("value") != value
            or set(stored) != {"algorithm", "covers", "value"}):
        raise DataError(f"{path}: checksum/consistency failed: 'checksum' does not match the "
                        f"fields it covers ({', '.join(CHECKSUM_FIELDS)}): the file was "
                        f"edited; {_RERUN}")
    return CalibrationFile(cal, doc["sigma2_source"], doc["source"], doc["noise_file"], value)


def _at(doc: Any, dotted: str) -> Any:
    """The value at a path of :func:`_first_difference` (``a.b[3].c``), or ``<missing>``."""
    import re

    out = doc
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", dotted):
        try:
            out = out[int(part[1:-1])] if part.startswith("[") else out[part]
        except (KeyError, IndexError, TypeError):
            return "<missing>"
    return out


def calibration_from_document(doc: Any, path: Any = "<memory>") -> Calibration:
    """The :class:`Calibration` of a checked calibration-file object
    (:func:`calibration_file_from_document`)."""
    return calibration_file_from_document(doc, path).calibration


def _read_json_document(path: Path) -> Any:
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a JSON calibration file (not UTF-8 text: {exc.reason} "
                        f"at byte {exc.start}); {_RERUN}") from None
    if not text.strip():
        raise DataError(f"{path}: empty file, not a calibration file; {_RERUN}")
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise DataError(f"{path}: not a JSON calibration file ({str(exc)[:80]}); "
                        f"{_RERUN}") from None


def read_calibration_document(path: str | os.PathLike) -> dict:
    """The JSON object of a calibration file (``.json``, or the ``document`` of a ``.mat``),
    after the complete check of :func:`load_calibration_file`."""
    return _read(Path(path))[1]


def _read(path: Path) -> tuple[CalibrationFile, dict]:
    check_file(path, "a calibration file (cal.json)", "calibration file")
    if path.suffix.lower() == ".mat":
        return _read_mat_document(path)
    doc = _read_json_document(path)
    return calibration_file_from_document(doc, path), doc


def _mat_text(mat: dict, key: str, path) -> str:
    v = mat.get(key)
    if v is None:
        raise _fail(path, key, "missing (not a tiltbench calibration .mat: write one with "
                    "calibrate --save cal.mat)")
    arr = np.asarray(v)
    if arr.dtype.kind != "U" or arr.size > 1:
        raise _fail(path, key, "must be a char row")
    return str(arr.reshape(-1)[0]) if arr.size else ""


def _mat_equal(got: Any, want: Any) -> bool:
    """A loaded ``.mat`` variable against the one :func:`mat_variables` derives."""
    if isinstance(want, str):
        arr = np.asarray(got)
        if arr.dtype.kind != "U" or arr.size > 1:
            return False
        return (str(arr.reshape(-1)[0]) if arr.size else "") == want
    arr = np.asarray(got)
    if arr.dtype.kind not in "fiu":
        return False
    w = np.atleast_2d(np.asarray(want, float))
    return arr.shape == w.shape and np.array_equal(arr.astype(float), w)


def _read_mat_document(path: Path) -> tuple[CalibrationFile, dict]:
    """The calibration-file object stored in a ``.mat`` export, checked like the JSON file;
    every plain variable but ``tool_version`` must equal the one derived from it."""
    import scipy.io

    if path.stat().st_size == 0:
        raise DataError(f"{path}: empty file, not a MATLAB .mat calibration file; {_RERUN}")
    try:
        mat = scipy.io.loadmat(path)
    # scipy's MAT reader raises many types on damaged bytes (MatReadError, ValueError,
    # struct.error, zlib.error, EOFError, UnicodeDecodeError …); any of them means "not a
    # .mat this program wrote", which is one line for the user, never a traceback
    except Exception as exc:  # noqa: BLE001
        raise DataError(f"{path}: not a MATLAB .mat calibration file "
                        f"({type(exc).__name__}: {str(exc)[:80]}); {_RERUN}") from None
    fmt = _mat_text(mat, "format", path)
    if fmt != FORMAT:
        raise _fail(path, "format", f"is {_short(fmt)}, expected {FORMAT!r}")
    if "format_version" not in mat:
        raise _fail(path, "format_version", "missing")
    fv = np.asarray(mat["format_version"])
    fv = fv.astype(float).reshape(-1) if fv.dtype.kind in "fiu" else np.array([np.nan])
    version = int(fv[0]) if fv.size == 1 and float(fv[0]).is_integer() else fv.tolist()
    if version != FORMAT_VERSION:
        old = isinstance(version, int) and 1 <= version < FORMAT_VERSION
        raise _fail(path, "format_version", f"is {_short(version)}; this tiltbench reads "
                    f"version {FORMAT_VERSION} only ("
                    + ("an older file without a checksum: " if old else
                       "written by a newer tiltbench? upgrade, or ") + f"{_RERUN})")
    try:
        doc = json.loads(_mat_text(mat, "document", path))
    except (ValueError, RecursionError) as exc:
        raise _fail(path, "document", f"is not the JSON calibration object ({str(exc)[:80]})"
                    f"; {_RERUN}") from None
    checked = calibration_file_from_document(doc, path)
    want = mat_variables(doc)
    names = [k for k in mat if not k.startswith("__")]
    for key in names:
        if key not in want:
            raise _fail(path, key, f"is not a variable of the export (the file was edited?); "
                        f"{_RERUN}")
    for key, value in want.items():
        if key in _MAT_COSMETIC or key == "document":  # the source itself, checked above
            continue
        if key not in mat:
            raise _fail(path, key, f"missing; {_RERUN}")
        if not _mat_equal(mat[key], value):
            raise DataError(f"{path}: checksum/consistency failed: '{key}' differs from the "
                            f"'document' variable (the file was edited); {_RERUN}")
    return checked, doc


def load_calibration_file(path: str | os.PathLike) -> CalibrationFile:
    """Read and check a calibration file: the one reader of every command.

    Parameters
    ----------
    path : a ``.json`` calibration file or its ``.mat`` export.

    Returns
    -------
    CalibrationFile : the calibration (equal, ``==``, to the one saved) and its provenance.

    Raises
    ------
    DataError : file missing, empty, not JSON (or not a ``.mat`` export), another format, an
        unknown ``format_version``, a missing, malformed or implausible field, a derived
        field that differs from its re-derivation or a checksum that does not match (one
        line: the file and the field).
    """
    return _read(Path(path))[0]


def load_calibration(path: str | os.PathLike) -> Calibration:
    """The :class:`Calibration` of a calibration file, equal (``==``) to the one saved:
    ``load_calibration_file(path).calibration``.

    Parameters
    ----------
    path : as :func:`load_calibration_file`, which says what raises :class:`DataError`.

    Examples
    --------
    A calibration saved (:func:`save_calibration`) as JSON and as ``.mat``, and read back:

    >>> import numpy as np, tempfile, pathlib
    >>> from calib import Ensayo, calibrate
    >>> th = np.linspace(0, 2 * np.pi, 100)
    >>> cal = calibrate(Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    ...                        + 0.05), noise_var=[0.25, 0.64])
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> [load_calibration(save_calibration(d / name, cal, sigma2_source="given")) == cal
    ...  for name in ("cal.json", "cal.mat")]
    [True, True]
    """
    return load_calibration_file(path).calibration


__all__ = ["CHECKSUM_FIELDS", "COSMETIC_FIELDS", "DEFINING_FIELDS", "FILE_UNITS", "FORMAT",
           "FORMAT_VERSION", "G_RANGE", "GAIN_RANGE", "MAX_ABS_BIAS", "N_RANGE",
           "SIGMA2_RANGE", "SIGMA2_SOURCES", "CalibrationFile", "calibration_document",
           "calibration_file_from_document", "calibration_from_document", "check_calibration",
           "defining_checksum", "file_sha256", "load_calibration", "load_calibration_file",
           "mat_variables", "read_calibration_document", "save_calibration",
           "save_calibration_mat"]
