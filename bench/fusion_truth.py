"""The part of a generated set's ``truth.json`` the fusion pictures draw: the true path and,
for a turning run, the true heading (``tiltbench fuse --truth``), read with every shape and
type checked so that a malformed file is one line naming the file and the key, never a
traceback (issue 23).

Keys (written by ``tiltbench generate``, docs/gnss.md and docs/fusion.md):
``vehicle.trajectory.samples.pos`` (n×2, m), ``.heading`` (n, rad) and ``.t`` (n, s), all
optional; the manifest must be a JSON object.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bench.validate_inputs import load_json
from calib.input_rules import DataError

SAMPLES_KEY = "vehicle.trajectory.samples"


def _numbers(value, path: Path, key: str, shape_text: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"{path}: '{key}' must be numbers ({shape_text}), got "
                        f"{type(value).__name__}") from None
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{path}: '{key}' has NaN or Inf: regenerate the truth file")
    return arr


def read_fusion_truth(path: str | Path) -> tuple[dict, np.ndarray | None,
                                                  tuple[np.ndarray, np.ndarray] | None]:
    """``(manifest, true_path (n, 2) m or None, (t (n,) s, ψ (n,) rad) or None)``.

    DataError (one line, the file and the key) when the file is not JSON, not an object, a
    level on the way to the samples is not an object, or a sample array has the wrong type,
    shape, length or non-finite values.
    """
    path = Path(path)
    manifest = load_json(path, "truth")
    if not isinstance(manifest, dict):
        raise DataError(f"{path}: the truth must be a JSON object, got "
                        f"{type(manifest).__name__}")
    node = manifest
    key = ""
    for part in SAMPLES_KEY.split("."):
        key = f"{key}.{part}" if key else part
        node = node.get(part, {})
        if not isinstance(node, dict):
            raise DataError(f"{path}: '{key}' must be an object, got {type(node).__name__}")
    pos = node.get("pos")
    true_path = None
    if pos is not None:
        true_path = _numbers(pos, path, f"{SAMPLES_KEY}.pos", "n×2 m")
        if true_path.ndim != 2 or true_path.shape[1] != 2 or true_path.shape[0] < 1:
            raise DataError(f"{path}: '{SAMPLES_KEY}.pos' must be n×2 (x, y in m), got shape "
                            f"{true_path.shape}")
    psi, ts = node.get("heading"), node.get("t")
    heading = None
    if psi is not None and ts is not None:
        t = _numbers(ts, path, f"{SAMPLES_KEY}.t", "n s")
        h = _numbers(psi, path, f"{SAMPLES_KEY}.heading", "n rad")
        if t.ndim != 1 or h.shape != t.shape or t.size < 1:
            raise DataError(f"{path}: '{SAMPLES_KEY}.heading' and '.t' must be two lists of the "
                            f"same length, got shapes {h.shape} and {t.shape}")
        if np.any(np.diff(t) <= 0):
            raise DataError(f"{path}: '{SAMPLES_KEY}.t' must be strictly increasing (s)")
        heading = (t, h)
    return manifest, true_path, heading


__all__ = ["SAMPLES_KEY", "read_fusion_truth"]
