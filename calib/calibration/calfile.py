"""The calibration file: a calibration that travels (``cal.json``, and its ``.mat`` export).

``tiltbench calibrate LOG --save cal.json`` writes it; ``trajectory``, ``nmin``, ``fuse``,
``validate`` and ``apply`` read it with ``--calibration cal.json`` instead of re-fitting, all
through :func:`load_calibration_file` (one reader, one set of checks), and each refuses a file
that does not apply to its log (:func:`check_applies`). The format is documented in
``docs/calibration-file.md``; in short, one JSON object (version 3, the tilt plane)::

    format           "tiltbench-calibration"          (FORMAT)
    format_version   3                                (FORMAT_VERSION; 2 still read)
    tool             {"name": "tiltbench", "version": "0.1.0"}   (cosmetic: never checked)
    method, g        "ols" | "wls" | "multiposition", m/s²
    gravity          {"source": "given" | "latitude" | "assumed", "latitude" deg, "height" m}
    n                samples of the calibration run
    sigma2           [σx², σy²] (m/s²)²;  sigma2_source "given" | "datos.txt" | "estimated"
    noise_file       {"name", "sha256"} of the datos.txt the σ² came from, or null
    source           {"name", "sha256"} of the ensayo.mat or log the fit used
    readings         {"axes": ["-y", "z"], "unit": "g", "sensitivity_counts_per_g",
                      "to_m_s2"}: the log's readings the calibration corrects
    sensor_axes      {"x": "-y", "y": "z"}: the log's signed axis of each calibrated axis
    param_names      ["bias_x", "scale_x", "bias_y", "scale_y"]
    params, std      (4,) m/s², 1, m/s², 1;   cov (4, 4), products of those units
    units            key path → unit of every number (docs/units.md)
    checksum         {"algorithm": "sha256", "covers": CHECKSUM_FIELDS, "value": hex}
    calibration      Calibration.to_state(): the exact rebuild (residuals included)

A six-face calibration of three axes (``"method": "six-face"``: bias, scale and misalignment,
the poses, the hold-to-hold variance) is a version-3 file of its own layout
(:mod:`calib.calibration.calfile_sixface`). A version-2 file has no ``gravity``, ``readings``
or ``sensor_axes``: it means the course's axes x, y in m/s² (:data:`~calib.calibration.
readings.COURSE_READINGS`).

**One calibration, stored once.** The estimate is *defined* by the fields the calibration is
rebuilt from (:data:`DEFINING_FIELDS`: ``method``, ``g``, ``gravity``, ``n``, ``readings``
and ``calibration.fits`` / ``joint`` / ``lack_of_fit``, plus the provenance
``sigma2_source``, ``source``, ``noise_file``). Every other readable number — ``params``,
``std``, ``cov``, ``sigma2``, ``units``, ``sensor_axes`` at the top, the ``calibrate --json``
block ``calibration.axes``, each fit's ``std`` and ``chi2_dof``, and for WLS / multi-position
the per-axis ``fits`` (blocks of ``joint``) — is *derived*: on load it is re-derived from the
rebuilt calibration and must be equal, exactly (floats are written with ``repr``, the shortest
round trip). The defining fields carry a SHA-256 of their canonical JSON
(:func:`defining_checksum`), so a hand edit that keeps the copies consistent is refused too.
Every check names the file and the field and asks to re-run ``calibrate --save``; a file that
passes gives ``load_calibration_file(path).calibration == cal``.

Before the consistency and checksum checks, the loader checks what the numbers must be for any
command to use them (:func:`check_calibration`): shapes, finite values, ``n`` an integer in
:data:`N_RANGE` and equal to the residual count, σ² > 0 within :data:`SIGMA2_RANGE` and equal
to what the residuals give, symmetric positive definite covariances with |ρ| ≤ 1, a plausible
g (:data:`G_RANGE`) that its source gives, bias and gain within :data:`MAX_ABS_BIAS` /
:data:`GAIN_RANGE`. :func:`save_calibration` runs the same checks and writes nothing when they
fail.

Version 1 files (no checksum) are refused with a one-line "re-run calibrate --save": a
self-consistent hand edit of a version-1 file cannot be told from an original.

The ``.mat`` export (:func:`save_calibration_mat`) holds the same numbers as plain double
variables and the text fields as char, for MATLAB/Octave, plus the whole JSON object as one
char variable ``document``: :func:`load_calibration_file` reads a ``.mat`` back from it exactly
as the ``.json`` (same checks) and checks that every plain variable equals the one derived
from it (only ``tool_version`` is cosmetic).
"""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from calib.calibration.calfile_fields import (
    CORRELATION_EIG_MIN,
    FORMAT,
    FORMAT_VERSION,
    G_RANGE,
    GAIN_RANGE,
    MAX_ABS_BIAS,
    N_RANGE,
    READ_VERSIONS,
    RELATIVE_TOLERANCE,
    RERUN,
    SIGMA2_RANGE,
    array,
    canonical_checksum,
    check_checksum,
    check_cov,
    check_derived,
    check_ref,
    checksum_entry,
    close,
    document_json,
    fail,
    file_ref,
    file_sha256,
    inconsistent,
    is_int,
    number,
    plain,
    short,
)
from calib.calibration.calfile_sixface import DEFINING_FIELDS as SIX_FACE_FIELDS
from calib.calibration.calfile_sixface import METHOD as SIX_FACE
from calib.calibration.calfile_sixface import (
    six_face_document,
    six_face_from_document,
    six_face_mat_variables,
)
from calib.calibration.lackoffit import LackOfFit
from calib.calibration.ls import FitResult
from calib.calibration.multiposition import Poses
from calib.calibration.readings import (
    COURSE_READINGS,
    GRAVITY_UNITS,
    READINGS_UNITS,
    GravitySource,
    LogReadings,
    gravity_from_document,
    readings_from_document,
    readings_of,
)
from calib.calibration.sixface import SixFaceFit
from calib.calibration.tilt_plane import METHODS, Calibration
from calib.conventions import AXES, JOINT_PARAM_NAMES, PARAM_NAMES
from calib.files.atomic import write_bytes, write_text
from calib.input_rules import DataError, check_file
from calib.logs.reader import ImuLog
from calib.units import nest

SIGMA2_SOURCES = ("given", "datos.txt", "estimated")
"""Where σ² came from: ``--noise-var``, the course ``datos.txt``, or the fit's residuals."""
KINDS = ("tilt-plane", "six-face")
"""What a calibration file holds: bias and scale of the tilt plane's two axes, or bias, scale
and misalignment of three axes (``"method": "six-face"``)."""

DEFINING_FIELDS_V2 = ("format", "format_version", "method", "g", "n", "sigma2_source",
                      "noise_file", "source", "calibration.fits", "calibration.joint",
                      "calibration.lack_of_fit")
"""The defining fields of a version-2 file (the checksum of a version-2 file covers these)."""
DEFINING_FIELDS = (*DEFINING_FIELDS_V2[:4], "gravity", *DEFINING_FIELDS_V2[4:8], "readings",
                   *DEFINING_FIELDS_V2[8:])
"""The fields a tilt-plane calibration of version 3 is rebuilt from; its ``checksum`` covers
exactly these (a six-face file: :data:`calib.calibration.calfile_sixface.DEFINING_FIELDS`)."""
CHECKSUM_FIELDS = DEFINING_FIELDS
"""The ``checksum.covers`` list of every version-3 tilt-plane file."""
COSMETIC_FIELDS = ("tool",)
"""Fields never checked nor used: editing them changes no number any command prints."""

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

FILE_UNITS_V2 = {  # the "units" object of a version-2 calibration file (docs/units.md)
    "format_version": "—", "g": "m/s²", "n": "count", "sigma2": "(m/s²)²",
    "params": _PARAM_UNITS, "std": _PARAM_UNITS, "cov": _COV4_UNITS,
    **nest("calibration", Calibration._JSON_UNITS),
    **nest("calibration.fits.*", _FIT_UNITS),
    **nest("calibration.joint", _JOINT_UNITS),
}
FILE_UNITS = {**FILE_UNITS_V2, **GRAVITY_UNITS, **READINGS_UNITS}
"""The ``units`` object of a version-3 tilt-plane file (docs/units.md), before the units of
the calibration's optional keys (:meth:`Calibration.state_units`)."""

_REQUIRED_V2 = ("format", "format_version", "method", "g", "n", "sigma2", "sigma2_source",
                "noise_file", "source", "param_names", "params", "std", "cov", "units",
                "checksum", "calibration")
_REQUIRED = ("format", "format_version", "method", "g", "gravity", "n", "sigma2",
             "sigma2_source", "noise_file", "source", "readings", "sensor_axes", "param_names",
             "params", "std", "cov", "units", "checksum", "calibration")


def defining_checksum(doc: dict) -> str:
    """SHA-256 (hex) of the canonical JSON of the defining fields of ``doc`` (those of its
    version and kind: :data:`DEFINING_FIELDS`, :data:`DEFINING_FIELDS_V2`, or the six-face
    ones).

    Canonical: ``{dotted field: value}``, keys sorted, no spaces, floats in ``repr`` (the
    shortest round trip), so the same numbers give the same hash whether ``doc`` was just
    built or read back from the file."""
    return canonical_checksum(doc, _checksum_fields(doc))


def _checksum_fields(doc: dict) -> tuple[str, ...]:
    if doc.get("format_version") == 2:
        return DEFINING_FIELDS_V2
    return SIX_FACE_FIELDS if doc.get("method") == SIX_FACE else DEFINING_FIELDS


def _document(cal: Calibration, source: dict | None, sigma2_source: str,
              noise_file: dict | None, tool: Any, checksum: bool = True, *,
              readings: LogReadings | None = COURSE_READINGS,
              gravity: GravitySource | None = None) -> dict:
    """The calibration-file object of ``cal`` given its provenance (references, not paths):
    what :func:`calibration_document` writes and what the loader re-derives to compare.
    ``gravity`` None: a version-2 object (no ``gravity``, ``readings``, ``sensor_axes``)."""
    v3 = gravity is not None
    doc: dict[str, Any] = {
        "format": FORMAT, "format_version": FORMAT_VERSION if v3 else 2, "tool": tool,
        "method": cal.method, "g": cal.g}
    if v3:
        doc["gravity"] = gravity.to_dict()
    doc.update({
        "n": cal.n, "sigma2": [cal.fits[a].sigma2.item() for a in AXES],
        "sigma2_source": sigma2_source, "noise_file": noise_file, "source": source})
    if v3:
        doc["readings"] = readings.to_dict()
        doc["sensor_axes"] = dict(zip(AXES, readings.axes, strict=True))
    doc.update({
        "param_names": list(JOINT_PARAM_NAMES), "params": cal.params.tolist(),
        "std": cal.std.tolist(), "cov": cal.cov.tolist(),
        "units": {**(FILE_UNITS if v3 else FILE_UNITS_V2),
                  **nest("calibration", cal.state_units())},
        "checksum": None,
        "calibration": cal.to_state(),
    })
    if checksum:  # the reader compares the checksum with the file's own fields instead
        doc["checksum"] = checksum_entry(doc, _checksum_fields(doc))
    return doc


def calibration_document(cal: Calibration | SixFaceFit, source: str | os.PathLike | None,
                         sigma2_source: str = "estimated",
                         noise_file: str | os.PathLike | None = None,
                         tool_version: str = "unknown", *,
                         readings: LogReadings | None = None,
                         gravity: GravitySource | None = None,
                         poses: Poses | None = None) -> dict:
    """The calibration-file object (module docstring) of ``cal``, format version 3.

    Parameters
    ----------
    cal : the calibration: a tilt-plane :class:`Calibration`, or a
        :class:`~calib.calibration.sixface.SixFaceFit` of three axes.
    source : the ensayo.mat or log it was fitted on (name and SHA-256 are recorded), or None.
    sigma2_source : where σ² came from, one of :data:`SIGMA2_SOURCES` (a six-face fit
        estimates its own: ``"estimated"``).
    noise_file : the datos.txt σ² was read from (name and SHA-256), or None.
    tool_version : the version of the program writing the file (``calib`` does not know it).
    readings : the log's readings it corrects (:func:`calib.calibration.readings.readings_of`
        of the log); None: the course's axes x, y in m/s².
    gravity : where ``cal.g`` came from; None: ``"given"``.
    poses : the holds a six-face fit was made from (their means go into the file); needed
        for a six-face fit, refused otherwise.
    """
    if sigma2_source not in SIGMA2_SOURCES:
        raise ValueError(f"sigma2_source must be one of {SIGMA2_SOURCES}, got {sigma2_source!r}")
    readings = COURSE_READINGS if readings is None else readings
    gravity = GravitySource("given") if gravity is None else gravity
    tool = {"name": "tiltbench", "version": str(tool_version)}
    if isinstance(cal, SixFaceFit):
        if poses is None:
            raise ValueError("a six-face calibration is saved with its holds (poses=)")
        if sigma2_source != "estimated" or noise_file is not None:
            raise ValueError("a six-face fit estimates its noise within the holds: "
                             "sigma2_source 'estimated', no noise_file")
        return six_face_document(cal, poses.means, file_ref(source), readings, gravity, tool)
    if poses is not None:
        raise ValueError("poses= is for a six-face fit; a tilt-plane calibration holds its own "
                         "residuals")
    return _document(cal, file_ref(source), sigma2_source, file_ref(noise_file), tool,
                     readings=readings, gravity=gravity)


def save_calibration(path: str | os.PathLike, cal: Calibration | SixFaceFit,
                     source: str | os.PathLike | None = None, sigma2_source: str = "estimated",
                     noise_file: str | os.PathLike | None = None,
                     tool_version: str = "unknown", force: bool = False, *,
                     readings: LogReadings | None = None,
                     gravity: GravitySource | None = None,
                     poses: Poses | None = None) -> Path:
    """Write ``cal`` as a calibration file (format version 3), atomically
    (:func:`calib.files.atomic.write_text`).

    ``.mat`` in the name writes the MATLAB/Octave export (:func:`save_calibration_mat`),
    anything else the JSON file. An existing file is refused (``FileExistsError``) unless
    ``force``. Parameters as :func:`calibration_document`. A calibration the loader would
    refuse (:func:`check_calibration`: σ² = 0 from noiseless data, a gain near 0, …) raises
    :class:`DataError` and nothing is written.

    Examples
    --------
    Saved and read back, as JSON and as ``.mat``: :func:`load_calibration`.
    """
    doc = calibration_document(cal, source, sigma2_source, noise_file, tool_version,
                               readings=readings, gravity=gravity, poses=poses)
    # the document goes through JSON before the check, as the reader will see it
    calibration_file_from_document(json.loads(document_json(doc)), f"{path} (not written)")
    if Path(path).suffix.lower() == ".mat":
        return save_calibration_mat(path, doc, force=force)
    return write_text(path, document_json(doc), force=force)


def mat_variables(doc: dict) -> dict[str, Any]:
    """The variables of the ``.mat`` export of a calibration-file object: numbers as double
    arrays, text as char (no structs or cells: every MATLAB and Octave reads them); NaN
    where the JSON has null."""
    if doc.get("method") == SIX_FACE:
        out = six_face_mat_variables(doc)
        out["document"] = document_json(doc)
        return out
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
        "document": document_json(doc),
    }
    if doc["format_version"] != 2:
        gravity, readings = doc["gravity"], doc["readings"]
        sens = readings["sensitivity_counts_per_g"]
        out.update({
            "gravity_source": gravity["source"],
            "latitude": np.nan if gravity["latitude"] is None else float(gravity["latitude"]),
            "height": np.nan if gravity["height"] is None else float(gravity["height"]),
            "axes": ",".join(readings["axes"]), "unit": readings["unit"],
            "sensitivity": np.nan if sens is None else float(sens),
            "to_m_s2": float(readings["to_m_s2"]),
            "units": out["units"] + "; latitude deg; height m",
        })
    return out


_MAT_COSMETIC = ("tool_version",)


def save_calibration_mat(path: str | os.PathLike, doc: dict, force: bool = False) -> Path:
    """Write the ``.mat`` export of a calibration-file object (MATLAB v5, atomically)."""
    import scipy.io

    buf = io.BytesIO()
    scipy.io.savemat(buf, mat_variables(doc), format="5", oned_as="row")
    return write_bytes(path, buf.getvalue(), force=force)


# ------------------------------------------------------------------ reading
def _fit_from(d: Any, field: str, names: tuple[str, ...], path) -> FitResult:
    """One fit of the state (``FitResult.to_dict()``), its types and shapes checked."""
    if not isinstance(d, dict):
        raise fail(path, field, f"must be an object (FitResult.to_dict()), got {short(d)}")
    for key in ("param_names", "params", "cov", "residuals", "sigma2", "sigma2_source", "dof",
                "rank", "cond", "chi2", "extra"):
        if key not in d:
            raise fail(path, f"{field}.{key}", "missing")
    p, joint = len(names), len(names) == 4
    if d["param_names"] != list(names):
        raise fail(path, f"{field}.param_names", f"must be {list(names)}")
    array(d["params"], f"{field}.params", (p,), path)
    array(d["cov"], f"{field}.cov", (p, p), path)
    array(d["residuals"], f"{field}.residuals", (None, 2) if joint else (None,), path)
    array(d["sigma2"], f"{field}.sigma2", (2,) if joint else (), path)
    if d["sigma2_source"] not in ("given", "estimated"):
        raise fail(path, f"{field}.sigma2_source", "must be 'given' or 'estimated', got "
                    f"{short(d['sigma2_source'])}")
    for key in ("dof", "rank"):
        if not is_int(d[key]) or d[key] < 1:
            raise fail(path, f"{field}.{key}", f"must be a positive integer, got "
                        f"{short(d[key])}")
    number(d["cond"], f"{field}.cond", path)
    if number(d["chi2"], f"{field}.chi2", path) < 0:
        raise fail(path, f"{field}.chi2", f"must not be negative, got {d['chi2']!r}")
    if not isinstance(d["extra"], dict):
        raise fail(path, f"{field}.extra", "must be an object")
    if "sigma2_dof" in d["extra"] and (not is_int(d["extra"]["sigma2_dof"])
                                       or d["extra"]["sigma2_dof"] < 1):
        raise fail(path, f"{field}.extra.sigma2_dof", "must be a positive integer")
    if "noise_cov" in d["extra"]:
        array(d["extra"]["noise_cov"], f"{field}.extra.noise_cov", (2, 2), path)
    try:
        return FitResult.from_dict(d)
    except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise fail(path, field, f"is malformed ({exc})") from None


def _check_fit(f: FitResult, field: str, path) -> None:
    """The numbers of one fit: variances, covariance, bias and gain, χ² against residuals."""
    for k, s2 in enumerate(np.atleast_1d(f.sigma2).tolist()):
        if not SIGMA2_RANGE[0] <= s2 <= SIGMA2_RANGE[1]:
            raise fail(path, f"{field}.sigma2", f"is {s2!r}: a noise variance must be in "
                        f"[{SIGMA2_RANGE[0]:g}, {SIGMA2_RANGE[1]:g}] (m/s²)²"
                        + (f" (axis {AXES[k]})" if f.sigma2.ndim else ""))
    check_cov(f.cov, f.param_names, f"{field}.cov", path)
    for k, name in enumerate(f.param_names):
        v = float(f.params[k])
        if name.startswith("bias") and abs(v) > MAX_ABS_BIAS:
            raise fail(path, f"{field}.params", f"has {name} = {v!r} m/s² (|bias| at most "
                        f"{MAX_ABS_BIAS:g})")
        if name.startswith("scale") and not GAIN_RANGE[0] <= 1 + v <= GAIN_RANGE[1]:
            raise fail(path, f"{field}.params", f"has {name} = {v!r}: the gain 1 + scale "
                        f"must be in [{GAIN_RANGE[0]:g}, {GAIN_RANGE[1]:g}]")
    if "noise_cov" in f.extra:
        check_cov(np.asarray(f.extra["noise_cov"], float), ("x", "y"),
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
    symmetric, positive definite, |ρ| ≤ 1 (:func:`calib.calibration.calfile_fields.
    check_cov`); |bias| ≤ :data:`MAX_ABS_BIAS`, gain in :data:`GAIN_RANGE`; g in
    :data:`G_RANGE`. Against each other: for ``ols``/``wls`` each axis has N residuals and
    N − 2 dof (the joint fit N × 2 and 2N − 4), for ``multiposition`` N = dof + P (P pose
    means); ``χ² = Σ r²/σ²`` (joint: ``Σ ‖L⁻¹r‖²``, C = LLᵀ) to :data:`RELATIVE_TOLERANCE`;
    an OLS σ² estimated from the residuals equals ``RSS/dof``; a pure-error σ² has
    ``sigma2_dof`` < N (its value comes from the scatter of the readings within poses, which
    the file does not hold: the checksum guards it); the per-axis fits of a joint fit are its
    blocks (equal, exactly).

    Raises
    ------
    DataError : one line, ``{path}: field '<field>' <what is wrong>``.
    """
    if not G_RANGE[0] <= cal.g <= G_RANGE[1]:
        raise fail(path, "g", f"is {cal.g!r} m/s²: gravity must be in [{G_RANGE[0]:g}, "
                    f"{G_RANGE[1]:g}]")
    n = cal.n
    if not is_int(n) or not N_RANGE[0] <= n <= N_RANGE[1]:
        raise fail(path, "n", f"is {short(n)}: the samples of a calibration run must be an "
                    f"integer in [{N_RANGE[0]}, {N_RANGE[1]:,}]")
    estimated = sigma2_source == "estimated"
    fits = [(f"calibration.fits.{a}", cal.fits[a]) for a in AXES]
    if cal.joint is not None:
        fits.append(("calibration.joint", cal.joint))
    elif cal.method != "ols":
        raise fail(path, "calibration.joint", f"is null but a {cal.method} calibration has "
                    "its joint fit there")
    if cal.method == "ols" and cal.joint is not None:
        raise fail(path, "calibration.joint", "must be null for an ols calibration")
    for field, f in fits:
        _check_fit(f, field, path)
        if (f.sigma2_source == "estimated") != estimated:
            raise inconsistent(path, f"{field}.sigma2_source", f"is {f.sigma2_source!r} but "
                                f"the file's sigma2_source is {sigma2_source!r}")
        joint = f.residuals.ndim == 2
        m = f.residuals.shape[0]
        if cal.method == "multiposition":
            want_rows, want_dof = m, (2 if joint else 1) * (n - m)
            if m > n:
                raise inconsistent(path, f"{field}.residuals", f"has {m} pose means for "
                                    f"n = {n} samples")
        else:
            want_rows, want_dof = n, (2 * n - 4) if joint else n - 2
            if "sigma2_dof" in f.extra and not f.extra["sigma2_dof"] < n:
                raise inconsistent(path, f"{field}.extra.sigma2_dof", f"is "
                                    f"{f.extra['sigma2_dof']} for n = {n} samples (pure-error "
                                    "dof N − c < N)")
        if m != want_rows:
            raise inconsistent(path, f"{field}.residuals", f"has {m} rows but n = {n}")
        if f.dof != want_dof:
            raise inconsistent(path, f"{field}.dof", f"is {f.dof}, expected {want_dof} for "
                                f"n = {n}")
        if cal.method != "multiposition":  # its χ² adds the scatter within poses
            got = _chi2(f)
            if not close(f.chi2, got):
                raise inconsistent(path, f"{field}.chi2", f"is {f.chi2!r} but the residuals "
                                    f"and σ² give {got!r}")
        if estimated and cal.method == "ols" and "sigma2_dof" not in f.extra:
            got = float(f.residuals @ f.residuals / f.dof)
            if not close(float(f.sigma2), got):
                raise inconsistent(path, f"{field}.sigma2", f"is {float(f.sigma2)!r} but the "
                                    f"residuals give RSS/dof = {got!r}")
    if cal.joint is not None:
        for k, a in enumerate(AXES):
            sl, f = slice(2 * k, 2 * k + 2), cal.fits[a]
            for name, got, want in (("params", f.params, cal.joint.params[sl]),
                                    ("cov", f.cov, cal.joint.cov[sl, sl]),
                                    ("sigma2", f.sigma2, cal.joint.sigma2[k]),
                                    ("residuals", f.residuals, cal.joint.residuals[:, k])):
                if not np.array_equal(got, want):
                    raise inconsistent(path, f"calibration.fits.{a}.{name}",
                                        "differs from its block of calibration.joint")


@dataclass(frozen=True, eq=False)
class CalibrationFile:
    """A checked calibration file: the calibration, its provenance and what it applies to.

    Attributes
    ----------
    calibration : the tilt-plane :class:`Calibration` every command uses, or the
        :class:`~calib.calibration.sixface.SixFaceFit` of a six-face file.
    sigma2_source : "given", "datos.txt" or "estimated" (six-face: "estimated").
    source : ``{"name", "sha256"}`` of the ensayo.mat or log the fit used, or None.
    noise_file : ``{"name", "sha256"}`` of the datos.txt σ² came from, or None.
    checksum : the SHA-256 of the defining fields (``checksum.value``).
    readings : the log's readings the calibration corrects (version 2: the course's axes
        x, y in m/s²).
    gravity : where g came from, or None (version 2 did not say).
    version : the file's ``format_version``.
    path : the file, for messages.
    hold_means : (H, 3) m/s², the hold means of a six-face fit, else None.
    """

    calibration: Calibration | SixFaceFit
    sigma2_source: str
    source: dict | None
    noise_file: dict | None
    checksum: str
    readings: LogReadings = COURSE_READINGS
    gravity: GravitySource | None = None
    version: int = FORMAT_VERSION
    path: str = "<memory>"
    hold_means: np.ndarray | None = None

    @property
    def kind(self) -> str:
        """``"six-face"`` (three axes, misalignment) or ``"tilt-plane"`` (:data:`KINDS`)."""
        return "six-face" if isinstance(self.calibration, SixFaceFit) else "tilt-plane"

    @property
    def log_axes(self) -> tuple[str, ...]:
        """The log's signed axis of each calibrated axis (x, y; six-face also z)."""
        return self.readings.log_axes(three=self.kind == "six-face")


def _version(doc: dict, path: Any) -> int:
    """The header of a calibration-file object: ``format`` and a ``format_version`` this
    tiltbench reads (:data:`READ_VERSIONS`)."""
    if "format" not in doc:
        raise fail(path, "format", f"missing: not a {FORMAT} file (a calibrate --json "
                   "output? write the file with calibrate --save)")
    if doc["format"] != FORMAT:
        raise fail(path, "format", f"is {short(doc['format'])}, expected {FORMAT!r}")
    if "format_version" not in doc:
        raise fail(path, "format_version", "missing")
    return _known_version(doc["format_version"], path)


def _known_version(version: Any, path: Any) -> int:
    if version not in READ_VERSIONS or not is_int(version):
        old = is_int(version) and 1 <= version < min(READ_VERSIONS)
        raise fail(path, "format_version", f"is {short(version)}; this tiltbench writes "
                   f"version {FORMAT_VERSION} only and reads versions "
                   f"{' and '.join(map(str, READ_VERSIONS))} ("
                   + ("an older file without a checksum: " if old else
                      "written by a newer tiltbench? upgrade, or ") + f"{RERUN})")
    return int(version)


def calibration_file_from_document(doc: Any, path: Any = "<memory>") -> CalibrationFile:
    """Check a calibration-file object completely and rebuild its calibration (exact).

    In order: the header (``format``, ``format_version``), every required field present and
    no unknown one; the defining fields' types and shapes; :func:`check_calibration` (a
    six-face file: :func:`calib.calibration.calfile_sixface.check_six_face`); g against its
    source; every derived field equal to its re-derivation; the ``checksum`` of the defining
    fields.

    Raises
    ------
    DataError : one line naming the file and the field; an edited file says
        "checksum/consistency failed" and to re-run ``calibrate --save``.
    """
    if not isinstance(doc, dict):
        raise DataError(f"{path}: not a calibration file (expected a JSON object with "
                        f"'format': '{FORMAT}')")
    version = _version(doc, path)
    if version == 3 and doc.get("method") == SIX_FACE:
        six = six_face_from_document(doc, path)
        return CalibrationFile(six.fit, "estimated", six.source, None, six.checksum,
                               six.readings, six.gravity, version, str(path), six.hold_means)
    required = _REQUIRED if version == 3 else _REQUIRED_V2
    for key in required:
        if key not in doc:
            raise fail(path, key, f"missing; {RERUN}")
    unknown = [k for k in doc if k not in required and k not in COSMETIC_FIELDS]
    if unknown:
        raise fail(path, unknown[0], f"is not part of format version {version} "
                   f"(the file was edited?); {RERUN}")
    if doc["method"] not in METHODS:
        methods = (*METHODS, SIX_FACE) if version == 3 else METHODS
        raise fail(path, "method", f"is {short(doc['method'])}, expected one of "
                   f"{', '.join(methods)}")
    if doc["sigma2_source"] not in SIGMA2_SOURCES:
        raise fail(path, "sigma2_source", f"is {short(doc['sigma2_source'])}, expected one "
                   f"of {', '.join(SIGMA2_SOURCES)}")
    g = number(doc["g"], "g", path)
    if not is_int(doc["n"]):
        raise fail(path, "n", f"must be an integer (samples), got {short(doc['n'])}")
    check_ref(doc, "source", path)
    check_ref(doc, "noise_file", path)
    readings, gravity = COURSE_READINGS, None
    if version == 3:
        readings = readings_from_document(doc["readings"], path)
    state = doc["calibration"]
    if not isinstance(state, dict):
        raise fail(path, "calibration", "must be an object (Calibration.to_state())")
    for key in ("fits", "joint"):
        if key not in state:
            raise fail(path, f"calibration.{key}", f"missing; {RERUN}")
    if not isinstance(state["fits"], dict):
        raise fail(path, "calibration.fits", "must be an object with fits 'x' and 'y'")
    fits = {a: _fit_from(state["fits"].get(a), f"calibration.fits.{a}", PARAM_NAMES, path)
            for a in AXES}
    joint = (None if state["joint"] is None else
             _fit_from(state["joint"], "calibration.joint", JOINT_PARAM_NAMES, path))
    lof = state.get("lack_of_fit")
    if lof is not None:
        if not isinstance(lof, dict) or set(lof) != set(AXES):
            raise fail(path, "calibration.lack_of_fit", "must be null or the tests of axes "
                       f"{' and '.join(AXES)}")
        try:
            lof = {str(a): LackOfFit.from_dict(v) for a, v in lof.items()}
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as exc:
            raise fail(path, "calibration.lack_of_fit", f"is malformed ({exc})") from None
    cal = Calibration(doc["method"], g, fits, doc["n"], joint, lof)
    check_calibration(cal, doc["sigma2_source"], path)
    if version == 3:
        gravity = gravity_from_document(doc["gravity"], g, path)
    try:
        want = json.loads(json.dumps(
            _document(cal, doc["source"], doc["sigma2_source"], doc["noise_file"],
                      doc.get("tool"), False, readings=readings, gravity=gravity),
            default=plain))
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        # a defining field that passed the checks yet does not re-serialise (a malformed
        # lack-of-fit test): the file is not one this tiltbench wrote
        raise fail(path, "calibration", f"is malformed ({exc}); {RERUN}") from None
    check_derived(doc, want, path, skip=("checksum", *COSMETIC_FIELDS))
    value = check_checksum(doc, _checksum_fields(doc), path)
    return CalibrationFile(cal, doc["sigma2_source"], doc["source"], doc["noise_file"], value,
                           readings, gravity, version, str(path))


def calibration_from_document(doc: Any, path: Any = "<memory>") -> Calibration | SixFaceFit:
    """The calibration of a checked calibration-file object
    (:func:`calibration_file_from_document`)."""
    return calibration_file_from_document(doc, path).calibration


def _read_json_document(path: Path) -> Any:
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a JSON calibration file (not UTF-8 text: {exc.reason} "
                        f"at byte {exc.start}); {RERUN}") from None
    if not text.strip():
        raise DataError(f"{path}: empty file, not a calibration file; {RERUN}")
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise DataError(f"{path}: not a JSON calibration file ({str(exc)[:80]}); "
                        f"{RERUN}") from None


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
        raise fail(path, key, "missing (not a tiltbench calibration .mat: write one with "
                   "calibrate --save cal.mat)")
    arr = np.asarray(v)
    if arr.dtype.kind != "U" or arr.size > 1:
        raise fail(path, key, "must be a char row")
    return str(arr.reshape(-1)[0]) if arr.size else ""


def _mat_equal(got: Any, want: Any) -> bool:
    """A loaded ``.mat`` variable against the one :func:`mat_variables` derives (NaN, the
    export's null, equal to NaN)."""
    if isinstance(want, str):
        arr = np.asarray(got)
        if arr.dtype.kind != "U" or arr.size > 1:
            return False
        return (str(arr.reshape(-1)[0]) if arr.size else "") == want
    arr = np.asarray(got)
    if arr.dtype.kind not in "fiu":
        return False
    w = np.atleast_2d(np.asarray(want, float))
    return arr.shape == w.shape and np.array_equal(arr.astype(float), w, equal_nan=True)


def _read_mat_document(path: Path) -> tuple[CalibrationFile, dict]:
    """The calibration-file object stored in a ``.mat`` export, checked like the JSON file;
    every plain variable but ``tool_version`` must equal the one derived from it."""
    import scipy.io

    if path.stat().st_size == 0:
        raise DataError(f"{path}: empty file, not a MATLAB .mat calibration file; {RERUN}")
    try:
        mat = scipy.io.loadmat(path)
    # scipy's MAT reader raises many types on damaged bytes (MatReadError, ValueError,
    # struct.error, zlib.error, EOFError, UnicodeDecodeError …); any of them means "not a
    # .mat this program wrote", which is one line for the user, never a traceback
    except Exception as exc:  # noqa: BLE001
        raise DataError(f"{path}: not a MATLAB .mat calibration file "
                        f"({type(exc).__name__}: {str(exc)[:80]}); {RERUN}") from None
    fmt = _mat_text(mat, "format", path)
    if fmt != FORMAT:
        raise fail(path, "format", f"is {short(fmt)}, expected {FORMAT!r}")
    if "format_version" not in mat:
        raise fail(path, "format_version", "missing")
    fv = np.asarray(mat["format_version"])
    fv = fv.astype(float).reshape(-1) if fv.dtype.kind in "fiu" else np.array([np.nan])
    _known_version(int(fv[0]) if fv.size == 1 and float(fv[0]).is_integer() else fv.tolist(),
                   path)
    try:
        doc = json.loads(_mat_text(mat, "document", path))
    except (ValueError, RecursionError) as exc:
        raise fail(path, "document", f"is not the JSON calibration object ({str(exc)[:80]})"
                   f"; {RERUN}") from None
    checked = calibration_file_from_document(doc, path)
    want = mat_variables(doc)
    names = [k for k in mat if not k.startswith("__")]
    for key in names:
        if key not in want:
            raise fail(path, key, f"is not a variable of the export (the file was edited?); "
                       f"{RERUN}")
    for key, value in want.items():
        if key in _MAT_COSMETIC or key == "document":  # the source itself, checked above
            continue
        if key not in mat:
            raise fail(path, key, f"missing; {RERUN}")
        if not _mat_equal(mat[key], value):
            raise DataError(f"{path}: checksum/consistency failed: '{key}' differs from the "
                            f"'document' variable (the file was edited); {RERUN}")
    return checked, doc


def load_calibration_file(path: str | os.PathLike) -> CalibrationFile:
    """Read and check a calibration file: the one reader of every command.

    Parameters
    ----------
    path : a ``.json`` calibration file or its ``.mat`` export (format version 2 or 3, a
        tilt-plane or a six-face calibration).

    Returns
    -------
    CalibrationFile : the calibration (equal, ``==``, to the one saved), its provenance and
        the readings it applies to.

    Raises
    ------
    DataError : file missing, empty, not JSON (or not a ``.mat`` export), another format, an
        unknown ``format_version``, a missing, malformed or implausible field, a derived
        field that differs from its re-derivation or a checksum that does not match (one
        line: the file and the field).
    """
    return _read(Path(path))[0]


def _where(readings: LogReadings, course: bool) -> str:
    return (f"the course's {readings.describe()}" if course and readings == COURSE_READINGS
            else readings.describe())


def check_applies(calfile: CalibrationFile, log: ImuLog | LogReadings | None = None, *,
                  tilt_plane: bool = True, log_name: str | None = None) -> None:
    """Refuse, in one line, a calibration that does not apply: the one check of every
    command that takes ``--calibration``.

    Parameters
    ----------
    calfile : the checked file (:func:`load_calibration_file`).
    log : the log it is about to correct (its readings: :func:`calib.calibration.readings.
        readings_of`), or the readings of what it is compared with (a generated set reads
        :data:`~calib.calibration.readings.COURSE_READINGS`); None: the kind only.
    tilt_plane : the command corrects the tilt plane's two axes by bias and scale (trajectory,
        fuse, nmin, validate, noise): a six-face file is refused with what to do instead.
        False (``apply``): either kind; a six-face file needs a log with three axes.
    log_name : the log's name in messages (default: ``log.source``).

    Raises
    ------
    DataError : a six-face file where a tilt-plane one is needed; the log read through other
        axes (``--axes``) or in another unit (or another sensitivity of raw counts) than the
        readings the calibration was fitted on (its scale factor absorbs the unit's
        conversion); a six-face file on a log without a third axis.
    """
    path = calfile.path
    if tilt_plane and calfile.kind == "six-face":
        raise DataError(f"{path}: holds a six-face calibration of 3 axes (bias, scale and "
                        "misalignment of x, y, z); this command needs a tilt-plane calibration "
                        "(bias and scale of the tilt plane's x, y: calibrate a tilt-table run, "
                        "or held poses in the tilt plane, with --save); a six-face file "
                        "corrects a 3-axis log: tiltbench apply LOG "
                        f"--calibration {Path(str(path)).name} --out corrected.csv")
    if log is None:
        return
    if isinstance(log, ImuLog):
        readings, name = readings_of(log), log_name or log.source
        three, course = log.acc_normal is not None, log.provenance.get("format") == "course"
    else:
        readings, name, three, course = log, log_name or "the log", True, True
    mine = calfile.readings
    if readings.axes != mine.axes:
        other = f"use a calibration of axes {','.join(readings.axes)}"
        fix = (f"{other} (a course file's axes are fixed)"
               if course and readings == COURSE_READINGS
               else f"read it with --axes={','.join(mine.axes)}, or {other}")
        raise DataError(f"{path}: calibrated on the log axes {','.join(mine.axes)} (--axes "
                        f"{','.join(mine.axes)}), but {name} reads "
                        f"{_where(readings, course)}: {fix}")
    if (readings.unit, readings.sensitivity) != (mine.unit, mine.sensitivity):
        theirs = readings.describe().split(" in ", 1)[1]
        fix = (f"read it with --sensitivity {mine.sensitivity:g}, or calibrate it"
               if readings.unit == mine.unit == "counts" else f"calibrate readings in {theirs}")
        raise DataError(f"{path}: calibrated on readings in {mine.describe().split(' in ')[1]}, "
                        f"but {name} reads {_where(readings, course)}: its scale factors hold "
                        f"only for the readings they were fitted on; {fix}")
    if calfile.kind == "six-face" and not three:
        raise DataError(f"{path}: a six-face calibration corrects 3 axes; {name} has only "
                        f"{','.join(readings.axes)} (give a log with its third axis, "
                        f"{readings.normal_axis.lstrip('-')})")


def load_calibration(path: str | os.PathLike) -> Calibration:
    """The tilt-plane :class:`Calibration` of a calibration file, equal (``==``) to the one
    saved: ``load_calibration_file(path).calibration`` after :func:`check_applies` (a
    six-face file is refused: read it with :func:`load_calibration_file`).

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
    calfile = load_calibration_file(path)
    check_applies(calfile)
    return calfile.calibration  # type: ignore[return-value]


__all__ = ["CHECKSUM_FIELDS", "CORRELATION_EIG_MIN", "COSMETIC_FIELDS", "DEFINING_FIELDS",
           "DEFINING_FIELDS_V2", "FILE_UNITS", "FILE_UNITS_V2", "FORMAT", "FORMAT_VERSION",
           "G_RANGE", "GAIN_RANGE", "KINDS", "MAX_ABS_BIAS", "N_RANGE", "READ_VERSIONS",
           "RELATIVE_TOLERANCE", "SIGMA2_RANGE", "SIGMA2_SOURCES", "CalibrationFile",
           "calibration_document", "calibration_file_from_document",
           "calibration_from_document", "check_applies", "check_calibration",
           "defining_checksum", "file_sha256", "load_calibration", "load_calibration_file",
           "mat_variables", "read_calibration_document", "save_calibration",
           "save_calibration_mat"]
