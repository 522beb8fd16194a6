"""``.mat`` logs with other variable names (``--map tita=angle,datos=acc,t=time``), and the
files ``tiltbench import`` writes when θ is unknown (``datos``, ``t``, ``pose``; no ``tita``).

Roles (course names, the keys of ``--map``): ``tita`` angle (N), ``datos`` accelerations
(N×2 as the course's x, y, or N×3 as x, y, z — ``--axes`` then picks two), ``t`` (N) s,
``pose`` (N) integer labels (-1 moving), ``Aerr`` (the vehicle run's N×2), ``gyro`` (N)
rad/s about the tilt axis. A mapped ``datos``/``Aerr`` is in m/s² — the course variable's
unit — unless ``--units`` states another; ``tita`` is in rad unless ``--angle-unit deg``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from calib.input_rules import DataError
from calib.logs.table import RawLog

ROLES = ("tita", "datos", "t", "pose", "Aerr", "gyro")
"""Course variable names ``--map`` may map."""


def read_mat(path: Path, mapping: dict[str, str] | None = None) -> RawLog:
    """Read a ``.mat`` log whose variables are named by ``mapping`` (course name → file name;
    unmapped roles use the course name when the file has it).

    Raises
    ------
    DataError : an unknown role, a mapped variable missing (the file's variables listed),
        no acceleration variable, non-numeric variables, shapes that do not match.
    """
    import scipy.io

    mapping = dict(mapping or {})
    bad = sorted(set(mapping) - set(ROLES))
    if bad:
        raise DataError(f"--map: unknown name(s) {', '.join(bad)}; map the course names "
                        f"{', '.join(ROLES)} to the file's variables (e.g. datos=acc)")
    try:
        mat = scipy.io.loadmat(str(path))
    except NotImplementedError as exc:
        raise DataError(f"{path}: a MATLAB v7.3 (HDF5) file, which cannot be read here; save "
                        "it with save(..., '-v7')") from exc
    except Exception as exc:  # scipy raises several types for a bad file
        raise DataError(f"{path}: not a readable MATLAB .mat file ({exc})") from exc
    names = sorted(k for k in mat if not k.startswith("__"))
    for role, name in mapping.items():
        if name not in mat:
            raise DataError(f"{path}: --map {role}={name}: no variable '{name}' (found: "
                            f"{', '.join(names) or 'none'})")
    got = {role: mapping.get(role, role) for role in ROLES if mapping.get(role, role) in mat}

    def numeric(role: str) -> np.ndarray:
        arr = np.asarray(mat[got[role]])
        if arr.dtype.kind not in "iuf":
            raise DataError(f"{path}: variable '{got[role]}' ({role}) is not real numbers")
        return arr.astype(float)

    def column(role: str) -> np.ndarray:
        arr = numeric(role)
        if arr.ndim == 2 and 1 in arr.shape:
            arr = arr.ravel()
        if arr.ndim != 1:
            raise DataError(f"{path}: variable '{got[role]}' ({role}) must be N×1, got shape "
                            f"{arr.shape}")
        return arr

    key = "datos" if "datos" in got else "Aerr" if "Aerr" in got else None
    if key is None:
        raise DataError(f"{path}: no acceleration variable (found: {', '.join(names)}); "
                        "name it with --map datos=NAME")
    acc = numeric(key)
    if acc.ndim != 2 or not ({2, 3} & set(acc.shape)):
        raise DataError(f"{path}: variable '{got[key]}' must be N×2 or N×3, got shape "
                        f"{acc.shape}")
    if acc.shape[1] not in (2, 3):
        acc = acc.T
    n = acc.shape[0]
    out = {"t": None, "tita": None, "pose": None, "gyro": None}
    for role in out:
        if role in got:
            out[role] = column(role)
            if out[role].shape[0] != n:
                raise DataError(f"{path}: '{got[role]}' has {out[role].shape[0]} samples but "
                                f"'{got[key]}' has {n}; one row per sample")
    label = None
    if out["pose"] is not None:
        label = np.array([str(int(v)) for v in out["pose"]], dtype=object)
    return RawLog(
        fmt="mat", acc={k: acc[:, i] for i, k in enumerate("xyz"[:acc.shape[1]])},
        acc_unit=None, t=out["t"], theta=out["tita"], label=label,
        gyro={} if out["gyro"] is None else {"tilt": out["gyro"]}, gyro_unit="rad/s",
        rows=None, row_word="index",
        mapping={role: name for role, name in got.items()},
        notes={"variables": names, "default_unit": "m/s2"})


__all__ = ["ROLES", "read_mat"]
