"""Validated readers for the course files, and atomic writers.

Every reader rejects what would silently give a wrong answer: wrong shapes, NaN/Inf,
non-monotonic time, angles that look like degrees. Messages name the file, the variable,
what is wrong and the fix.

Angles: any finite θ in radians is valid (several turns, negative, oscillating, overshooting
2π); there is no range check. Degrees are told from the readings: :func:`check_angle_units`
refuses ``tita`` when the nominal model fits θ·π/180 far better than θ (the rule is in
:mod:`calib.angles`).
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from calib.angles import compare_angle_units


class DataError(ValueError):
    """Input data that cannot be used as given (message names file, variable and fix)."""


@dataclass(frozen=True)
class Ensayo:
    """A calibration run ("ensayo").

    Attributes
    ----------
    tita : (N,) float, rad — table angle reported by the encoder.
    datos : (N, 2) float, m/s² — measured [A_mx, A_my].
    t : (N,) float, s, or None — sample times (sweeps); None for the course file.
    source : str — where it came from (for messages).
    """

    tita: np.ndarray
    datos: np.ndarray
    t: np.ndarray | None = None
    source: str = "<memory>"

    def __post_init__(self) -> None:
        for name in ("tita", "datos", "t"):
            value = getattr(self, name)
            if value is not None:
                arr = np.array(value, dtype=float)
                arr.setflags(write=False)
                object.__setattr__(self, name, arr)

    @property
    def n(self) -> int:
        return int(self.tita.shape[0])


@dataclass(frozen=True)
class Acel:
    """A vehicle run: ``t`` (M,) s, uniformly sampled; ``aerr`` (M, 2) m/s², uncorrected."""

    t: np.ndarray
    aerr: np.ndarray
    source: str = "<memory>"

    def __post_init__(self) -> None:
        for name in ("t", "aerr"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)


@dataclass(frozen=True)
class Datos:
    """Contents of the course ``datos.txt``: initial position (m), velocity (m/s), noise var."""

    p0: np.ndarray
    v0: np.ndarray
    noise_var: np.ndarray


def _loadmat(path: Path) -> dict:
    import scipy.io

    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: file not found")
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected a MATLAB .mat file")
    try:
        return scipy.io.loadmat(str(path))
    except Exception as exc:  # scipy raises several types for a bad file
        raise DataError(f"{path}: not a readable MATLAB .mat file ({exc})") from exc


def _get(mat: dict, path: Path, name: str) -> np.ndarray:
    if name not in mat:
        found = sorted(k for k in mat if not k.startswith("__"))
        raise DataError(f"{path}: variable '{name}' is missing (found: {', '.join(found)})")
    return _numeric(mat[name], path, name)


def _numeric(value, where, name: str) -> np.ndarray:
    """A .mat variable as a real float array; text, cells, structs and complex are errors."""
    arr = np.asarray(value)
    if arr.dtype.kind not in "biuf":
        what = {"c": "complex", "U": "text", "S": "text", "O": "a cell array or struct",
                "V": "a struct"}.get(arr.dtype.kind, f"of type {arr.dtype}")
        raise DataError(f"{where}: variable '{name}' is {what}; expected real numbers")
    return arr.astype(float)


def check_finite(arr: np.ndarray, where: str, name: str) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise DataError(
            f"{where}: variable '{name}' has {int(bad.sum())} NaN/Inf value(s), first at "
            f"index {tuple(int(i) for i in idx)}; remove or repair those samples"
        )


def check_angle_units(tita: np.ndarray, datos: np.ndarray, where: str,
                      name: str = "tita") -> None:
    """Refuse angles whose readings say they are degrees (rule: :mod:`calib.angles`).

    No range check: any finite θ in radians is valid. ``tita`` (N,) and ``datos`` (N, 2) m/s²
    must already be finite and of matching length.
    """
    units = compare_angle_units(tita, datos)
    if units.looks_like_degrees:
        raise DataError(
            f"{where}: variable '{name}' looks like degrees, not radians: the nominal model "
            f"(A_rx = -g sin θ, A_ry = -g cos θ) fits θ·π/180 far better than θ "
            f"({units.summary()}); convert the angles to radians (θ·π/180) and read the file "
            "again"
        )


def check_time(t: np.ndarray, where: str, name: str = "t") -> None:
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0))
        raise DataError(
            f"{where}: variable '{name}' is not strictly increasing (t[{i}] = {t[i]:.6g}, "
            f"t[{i + 1}] = {t[i + 1]:.6g}); samples must be in time order"
        )


def _column(arr: np.ndarray, where: str, name: str) -> np.ndarray:
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.ravel()
    if arr.ndim != 1:
        raise DataError(f"{where}: variable '{name}' must be N×1, got shape {arr.shape}")
    return arr


def _two_columns(arr: np.ndarray, where: str, name: str) -> np.ndarray:
    if arr.ndim != 2 or 2 not in arr.shape:
        raise DataError(f"{where}: variable '{name}' must be N×2 (x, y), got shape {arr.shape}")
    if arr.shape[1] != 2:  # stored 2×N: transpose, columns are x and y
        arr = arr.T
    return arr


def validate_ensayo(
    tita: np.ndarray, datos: np.ndarray, t: np.ndarray | None = None, where: str = "<memory>"
) -> Ensayo:
    """Check shapes, finiteness, units and time order; return an :class:`Ensayo`.

    Any finite ``tita`` in radians is accepted; it is refused as degrees only when the
    readings say so (:func:`check_angle_units`, rule in :mod:`calib.angles`).
    """
    tita = _column(np.asarray(tita, dtype=float), where, "tita")
    datos = _two_columns(np.asarray(datos, dtype=float), where, "datos")
    if datos.shape[0] != tita.shape[0]:
        raise DataError(
            f"{where}: 'tita' has {tita.shape[0]} samples but 'datos' has {datos.shape[0]}; "
            "they must have one row per sample"
        )
    if tita.shape[0] < 3:
        raise DataError(f"{where}: only {tita.shape[0]} samples; at least 3 are needed")
    check_finite(tita, where, "tita")
    check_finite(datos, where, "datos")
    check_angle_units(tita, datos, where)
    if t is not None:
        t = _column(np.asarray(t, dtype=float), where, "t")
        if t.shape[0] != tita.shape[0]:
            raise DataError(f"{where}: 't' has {t.shape[0]} samples, 'tita' {tita.shape[0]}")
        check_finite(t, where, "t")
        check_time(t, where)
    return Ensayo(tita=tita, datos=datos, t=t, source=where)


def read_ensayo(path: str | os.PathLike) -> Ensayo:
    """Read a course ``ensayo.mat``: ``tita`` (N×1, rad), ``datos`` (N×2, m/s²), optional ``t``.

    Parameters
    ----------
    path : the MATLAB v5 file with ``tita`` (N×1 or 1×N) rad, ``datos`` (N×2) m/s²
        ``[A_mx, A_my]`` and optionally ``t`` (N) s, strictly increasing.

    Returns
    -------
    Ensayo : ``tita`` (N,) rad, ``datos`` (N, 2) m/s², ``t`` (N,) s or None.

    Raises
    ------
    DataError : missing variable, bad shape, NaN/Inf, non-monotonic ``t``, or ``tita`` that
        the readings show to be in degrees (:mod:`calib.angles`; the message names the file,
        the variable and the fix). Any finite ``tita`` in radians is valid: several turns,
        negative, oscillating or overshooting 2π.

    Examples
    --------
    >>> from calib import read_ensayo
    >>> e = read_ensayo("ensayo.mat")  # doctest: +SKIP
    >>> e.n, e.datos.shape  # doctest: +SKIP
    (20001, (20001, 2))
    """
    path = Path(path)
    mat = _loadmat(path)
    t = _get(mat, path, "t") if "t" in mat else None
    return validate_ensayo(_get(mat, path, "tita"), _get(mat, path, "datos"), t, str(path))


def read_acel(path: str | os.PathLike) -> Acel:
    """Read a course ``acel.mat``: ``t`` (M×1, s, uniform), ``Aerr`` (M×2, m/s²).

    Parameters
    ----------
    path : the MATLAB v5 file with ``t`` (M) s, uniformly sampled and increasing, and
        ``Aerr`` (M×2) uncorrected vehicle accelerations ``[x, y]``, m/s².

    Returns
    -------
    Acel : ``t`` (M,) s, ``aerr`` (M, 2) m/s².

    Examples
    --------
    >>> from calib import read_acel
    >>> a = read_acel("acel.mat")  # doctest: +SKIP
    >>> a.t.shape, a.aerr.shape  # doctest: +SKIP
    ((6000,), (6000, 2))
    """
    path = Path(path)
    mat = _loadmat(path)
    where = str(path)
    t = _column(_get(mat, path, "t"), where, "t")
    aerr = _two_columns(_get(mat, path, "Aerr"), where, "Aerr")
    if aerr.shape[0] != t.shape[0]:
        raise DataError(f"{where}: 't' has {t.shape[0]} samples but 'Aerr' has {aerr.shape[0]}")
    check_finite(t, where, "t")
    check_finite(aerr, where, "Aerr")
    check_time(t, where)
    d = np.diff(t)
    if d.size and np.max(np.abs(d - d.mean())) > 1e-6 * max(d.mean(), 1e-12) + 1e-9:
        raise DataError(f"{where}: 't' is not uniformly sampled; resample before integrating")
    return Acel(t=t, aerr=aerr, source=where)


def read_puntos(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Read a course ``puntos.mat``: candidate points (1×2 each, m), named by letter.

    Parameters
    ----------
    path : the MATLAB v5 file; every variable is one candidate ``[x, y]`` (1×2), m.

    Returns
    -------
    dict : name → (2,) position, m, sorted by name (at least two).

    Examples
    --------
    >>> from calib import read_puntos
    >>> sorted(read_puntos("puntos.mat"))  # doctest: +SKIP
    ['A', 'B', 'C', 'D']
    """
    path = Path(path)
    mat = _loadmat(path)
    out = {}
    for name in sorted(k for k in mat if not k.startswith("__")):
        p = _numeric(mat[name], path, name).ravel()
        if p.shape != (2,):
            raise DataError(f"{path}: variable '{name}' must be 1×2 (x, y), got {p.shape}")
        check_finite(p, str(path), name)
        out[name] = p
    if len(out) < 2:
        raise DataError(f"{path}: needs at least two candidate points, found {len(out)}")
    return out


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def read_datos(path: str | os.PathLike) -> Datos:
    """Read the course ``datos.txt`` (Spanish wording; three bracketed pairs).

    Lines: ``Posición inicial = [x y]``, ``Velocidad inicial = [vx vy]``,
    ``varianza del ruido de los acelerómetros = [σx² σy²]``. Matching is by keyword
    (``posici``, ``velocidad``, ``varianza``), so accents and spacing do not matter.

    Parameters
    ----------
    path : the text file.

    Returns
    -------
    Datos : ``p0`` (2,) m, ``v0`` (2,) m/s, ``noise_var`` (2,) (m/s²)².

    Examples
    --------
    >>> from calib import read_datos
    >>> d = read_datos("datos.txt")  # doctest: +SKIP
    >>> d.v0.tolist(), d.noise_var.tolist()  # doctest: +SKIP
    ([1.0, 3.0], [0.25, 0.64])
    """
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: file not found")
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected the course datos.txt")
    text = path.read_bytes().decode("utf-8", errors="replace")
    found: dict[str, np.ndarray] = {}
    for line in text.splitlines():
        low = line.lower()
        m = re.search(r"\[([^\]]*)\]", line)
        if not m:
            continue
        nums = [float(v) for v in re.findall(_NUM, m.group(1))]
        key = "p0" if "posici" in low else "v0" if "velocidad" in low else (
            "noise_var" if "varianza" in low else None)
        if key is None:
            continue
        if len(nums) != 2:
            raise DataError(f"{path}: line {line.strip()!r} must hold two numbers in [ ]")
        found[key] = np.array(nums)
    missing = [k for k in ("p0", "v0", "noise_var") if k not in found]
    if missing:
        raise DataError(f"{path}: could not find {', '.join(missing)} (initial position, "
                        "initial velocity, noise variances) in the course wording")
    if np.any(found["noise_var"] <= 0):
        raise DataError(f"{path}: noise variances must be positive, got {found['noise_var']}")
    return Datos(**found)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, force: bool = False) -> Path:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    Refuses to replace an existing file unless ``force`` (:class:`FileExistsError`); a crash
    never leaves half a file.
    """
    path = Path(path)
    if path.is_dir():
        raise DataError(f"{path}: is a directory; expected an output file name")
    if path.exists() and not force:
        raise FileExistsError(f"{path}: exists")
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:  # name the file asked for, not the temporary one
        raise type(exc)(exc.errno, exc.strerror, str(path)) from exc
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        # mkstemp creates 0600; give the file the mode a plain open() would (umask applied).
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def atomic_write_text(path: str | os.PathLike, text: str, force: bool = False) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"), force=force)


def to_jsonable(obj):
    """Convert numpy scalars/arrays in nested containers to plain Python for ``json``."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def dumps(obj) -> str:
    """Stable JSON text (sorted keys, repr floats) so the same data gives the same bytes."""
    return json.dumps(to_jsonable(obj), indent=2, sort_keys=True) + "\n"
