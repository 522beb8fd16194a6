"""The six-face calibration of three axes in the calibration file (format version 3,
``"method": "six-face"``; ``docs/calibration-file.md``).

One JSON object, keys in this order (kind: **d**efining, *derived*, cosmetic)::

    format, format_version      "tiltbench-calibration", 3                          d
    tool                        {"name", "version"}                                 cosmetic
    method                      "six-face"                                          d
    g, gravity                  m/s²; {"source", "latitude" deg, "height" m}        d
    n                           samples of every hold, Σ n_h                        derived
    source                      {"name", "sha256"} of the log                       d
    readings                    {"axes", "unit", "sensitivity_counts_per_g",        d
                                 "to_m_s2"}: what the calibration corrects
    sensor_axes                 {"x": a, "y": b, "z": â × b̂}: the log's signed axes  derived
    param_names, params, std    12 parameters, per axis a: bias_a m/s², scale_a 1,   derived
                                misalignment_ab rad, misalignment_ac rad
    cov                         (12, 12), the products of those units               derived
    bias, scale                 (3,) m/s², (3,) 1                                   derived
    misalignment, k_matrix      (3, 3) rad (m_ab off the diagonal), (3, 3) 1         derived
    sigma_within                (3,) σ_W m/s², the scatter within holds             derived
    hold_to_hold_variance       (3, 2) σ_B² (m/s²)² per axis, class (axis vertical,  derived
                                axis level); null when no face is held twice
    poses                       per hold {"face", "n", "mean" (3,) m/s²}            d
    units, checksum             key path → unit; SHA-256 of the defining fields     derived
    calibration                 SixFaceFit.to_dict() but its "source" (a path)      d

Defining fields (:data:`DEFINING_FIELDS`) rebuild the :class:`~calib.calibration.sixface.
SixFaceFit`; every derived field is re-derived from it on load and must be equal, exactly;
the checksum covers the defining fields. Before that, the numbers are checked against
themselves (:func:`check_six_face`): shapes, a positive definite covariance, the scale and
misalignment parameters equal to their entries of K (exactly), a K that can be solved, faces
that identify every parameter, each hold's face the one its mean points along, the residuals
equal to ``mean − (b + g K u)`` and each hold's std to ``√(σ_B,c² + σ_W²/n)`` with σ_B,c
the σ_B of the hold's class for that axis (vertical on faces ±a, level on the others;
:func:`calib.calibration.sixface.hold_classes`) (to 10⁻⁹ relative), σ_B measured exactly when
a face is held twice, and a class with no re-held face carrying the other class' σ_B.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from calib.calibration.calfile_fields import (
    FORMAT,
    FORMAT_VERSION,
    G_RANGE,
    GAIN_RANGE,
    MAX_ABS_BIAS,
    N_RANGE,
    RELATIVE_TOLERANCE,
    RERUN,
    SIGMA2_RANGE,
    array,
    check_checksum,
    check_cov,
    check_derived,
    check_ref,
    checksum_entry,
    cov_units,
    fail,
    inconsistent,
    is_int,
    number,
    short,
)
from calib.calibration.readings import (
    GRAVITY_UNITS,
    READINGS_UNITS,
    GravitySource,
    LogReadings,
    gravity_from_document,
    readings_from_document,
)
from calib.calibration.sixface import (
    AXES_3,
    SixFaceFit,
    face_name,
    face_vectors,
    hold_classes,
)

METHOD = "six-face"
"""The ``method`` of a six-face calibration file."""
DEFINING_FIELDS = ("format", "format_version", "method", "g", "gravity", "source", "readings",
                   "poses", "calibration")
"""The fields a six-face calibration is rebuilt from; its ``checksum`` covers exactly these."""
PARAM_NAMES = tuple(name for k, a in enumerate(AXES_3) for name in (
    f"bias_{a}", f"scale_{a}", *(f"misalignment_{a}{b}" for b in AXES_3 if b != a)))
"""The 12 parameters, in the order of :func:`calib.calibration.sixface.fit_six_face`."""
K_COND_MAX = 1e6
"""Largest condition number of K that a correction ``a = K⁻¹(m − b)`` may solve: the ratio
of the largest to the smallest gain allowed (:data:`GAIN_RANGE`); misalignments of a real
sensor are milliradians and leave K near ``I + S``."""
COV_ROUNDING = 1e-12
"""Largest asymmetry of the covariance, relative to ``√(C_ii C_jj)``: the delta-method
products ``J C Jᵀ`` of the fit are symmetric to a few rounding units (~1e-16), an edit is
not."""
STATE_KEYS = ("method", *(f.name for f in fields(SixFaceFit) if f.name != "source"))
"""The keys of the ``calibration`` object: :meth:`SixFaceFit.to_dict` without ``source`` (a
path, for messages; the file records the log's name in ``source``)."""
_REQUIRED = ("format", "format_version", "method", "g", "gravity", "n", "source", "readings",
             "sensor_axes", "param_names", "params", "std", "cov", "bias", "scale",
             "misalignment", "k_matrix", "sigma_within", "hold_to_hold_variance", "poses",
             "units", "checksum", "calibration")
_COSMETIC = ("tool",)

_P_UNITS = ["m/s²", "1", "rad", "rad"] * 3
FILE_UNITS = {
    "format_version": "—", "g": "m/s²", **GRAVITY_UNITS, "n": "count", **READINGS_UNITS,
    "params": "[" + ", ".join(_P_UNITS) + "]", "std": "[" + ", ".join(_P_UNITS) + "]",
    "cov": cov_units(_P_UNITS), "bias": "m/s²", "scale": "1", "misalignment": "rad",
    "k_matrix": "1", "sigma_within": "m/s²", "hold_to_hold_variance": "(m/s²)²",
    "poses.n": "count", "poses.mean": "m/s²",
    "calibration.params": "[" + ", ".join(_P_UNITS) + "]", "calibration.cov": cov_units(_P_UNITS),
    "calibration.dof": "1", "calibration.k_matrix": "1", "calibration.residuals": "m/s²",
    "calibration.hold_std": "m/s²", "calibration.n": "count",
    "calibration.sigma_within": "m/s²", "calibration.sigma_between": "m/s²",
    "calibration.widening": "1", "calibration.lack_of_fit_p": "1", "calibration.g": "m/s²",
    "calibration.level": "1",
}
"""The ``units`` object of a six-face calibration file (docs/units.md); the Satterthwaite
``dof`` (one per parameter) are not whole numbers, hence ``1``; ``sigma_between`` (m/s²) and
``hold_to_hold_variance`` ((m/s²)²) are (3, 2), per axis and class (axis vertical, level)."""


@dataclass(frozen=True, eq=False)
class SixFaceFile:
    """A checked six-face calibration-file object: the fit and what it was made from."""

    fit: SixFaceFit
    hold_means: np.ndarray
    """(H, 3) m/s², the mean reading of each hold (the ``poses`` of the file)."""
    source: dict | None
    readings: LogReadings
    gravity: GravitySource
    checksum: str


def _none_if_nan(values: np.ndarray) -> list:
    """A JSON list (nested for a 2-D array) with null for NaN (not measured)."""
    def one(v: Any) -> Any:
        return [one(x) for x in v] if isinstance(v, list) else (
            None if not np.isfinite(v) else v)
    return one(np.asarray(values, float).tolist())


def _nan_if_none(v: Any) -> Any:
    """The inverse of :func:`_none_if_nan` before a shape check (anything else unchanged)."""
    if isinstance(v, list):
        return [_nan_if_none(x) for x in v]
    return np.nan if v is None else v


def six_face_document(fit: SixFaceFit, hold_means: np.ndarray, source: dict | None,
                      readings: LogReadings, gravity: GravitySource, tool: Any,
                      checksum: bool = True) -> dict:
    """The calibration-file object of a six-face fit (module docstring).

    Parameters
    ----------
    fit : the fit (:func:`calib.calibration.sixface.fit_six_face`).
    hold_means : (H, 3) m/s², the hold means it was fitted on (``Poses.means``).
    source : ``{"name", "sha256"}`` of the log, or None.
    readings : which of the log's readings it corrects.
    gravity : where ``fit.g`` came from.
    tool : the ``tool`` object (cosmetic).
    checksum : False: leave ``checksum`` None (the reader compares the file's own).
    """
    means = np.asarray(hold_means, dtype=float)
    state = {k: v for k, v in fit.to_dict().items() if k != "source"}
    doc = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "tool": tool, "method": METHOD,
        "g": fit.g, "gravity": gravity.to_dict(), "n": int(np.sum(fit.n)), "source": source,
        "readings": readings.to_dict(),
        "sensor_axes": dict(zip(AXES_3, readings.log_axes(three=True), strict=True)),
        "param_names": list(fit.param_names), "params": fit.params.tolist(),
        "std": fit.std.tolist(), "cov": fit.cov.tolist(), "bias": fit.bias.tolist(),
        "scale": fit.scale.tolist(), "misalignment": fit.misalignment.tolist(),
        "k_matrix": fit.k_matrix.tolist(), "sigma_within": fit.sigma_within.tolist(),
        "hold_to_hold_variance": _none_if_nan(fit.sigma_between**2),
        "poses": [{"face": f, "n": int(n), "mean": m.tolist()}
                  for f, n, m in zip(fit.faces, fit.n, means, strict=True)],
        "units": dict(FILE_UNITS), "checksum": None, "calibration": state,
    }
    if checksum:
        doc["checksum"] = checksum_entry(doc, DEFINING_FIELDS)
    return doc


def _state_fit(state: Any, path: Any) -> tuple[SixFaceFit, int]:
    """The ``calibration`` object: keys, types and shapes, then the rebuilt fit."""
    if not isinstance(state, dict):
        raise fail(path, "calibration", "must be an object (SixFaceFit.to_dict())")
    for key in STATE_KEYS:
        if key not in state:
            raise fail(path, f"calibration.{key}", f"missing; {RERUN}")
    extra = [k for k in state if k not in STATE_KEYS]
    if extra:
        raise fail(path, f"calibration.{extra[0]}", f"is not part of a six-face calibration; "
                   f"{RERUN}")
    if state["method"] != METHOD:
        raise fail(path, "calibration.method", f"is {short(state['method'])}, expected "
                   f"{METHOD!r}")
    if state["param_names"] != list(PARAM_NAMES):
        raise fail(path, "calibration.param_names", f"must be {list(PARAM_NAMES)}")
    faces = state["faces"]
    names = {f"{s}{a}" for a in AXES_3 for s in "+-"}
    if not isinstance(faces, list) or not faces or not all(f in names for f in faces):
        raise fail(path, "calibration.faces", "must be a list of faces '+x', '-x', … '-z', got "
                   f"{short(faces)}")
    h = len(faces)
    n = state["n"]
    if not isinstance(n, list) or len(n) != h or not all(is_int(v) and v >= 2 for v in n):
        raise fail(path, "calibration.n", f"must be {h} integers ≥ 2 (samples per hold), got "
                   f"{short(n)}")
    array(state["params"], "calibration.params", (12,), path)
    array(state["cov"], "calibration.cov", (12, 12), path)
    dof = array(state["dof"], "calibration.dof", (12,), path)
    if np.any(dof <= 0):
        raise fail(path, "calibration.dof", f"must be positive, got {dof.tolist()}")
    array(state["k_matrix"], "calibration.k_matrix", (3, 3), path)
    array(state["residuals"], "calibration.residuals", (h, 3), path)
    if np.any(array(state["hold_std"], "calibration.hold_std", (h, 3), path) <= 0):
        raise fail(path, "calibration.hold_std", "must be positive (m/s²)")
    sw = array(state["sigma_within"], "calibration.sigma_within", (3,), path)
    if not np.all((sw**2 >= SIGMA2_RANGE[0]) & (sw**2 <= SIGMA2_RANGE[1])):
        raise fail(path, "calibration.sigma_within", f"is {sw.tolist()}: each σ_W² must be in "
                   f"[{SIGMA2_RANGE[0]:g}, {SIGMA2_RANGE[1]:g}] (m/s²)²")
    sb = array(_nan_if_none(state["sigma_between"]), "calibration.sigma_between", (3, 2), path,
               nullable=True)
    if np.any(sb < 0):
        raise fail(path, "calibration.sigma_between", "must not be negative")
    array(state["widening"], "calibration.widening", (3,), path, nullable=True)
    p = array(state["lack_of_fit_p"], "calibration.lack_of_fit_p", (3,), path, nullable=True)
    if np.any((p < 0) | (p > 1)):
        raise fail(path, "calibration.lack_of_fit_p", f"must be p-values in [0, 1], got "
                   f"{p.tolist()}")
    misfit = state.get("misfit_in_intervals", [False] * 3)
    if not isinstance(misfit, list) or len(misfit) != 3 or not all(
            isinstance(v, bool) for v in misfit):
        raise fail(path, "calibration.misfit_in_intervals", f"must be 3 booleans, got "
                   f"{short(misfit)}")
    number(state["g"], "calibration.g", path)
    if not isinstance(state["g_source"], str):
        raise fail(path, "calibration.g_source", "must be text")
    level = number(state["level"], "calibration.level", path)
    if not 0 < level < 1:
        raise fail(path, "calibration.level", f"is {level!r}: a level is in (0, 1)")
    try:
        return SixFaceFit.from_dict({**state, "source": "<file>"}), int(sum(n))
    except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise fail(path, "calibration", f"is malformed ({exc}); {RERUN}") from None


def _hold_means(poses: Any, fit: SixFaceFit, path: Any) -> np.ndarray:
    """The ``poses`` list: one ``{"face", "n", "mean"}`` per hold of the fit."""
    h = len(fit.faces)
    if not isinstance(poses, list) or len(poses) != h:
        raise fail(path, "poses", f"must list the {h} holds of the fit, got {short(poses)}")
    means = []
    for i, pose in enumerate(poses):
        if not isinstance(pose, dict) or set(pose) != {"face", "n", "mean"}:
            raise fail(path, f"poses[{i}]", f"must be {{\"face\", \"n\", \"mean\"}}, got "
                       f"{short(pose)}")
        means.append(array(pose["mean"], f"poses[{i}].mean", (3,), path))
    return np.array(means)


def check_six_face(fit: SixFaceFit, hold_means: np.ndarray, g: float, path: Any) -> None:
    """The numbers of a six-face fit, and the fit against its hold means (module docstring).

    Raises
    ------
    DataError : one line, ``{path}: field '<field>' …`` or ``checksum/consistency failed``.
    """
    if not G_RANGE[0] <= g <= G_RANGE[1]:
        raise fail(path, "g", f"is {g!r} m/s²: gravity must be in [{G_RANGE[0]:g}, "
                   f"{G_RANGE[1]:g}]")
    if fit.g != g:
        raise inconsistent(path, "calibration.g", f"is {fit.g!r}, but the file's g is {g!r}")
    total = int(np.sum(fit.n))
    if not N_RANGE[0] <= total <= N_RANGE[1]:
        raise fail(path, "calibration.n", f"sums to {total}: the samples of a calibration run "
                   f"must be in [{N_RANGE[0]}, {N_RANGE[1]:,}]")
    u = face_vectors(fit.faces)
    if len(set(fit.faces)) < 4 or not np.all(np.any(u != 0, axis=0)):
        raise fail(path, "calibration.faces", f"({', '.join(sorted(set(fit.faces)))}) cannot "
                   "identify every parameter: four faces or more, along every case axis")
    # the fit's covariance is J C Jᵀ per axis (the delta method): symmetric to rounding
    check_cov(fit.cov, fit.param_names, "calibration.cov", path, rounding=COV_ROUNDING)
    k = fit.k_matrix
    kaa = np.diag(k)
    for a, axis in enumerate(AXES_3):
        if not GAIN_RANGE[0] <= kaa[a] <= GAIN_RANGE[1]:
            raise fail(path, "calibration.k_matrix", f"has K_{axis}{axis} = {kaa[a]!r}: the "
                       f"gain 1 + scale must be in [{GAIN_RANGE[0]:g}, {GAIN_RANGE[1]:g}]")
        if abs(fit.bias[a]) > MAX_ABS_BIAS:
            raise fail(path, "calibration.params", f"has bias_{axis} = {fit.bias[a]!r} m/s² "
                       f"(|bias| at most {MAX_ABS_BIAS:g})")
        others = [j for j in range(3) if j != a]
        # the fit's own arithmetic (fit_six_face): scale = K_aa − 1, m_ab = K_ab / K_aa
        want = [kaa[a] - 1.0, *(k[a, j] / kaa[a] for j in others)]
        got = fit.params[4 * a + 1: 4 * a + 4].tolist()
        if got != want:
            raise inconsistent(path, "calibration.params", f"of axis {axis} ({got}) are not "
                               f"the scale and misalignments of calibration.k_matrix ({want})")
    cond = float(np.linalg.cond(k))
    if not cond <= K_COND_MAX:
        raise fail(path, "calibration.k_matrix", f"has condition number {cond:.3g} (at most "
                   f"{K_COND_MAX:g}): the correction cannot solve K a = m − b")
    sb = np.asarray(fit.sigma_between, dtype=float)
    nan = np.isnan(sb)
    if nan.any() != (len(set(fit.faces)) == len(fit.faces)) or (nan.any() and not nan.all()):
        raise inconsistent(path, "calibration.sigma_between", "must be measured (numbers) "
                           "exactly when a face is held twice")
    # a class (axis vertical / level) none of whose faces is held twice carries the other's
    for a, c in zip(*np.nonzero(fit.borrowed()), strict=True):
        if sb[a, c] != sb[a, 1 - c]:
            raise inconsistent(path, f"calibration.sigma_between[{a}][{c}]",
                               f"is {sb[a, c]!r}, but no face of that class is held twice: "
                               f"it must be the other class' {sb[a, 1 - c]!r}")
    # an axis whose lack of fit went into its intervals (SixFaceFit.misfit_in_intervals)
    # has its estimate from the face means: its widening is measured, its hold std at least
    # the face-level scatter
    misfit = np.array(getattr(fit, "misfit_in_intervals", (False,) * 3), dtype=bool)
    plain = ~misfit
    if not np.array_equal(np.isnan(fit.widening[plain]), nan[plain].any(axis=1)):
        raise inconsistent(path, "calibration.widening", "must be null exactly where "
                           "sigma_between is")
    # the fit's faces are the case axes its hold means point along (sixface.faces_of)
    faces = tuple(face_name(r) for r in hold_means)
    for i, (got_face, want_face) in enumerate(zip(faces, fit.faces, strict=True)):
        if got_face != want_face:
            raise inconsistent(path, f"poses[{i}].mean", f"points along {got_face}, not the "
                               f"face {want_face} of the hold")
    model = fit.bias + g * u @ k.T
    scale_m = max(float(np.max(np.abs(hold_means))), g)
    off = np.abs(fit.residuals - (hold_means - model))
    if np.max(off) > RELATIVE_TOLERANCE * scale_m:
        i, a = np.unravel_index(np.argmax(off), off.shape)
        raise inconsistent(path, f"calibration.residuals[{i}][{a}]",
                           f"is {fit.residuals[i, a]!r} but the hold's mean and the model give "
                           f"{hold_means[i, a] - model[i, a]!r}")
    sb2 = np.where(nan, 0.0, sb) ** 2
    v = (np.take_along_axis(sb2.T, hold_classes(fit.faces), axis=0)  # σ_B,c(h)² per axis
         + fit.sigma_within**2 / np.asarray(fit.n, float)[:, None])
    rel = (fit.hold_std**2 - v) / v
    rel[:, plain] = np.abs(rel[:, plain])
    rel[:, misfit] = -np.minimum(rel[:, misfit], 0.0)  # at least √(σ_B² + σ_W²/n)
    if np.max(rel) > RELATIVE_TOLERANCE:
        i, a = np.unravel_index(np.argmax(rel), rel.shape)
        raise inconsistent(path, f"calibration.hold_std[{i}][{a}]",
                           f"is {fit.hold_std[i, a]!r}, not √(σ_B,c² + σ_W²/n) = "
                           f"{float(np.sqrt(v[i, a]))!r}")


def six_face_from_document(doc: dict, path: Any) -> SixFaceFile:
    """Check a six-face calibration-file object completely (its ``format`` and
    ``format_version`` already checked) and rebuild its fit (exact).

    Raises
    ------
    DataError : one line naming the file and the field.
    """
    for key in _REQUIRED:
        if key not in doc:
            raise fail(path, key, f"missing; {RERUN}")
    unknown = [k for k in doc if k not in _REQUIRED and k not in _COSMETIC]
    if unknown:
        raise fail(path, unknown[0], f"is not part of a six-face calibration file of format "
                   f"version {FORMAT_VERSION} (the file was edited?); {RERUN}")
    g = number(doc["g"], "g", path)
    gravity = gravity_from_document(doc["gravity"], g, path)
    check_ref(doc, "source", path)
    readings = readings_from_document(doc["readings"], path)
    fit, _ = _state_fit(doc["calibration"], path)
    means = _hold_means(doc["poses"], fit, path)
    check_six_face(fit, means, g, path)
    name = (doc["source"] or {}).get("name", "<memory>")
    fit = SixFaceFit.from_dict({**doc["calibration"], "source": name})
    want = six_face_document(fit, means, doc["source"], readings, gravity, doc.get("tool"),
                             checksum=False)
    check_derived(doc, want, path, skip=("checksum", *_COSMETIC))
    value = check_checksum(doc, DEFINING_FIELDS, path)
    return SixFaceFile(fit, means, doc["source"], readings, gravity, value)


def six_face_mat_variables(doc: dict) -> dict[str, Any]:
    """The plain variables of the ``.mat`` export of a six-face calibration-file object
    (double and char only; NaN where the JSON has null)."""
    tool = doc.get("tool")
    gravity, readings = doc["gravity"], doc["readings"]

    def num(v: Any) -> float:
        return np.nan if v is None else float(v)

    return {
        "format": doc["format"], "format_version": float(doc["format_version"]),
        "tool_version": str(tool.get("version", "")) if isinstance(tool, dict) else "",
        "method": doc["method"], "g": float(doc["g"]), "gravity_source": gravity["source"],
        "latitude": num(gravity["latitude"]), "height": num(gravity["height"]),
        "n": float(doc["n"]), "axes": ",".join(readings["axes"]), "unit": readings["unit"],
        "sensitivity": num(readings["sensitivity_counts_per_g"]),
        "to_m_s2": float(readings["to_m_s2"]),
        "sensor_axes": ",".join(doc["sensor_axes"][a] for a in AXES_3),
        "param_names": ",".join(doc["param_names"]),
        "params": np.asarray(doc["params"], float).reshape(1, 12),
        "std": np.asarray(doc["std"], float).reshape(1, 12),
        "cov": np.asarray(doc["cov"], float),
        "bias": np.asarray(doc["bias"], float).reshape(1, 3),
        "scale": np.asarray(doc["scale"], float).reshape(1, 3),
        "misalignment": np.asarray(doc["misalignment"], float),
        "k_matrix": np.asarray(doc["k_matrix"], float),
        "sigma_within": np.asarray(doc["sigma_within"], float).reshape(1, 3),
        "hold_to_hold_variance": np.array([[num(v) for v in row]
                                           for row in doc["hold_to_hold_variance"]]),
        "faces": ",".join(p["face"] for p in doc["poses"]),
        "hold_n": np.array([[float(p["n"]) for p in doc["poses"]]]),
        "hold_means": np.array([p["mean"] for p in doc["poses"]], float).reshape(-1, 3),
        "source_name": (doc["source"] or {}).get("name", ""),
        "source_sha256": (doc["source"] or {}).get("sha256", ""),
        "checksum": doc["checksum"]["value"],
        "units": "g m/s^2; params per axis [bias m/s^2, scale 1, misalignment rad x2]; cov "
                 "products of the params' units; bias, sigma_within, hold_means m/s^2; "
                 "hold_to_hold_variance (m/s^2)^2, 3x2 (axis x y z; class axis vertical, axis "
                 "level); misalignment rad; k_matrix 1; latitude deg; height m",
    }


__all__ = ["COV_ROUNDING", "DEFINING_FIELDS", "FILE_UNITS", "K_COND_MAX", "METHOD",
           "PARAM_NAMES", "STATE_KEYS", "SixFaceFile", "check_six_face", "six_face_document",
           "six_face_from_document", "six_face_mat_variables"]
