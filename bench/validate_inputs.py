"""The JSON inputs of ``tiltbench validate``, each checked against a JSON Schema before
anything is computed: ``truth.json`` (:func:`read_truth`), ``est.json``
(:func:`parse_estimates`), ``answer_key.json`` (:func:`check_answer_key`); every error is one
line naming the file, the key path, what it expects and what it got (:func:`load_json`,
:func:`check_schema`). The comparison itself: :mod:`bench.validate` (formats:
``docs/validate.md``).
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from calib.conventions import AXES, G
from calib.files.course import DataError

# --- The JSON inputs, checked against a schema -----------------------------------------------
# One JSON Schema (draft 2020-12, checked by the ``jsonschema`` package) per object validate
# reads; every leaf says in its ``description`` what it expects, which is what the message says.
# Numbers must be finite: the type checker's "number" and "integer" exclude NaN, ±Infinity,
# booleans and integers beyond the float range (``json`` reads ``NaN``, ``1e999`` and 400-digit
# integers without complaint).

FINITE = {"type": "number", "description": "a finite number"}
NONNEG = {"type": "number", "minimum": 0, "description": "a non-negative finite number"}
POSITIVE = {"type": "number", "exclusiveMinimum": 0, "description": "a positive finite number"}
POS_INT = {"type": "integer", "minimum": 1, "description": "a positive integer"}
NONNEG_INT = {"type": "integer", "minimum": 0, "description": "a non-negative integer"}

TRUTH_AXIS_SCHEMA = {
    "type": "object", "description": "an object {bias, scale, noise_var}",
    "properties": {"bias": FINITE, "scale": FINITE, "noise_var": NONNEG},
    "required": ["bias", "scale"]}
SENSOR_SCHEMA = {
    "type": "object", "description": "an object {x: {bias, scale, noise_var}, y: {...}}",
    "properties": {"x": TRUTH_AXIS_SCHEMA, "y": TRUTH_AXIS_SCHEMA}, "required": ["x", "y"]}
THETA_DESIGN_SCHEMA = {
    "type": "object", "description": "an object {kind, start, stop, count, values, positions, "
                                     "per_position} (bench.tilt.ThetaDesign)",
    "properties": {
        "kind": {"enum": ["range", "list", "positions"],
                 "description": "one of 'range', 'list', 'positions'"},
        "start": FINITE, "stop": FINITE, "count": POS_INT,
        "values": {"type": "array", "items": FINITE,
                   "description": "an array of finite numbers (rad)"},
        "positions": NONNEG_INT, "per_position": NONNEG_INT},
    "additionalProperties": False,
    # kind defaults to "range" (an absent kind satisfies the first "if")
    "allOf": [
        {"if": {"properties": {"kind": {"const": "range"}}},
         "then": {"properties": {"count": {"minimum": 3, "description":
                                           "an integer ≥ 3 (kind 'range')"}}}},
        {"if": {"properties": {"kind": {"const": "list"}}, "required": ["kind"]},
         "then": {"required": ["values"], "properties": {"values": {
             "minItems": 3, "description": "at least 3 angles (kind 'list')"}}}},
        {"if": {"properties": {"kind": {"const": "positions"}}, "required": ["kind"]},
         "then": {"required": ["positions", "per_position"], "properties": {
             "positions": {"minimum": 1, "description": "a positive integer (kind 'positions')"},
             "per_position": {"minimum": 1,
                              "description": "a positive integer (kind 'positions')"}}}}]}
SWEEP_SCHEMA = {
    "type": "object", "description": "an object {kind, start, stop, duration, rate, cycles} "
                                     "(bench.tilt.SweepProfile)",
    "properties": {
        "kind": {"enum": ["constant", "accel", "updown", "sine"],
                 "description": "one of 'constant', 'accel', 'updown', 'sine'"},
        "start": FINITE, "stop": FINITE, "duration": POSITIVE, "rate": POSITIVE,
        "cycles": POSITIVE},
    "required": ["kind"], "additionalProperties": False}
THETA_SUMMARY_SCHEMA = {
    "type": "object", "description": "an object {min, max, distinct}",
    "properties": {"min": FINITE, "max": FINITE, "distinct": POS_INT}}
EST_AXIS_SCHEMA = {
    "type": "object", "description": "an object {bias, scale, bias_std, scale_std, cov}",
    "properties": {
        "bias": FINITE, "scale": FINITE, "bias_std": POSITIVE, "scale_std": POSITIVE,
        "n": POS_INT,
        "cov": {"type": "array", "minItems": 2, "maxItems": 2,
                "description": "a 2×2 array [[var_bias, cov], [cov, var_scale]]",
                "items": {"type": "array", "minItems": 2, "maxItems": 2, "items": FINITE,
                          "description": "a row of 2 finite numbers"}}},
    "required": ["bias", "scale"]}
EST_AXES_SCHEMA = {
    "type": "object", "description": "an object {x: {bias, scale, ...}, y: {...}}",
    "properties": {"x": EST_AXIS_SCHEMA, "y": EST_AXIS_SCHEMA}, "required": ["x", "y"]}
EST_TOP_SCHEMA = {"type": "object", "properties": {"g": POSITIVE, "n": POS_INT}}
ANSWER_KEY_SCHEMA = {
    "type": "object", "properties": {"students": {
        "type": "array", "description": "an array of {student, truth}",
        "items": {"type": "object", "description": "an object {student, truth}",
                  "properties": {"student": {"type": "string", "description": "a folder name"},
                                 "truth": {"type": "object", "description": "an object"}},
                  "required": ["student", "truth"]}}},
    "required": ["students"]}

def short(v: Any, depth: int = 3) -> str:
    """A bounded one-line JSON-like rendering of a value (deep, long or huge values are cut)."""
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        digits = int(v.bit_length() * 0.30103)
        return str(v) if abs(v) < 10**30 else f"an integer of ~{digits} digits"
    if isinstance(v, float):
        return {math.inf: "Infinity", -math.inf: "-Infinity"}.get(v, "NaN" if v != v else repr(v))
    if isinstance(v, str):
        text = json.dumps(v if len(v) <= 40 else v[:40] + "…", ensure_ascii=False)
        # one line whatever the string holds (U+2028, U+0085, \x1c … break lines too)
        return "".join(c if c.isprintable() else f"\\u{ord(c):04x}" for c in text)
    if isinstance(v, Mapping):
        if depth == 0:
            return "{…}"
        items = list(v.items())
        body = ", ".join(f"{short(str(k))}: {short(x, depth - 1)}" for k, x in items[:4])
        return "{" + body + (", …" if len(items) > 4 else "") + "}"
    if isinstance(v, (list, tuple)):
        if depth == 0:
            return "[…]"
        body = ", ".join(short(x, depth - 1) for x in v[:6])
        return "[" + body + (", …" if len(v) > 6 else "") + "]"
    return short(str(v))


def _is_finite_number(checker, v: Any) -> bool:
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer,
                                                              np.floating)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:  # an integer beyond the float range
        return False


def _is_finite_integer(checker, v: Any) -> bool:
    return _is_finite_number(checker, v) and float(v).is_integer()


@functools.cache
def _validator_class():
    from jsonschema import Draft202012Validator, validators

    checker = Draft202012Validator.TYPE_CHECKER.redefine_many(
        {"number": _is_finite_number, "integer": _is_finite_integer,
         # library callers pass Python objects: a tuple (asdict of a dataclass) is an array
         "array": lambda checker, v: isinstance(v, (list, tuple))})
    return validators.extend(Draft202012Validator, type_checker=checker)


def json_path(parts) -> str:
    out = ""
    for p in parts:
        if isinstance(p, int):
            out += f"[{p}]"
        else:
            key = p if p.isidentifier() else json.dumps(p, ensure_ascii=False)
            out += f".{key}" if out else key
    return out


def check_schema(obj: Any, schema: Mapping, name: str, at: tuple = ()) -> None:
    """Raise :class:`DataError` "NAME: field.path: expected …, got …" for the first violation.

    Parameters
    ----------
    obj : the JSON value.  schema : a JSON Schema (draft 2020-12) whose leaves carry a
    ``description`` of what they expect.  name : the file name for the message.
    at : the path of ``obj`` inside the file (for objects found below the top).
    """
    err = next(iter(_validator_class()(schema).iter_errors(obj)), None)
    if err is None:
        return
    where = list(at) + list(err.absolute_path)
    if err.validator == "required":
        missing = next(k for k in err.validator_value if k not in err.instance)
        raise DataError(f"{name}: {json_path([*where, missing])} is missing")
    if err.validator == "additionalProperties":
        known = list(err.schema.get("properties", {}))
        extra = next(k for k in err.instance if k not in known)
        raise DataError(f"{name}: {json_path(where) or 'top level'}: unknown key {short(extra)} "
                        f"(known: {', '.join(known)})")
    expected = err.schema.get("description") or err.message
    raise DataError(f"{name}: {json_path(where) or 'top level'}: expected {expected}, got "
                    f"{short(err.instance)}")


def _find(root: Any, pred) -> tuple[tuple, Any] | None:
    """``(path, mapping)`` of the first mapping (breadth first) for which ``pred`` holds."""
    queue: list[tuple[tuple, Any]] = [((), root)]
    while queue:
        path, d = queue.pop(0)
        if not isinstance(d, Mapping):
            continue
        if pred(d):
            return path, d
        queue.extend(((*path, k), v) for k, v in d.items() if isinstance(v, Mapping))
    return None


@dataclass(frozen=True)
class Truth:
    """What validate reads from a truth object, checked (paths for messages)."""

    params: dict | None          # true_sensor_params
    g: float | None
    design_at: tuple | None      # path of theta_design / sweep
    design: dict | None          # the checked design mapping
    static: bool
    n: int | None                # the run's sample count recorded beside the design
    summary: Mapping | None      # theta_summary {min, max, distinct}


def read_truth(truth: Any, name: str = "truth.json") -> Truth:
    """Check a ``truth.json`` object against the schemas; :class:`DataError` names the field.

    Located breadth first (a course truth nests the calibration): the first ``sensor`` with
    x/y bias and scale, the first ``g``, the first ``theta_design`` or ``sweep`` (with the
    ``n`` and ``theta_summary`` of the same object).
    """
    if not isinstance(truth, Mapping):
        raise DataError(f"{name}: expected a JSON object at the top level, got {short(truth)}")
    params = None
    hit = _find(truth, lambda d: "sensor" in d)
    good = _find(truth, lambda d: isinstance(d.get("sensor"), Mapping) and all(
        isinstance(d["sensor"].get(a), Mapping) and "bias" in d["sensor"][a]
        and "scale" in d["sensor"][a] for a in AXES))
    if good is not None or hit is not None:
        at, holder = good if good is not None else hit
        check_schema(holder["sensor"], SENSOR_SCHEMA, name, (*at, "sensor"))
        s = holder["sensor"]
        params = {}
        for a in AXES:
            params[f"bias_{a}"] = float(s[a]["bias"])
            params[f"scale_{a}"] = float(s[a]["scale"])
            if "noise_var" in s[a]:
                params[f"noise_var_{a}"] = float(s[a]["noise_var"])
    g = None
    hit = _find(truth, lambda d: "g" in d)
    if hit is not None:
        check_schema(hit[1]["g"], POSITIVE, name, (*hit[0], "g"))
        g = float(hit[1]["g"])
    design_at = design = holder = None
    static = False
    hit = _find(truth, lambda d: "theta_design" in d)
    if hit is not None:
        static, key = True, "theta_design"
        check_schema(hit[1][key], THETA_DESIGN_SCHEMA, name, (*hit[0], key))
    else:
        hit, key = _find(truth, lambda d: "sweep" in d), "sweep"
        if hit is not None:
            check_schema(hit[1][key], SWEEP_SCHEMA, name, (*hit[0], key))
    n = summary = None
    if hit is not None:
        holder = hit[1]
        design_at, design = (*hit[0], key), dict(holder[key])
        if "n" in holder:
            check_schema(holder["n"], POS_INT, name, (*hit[0], "n"))
            n = int(holder["n"])
        if "theta_summary" in holder:
            check_schema(holder["theta_summary"], THETA_SUMMARY_SCHEMA, name,
                         (*hit[0], "theta_summary"))
            summary = holder["theta_summary"]
    return Truth(params, g, design_at, design, static, n, summary)


def check_answer_key(key: Any, name: str = "answer_key.json") -> None:
    """Check a class ``answer_key.json`` object: ``students`` is a list of {student, truth}."""
    check_schema(key, ANSWER_KEY_SCHEMA, name)


def true_sensor_params(truth: Mapping) -> dict[str, float] | None:
    """``{bias_x, scale_x, bias_y, scale_y, noise_var_x, noise_var_y}`` from a truth object.

    Looks for ``sensor.{x,y}.{bias, scale, noise_var}`` (top level first, then nested, e.g.
    the calibration part of a course truth). None when absent; :class:`DataError` naming the
    field when present but malformed.
    """
    return read_truth(truth).params


def parse_estimates(est: Any, where: str = "est.json") -> dict[str, Any]:
    """Normalise an ``est.json`` object (checked against :data:`EST_AXIS_SCHEMA`).

    Accepted forms (``docs/validate.md``): ``{"axes": {"x": {...}, "y": {...}}, ...}`` (the
    ``calibrate --json`` object), the same without the ``axes`` wrapper, or flat keys
    ``bias_x, scale_x, bias_y, scale_y`` (optionally ``bias_std_x``, …). Per axis ``bias`` and
    ``scale`` are required; ``bias_std``, ``scale_std``, ``cov`` (2×2, [bias, scale]) and
    ``n`` are optional. :class:`DataError` names the file and the field path.

    Returns
    -------
    ``{"params": (4,), "std": (4,) or None, "cov": (4, 4) or None, "g": float,
    "n": {field path: int}}`` (the sample counts the file states).
    """
    if not isinstance(est, Mapping):
        raise DataError(f"{where}: expected a JSON object at the top level, got {short(est)}")
    check_schema(est, EST_TOP_SCHEMA, where)
    if "axes" in est:
        check_schema(est["axes"], EST_AXES_SCHEMA, where, ("axes",))
        axes, at = est["axes"], lambda a, k: f"axes.{a}.{k}"
    elif all(a in est for a in AXES):
        check_schema({a: est[a] for a in AXES}, EST_AXES_SCHEMA, where)
        axes, at = est, lambda a, k: f"{a}.{k}"
    elif all(f"{p}_{a}" in est for a in AXES for p in ("bias", "scale")):
        axes = {a: {k[:-2]: v for k, v in est.items() if k.endswith(f"_{a}")} for a in AXES}
        for a in AXES:  # paths named by the flat keys
            keep = ("bias", "scale", "bias_std", "scale_std", "cov")
            for k in keep:
                if k in axes[a]:
                    check_schema(axes[a][k], EST_AXIS_SCHEMA["properties"][k], where,
                                 (f"{k}_{a}",))
            axes[a] = {k: v for k, v in axes[a].items() if k in keep}
        at = lambda a, k: f"{k}_{a}"  # noqa: E731
    else:
        raise DataError(f"{where}: expected 'axes': {{'x': {{'bias', 'scale'}}, 'y': ...}} "
                        "or keys bias_x, scale_x, bias_y, scale_y (see docs/validate.md)")
    params, std, cov = np.zeros(4), np.zeros(4), np.zeros((4, 4))
    have_std, have_cov = True, True
    counts = {"n": int(est["n"])} if "n" in est else {}
    for k, a in enumerate(AXES):
        ax = axes[a]
        if "n" in ax:
            counts[at(a, "n")] = int(ax["n"])
        for j, p in enumerate(("bias", "scale")):
            params[2 * k + j] = float(ax[p])
            if f"{p}_std" in ax:
                std[2 * k + j] = float(ax[f"{p}_std"])
            else:
                have_std = False
        if "cov" in ax:
            c = np.asarray(ax["cov"], dtype=float)
            if not np.allclose(c, c.T) or np.any(np.linalg.eigvalsh(c) <= 0):
                raise DataError(f"{where}: {at(a, 'cov')} must be a symmetric positive definite "
                                "2×2 [[var_bias, cov], [cov, var_scale]]")
            cov[2 * k:2 * k + 2, 2 * k:2 * k + 2] = c
        else:
            have_cov = False
    if have_cov and not have_std:
        std, have_std = np.sqrt(np.diag(cov)), True
    return {"params": params, "std": std if have_std else None,
            "cov": cov if have_cov else None, "g": float(est.get("g", G)), "n": counts}


def load_json(path: str | Path, what: str) -> Any:
    """Read a JSON file; :class:`DataError` naming the file on failure (not JSON, not UTF-8,
    nested too deeply for the reader, an integer too long to convert)."""
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: {what} not found")
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected the {what} (JSON)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: not valid JSON ({exc})") from exc
    except RecursionError as exc:
        raise DataError(f"{path}: JSON nested too deeply to read (the {what} has a few "
                        "levels)") from exc
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise DataError(f"{path}: not readable as JSON ({exc})") from exc


__all__ = ["ANSWER_KEY_SCHEMA", "EST_AXES_SCHEMA", "EST_AXIS_SCHEMA", "EST_TOP_SCHEMA",
           "SENSOR_SCHEMA", "SWEEP_SCHEMA", "THETA_DESIGN_SCHEMA", "THETA_SUMMARY_SCHEMA",
           "TRUTH_AXIS_SCHEMA", "Truth", "check_answer_key", "check_schema", "json_path",
           "load_json", "parse_estimates", "read_truth", "short", "true_sensor_params"]
