"""The calibration file's fields, read one at a time: typed readers that refuse in one line,
the covariance check, the exact comparison of derived fields, the checksum of the defining
fields and the bounds every calibration in a file must respect.

Shared by the tilt-plane part (:mod:`calib.calibration.calfile`) and the six-face part
(:mod:`calib.calibration.calfile_sixface`) of the calibration file, so that both refuse a
bad field with the same words (``{path}: field '<field>' <what is wrong>``) and both compare
and hash their documents the same way. The format itself is documented in
``docs/calibration-file.md``.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from calib.input_rules import (  # the value rules shared with sensor.json: one home
    CORRELATION_EIG_MIN,
    G_RANGE,
    GAIN_RANGE,
    MAX_ABS_ACCEL,
    SIGMA2_RANGE,
    DataError,
)
from calib.input_rules import check_covariance as check_cov
from calib.input_rules import field_error as fail

FORMAT = "tiltbench-calibration"
"""The ``format`` value of every calibration file."""
FORMAT_VERSION = 3
"""The ``format_version`` this tiltbench writes (version 2 files are still read)."""
READ_VERSIONS = (2, 3)
"""The versions this reader knows: 2 (the tilt plane, course axes x, y in m/s²) and 3 (adds
the log's axes and unit, the source of g, and the six-face calibration of three axes)."""
RERUN = "re-run `tiltbench calibrate … --save`"
"""The way out of every refused file: write it again from its inputs."""

N_RANGE = (3, 10_000_000)
"""Samples of a calibration run: at least 3 (two parameters per axis and one dof for σ²), at
most 10⁷ (the residuals alone would make a 600 MB file; no course or bench run is near)."""
MAX_ABS_BIAS = MAX_ABS_ACCEL
"""Largest |bias|, m/s²: the largest reading any file may hold (:data:`calib.input_rules.
MAX_ABS_ACCEL`); a bias above it is not a calibration of a sensor."""
RELATIVE_TOLERANCE = 1e-9
"""Relative tolerance of the recomputed sums (χ², σ² from the residuals): a sum of N terms
recomputed in another order differs by ~N·ε ≈ 1e-12 for N = 20001; an edit differs by more."""


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 (hex) of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_ref(path: str | os.PathLike | None) -> dict | None:
    """``{"name", "sha256"}`` of a file (its name only, not the folder), or None."""
    if path is None:
        return None
    return {"name": Path(path).name, "sha256": file_sha256(path)}


def get_dotted(doc: dict, dotted: str) -> Any:
    """``doc["a"]["b"]`` for ``"a.b"`` (None where a level is missing)."""
    out: Any = doc
    for key in dotted.split("."):
        out = out.get(key) if isinstance(out, dict) else None
    return out


def plain(obj: Any) -> Any:
    """``json.dumps`` hook for what a result holds besides plain Python: numpy arrays and
    scalars (numpy floats are ``float`` already and print the same ``repr``)."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f"not JSON: {type(obj).__name__}")


def canonical_checksum(doc: dict, fields: tuple[str, ...]) -> str:
    """SHA-256 (hex) of the canonical JSON of ``fields`` of ``doc``.

    Canonical: ``{dotted field: value}``, keys sorted, no spaces, floats in ``repr`` (the
    shortest round trip), so the same numbers give the same hash whether ``doc`` was just
    built or read back from the file."""
    part = {f: get_dotted(doc, f) for f in fields}
    text = json.dumps(part, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      default=plain)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def document_json(doc: dict) -> str:
    """The text of a calibration file: keys in the order the writer built them (not sorted:
    the header is read first), indented, floats in shortest round-trip form."""
    return json.dumps(doc, indent=2, default=plain) + "\n"


# ------------------------------------------------------------------ one-line refusals
def inconsistent(path: Any, field: str, what: str) -> DataError:
    """Two parts of the file disagree: it was edited (or damaged) after calibrate wrote it."""
    return DataError(f"{path}: checksum/consistency failed: '{field}' {what}; {RERUN}")


def short(v: Any) -> str:
    """``repr(v)`` cut to 40 characters, for messages."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def is_int(v: Any) -> bool:
    """A JSON integer (not a bool, not ``300.0``)."""
    return isinstance(v, int) and not isinstance(v, bool)


def number(v: Any, field: str, path: Any) -> float:
    """``v`` as a finite float, else :func:`fail`."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise fail(path, field, f"must be a finite number, got {short(v)}")
    return float(v)


def array(v: Any, field: str, shape: tuple[int | None, ...], path: Any,
          nullable: bool = False) -> np.ndarray:
    """``v`` as a finite float array of ``shape`` (None: any length); ``nullable``: a JSON
    ``null`` entry reads as NaN (a quantity that was not measured)."""
    if isinstance(v, (str, bytes, dict, bool)):
        raise fail(path, field, f"must be numbers of shape {shape}, got {short(v)}")
    if nullable and isinstance(v, list):
        v = [np.nan if x is None else x for x in v]
    try:
        arr = np.asarray(v, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise fail(path, field, f"must be numbers of shape {shape}") from None
    if arr.ndim != len(shape) or any(s is not None and s != a
                                     for s, a in zip(shape, arr.shape, strict=True)):
        raise fail(path, field, f"must have shape {shape}, got {arr.shape}")
    bad = ~np.isfinite(arr)
    if nullable:
        bad &= ~np.isnan(arr)
    if np.any(bad):
        raise fail(path, field, "holds NaN or Infinity")
    return arr


def check_ref(doc: dict, key: str, path: Any) -> None:
    """``doc[key]`` is null or ``{"name": file name, "sha256": 64 hex digits}``."""
    v = doc[key]
    if v is None:
        return
    if (not isinstance(v, dict) or set(v) != {"name", "sha256"}
            or not isinstance(v["name"], str) or not isinstance(v["sha256"], str)
            or len(v["sha256"]) != 64 or any(c not in "0123456789abcdef" for c in v["sha256"])):
        raise fail(path, key, "must be null or {\"name\": file name, \"sha256\": 64 hex "
                   f"digits}}, got {short(v)}")


def close(a: float, b: float) -> bool:
    """Equal to :data:`RELATIVE_TOLERANCE` (a sum recomputed in another order)."""
    return abs(a - b) <= RELATIVE_TOLERANCE * max(abs(a), abs(b))


# ------------------------------------------------------------------ derived fields, checksum
def first_difference(got: Any, want: Any, where: str) -> str | None:
    """The dotted path of the first place ``got`` differs from ``want`` (exact), or None."""
    if isinstance(want, dict):
        if not isinstance(got, dict):
            return where
        for k in want:
            if k not in got:
                return f"{where}.{k}".lstrip(".")
            d = first_difference(got[k], want[k], f"{where}.{k}".lstrip("."))
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
            d = first_difference(u, v, f"{where}[{i}]")
            if d is not None:
                return d
        return None
    if isinstance(got, bool) != isinstance(want, bool) or isinstance(got, (list, dict)):
        return where
    if isinstance(want, float) and isinstance(got, (int, float)):
        return None if float(got) == want else where
    return None if got == want else where


def value_at(doc: Any, dotted: str) -> Any:
    """The value at a path of :func:`first_difference` (``a.b[3].c``), or ``<missing>``."""
    out = doc
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", dotted):
        try:
            out = out[int(part[1:-1])] if part.startswith("[") else out[part]
        except (KeyError, IndexError, TypeError):
            return "<missing>"
    return out


def check_derived(doc: dict, want: dict, path: Any, skip: tuple[str, ...]) -> None:
    """Every field of ``want`` (the document re-derived from the rebuilt calibration) but
    ``skip`` equal, exactly, to the file's; the first that differs is named with both
    values."""
    want = {k: v for k, v in want.items() if k not in skip}
    field = first_difference({k: v for k, v in doc.items() if k in want}, want, "")
    if field is not None:
        raise DataError(f"{path}: checksum/consistency failed: '{field}' is "
                        f"{short(value_at(doc, field))}, not the "
                        f"{short(value_at(want, field))} derived from the calibration (the "
                        f"file was edited); {RERUN}")


def check_checksum(doc: dict, fields: tuple[str, ...], path: Any) -> str:
    """``doc["checksum"]`` equal to ``{"algorithm": "sha256", "covers": fields, "value":
    :func:`canonical_checksum`}``; returns the value."""
    stored = doc.get("checksum")
    value = canonical_checksum(doc, fields)
    if (not isinstance(stored, dict) or stored.get("algorithm") != "sha256"
            or stored.get("covers") != list(fields) or stored.get("value") != value
            or set(stored) != {"algorithm", "covers", "value"}):
        raise DataError(f"{path}: checksum/consistency failed: 'checksum' does not match the "
                        f"fields it covers ({', '.join(fields)}): the file was edited; "
                        f"{RERUN}")
    return value


def checksum_entry(doc: dict, fields: tuple[str, ...]) -> dict:
    """The ``checksum`` object a writer puts in ``doc``."""
    return {"algorithm": "sha256", "covers": list(fields),
            "value": canonical_checksum(doc, fields)}


def cov_units(units: list[str]) -> str:
    """The unit list of a covariance of parameters in ``units`` (row by row, flattened):
    ``["m/s²", "1"]`` → ``"[(m/s²)², m/s², m/s², 1]"``."""
    def product(a: str, b: str) -> str:
        if a == "1":
            return b
        if b == "1":
            return a
        return f"({a})²" if a == b and "/" in a else (f"{a}²" if a == b else f"{a}·{b}")

    return "[" + ", ".join(product(a, b) for a in units for b in units) + "]"


__all__ = ["CORRELATION_EIG_MIN", "FORMAT", "FORMAT_VERSION", "GAIN_RANGE", "G_RANGE",
           "MAX_ABS_BIAS", "N_RANGE", "READ_VERSIONS", "RELATIVE_TOLERANCE", "RERUN",
           "SIGMA2_RANGE", "array", "canonical_checksum", "check_checksum", "check_cov",
           "check_derived", "check_ref", "checksum_entry", "close", "cov_units",
           "document_json", "fail", "file_ref", "file_sha256", "first_difference",
           "get_dotted", "inconsistent", "is_int", "number", "plain", "short", "value_at"]
