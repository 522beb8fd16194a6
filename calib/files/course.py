"""Validated readers for the course files, and atomic writers.

Every reader rejects what would silently give a wrong answer: wrong shapes, NaN/Inf,
non-monotonic time, angles that look like degrees. Messages name the file, the variable,
what is wrong and the fix.

Angles: any finite θ in radians is valid (several turns, negative, oscillating, overshooting
2π); there is no range check. Degrees are told from the readings: :func:`check_angle_units`
refuses ``tita`` when the nominal model fits θ·π/180 far better than θ (the rule is in
:mod:`calib.files.angles`).
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from calib.files.angles import compare_angle_units
from calib.files.atomic import write_bytes as atomic_write_bytes  # noqa: F401  (one home)
from calib.files.atomic import write_text as atomic_write_text  # noqa: F401
from calib.files.datos_txt import parse_datos
from calib.files.degeneracy import check_magnitudes, check_signal, refuse_beyond
from calib.input_rules import (  # noqa: F401  (re-exported: calib.files.course is where users look)
    MAX_ABS_ACCEL,
    MAX_ABS_POSITION,
    MAX_ABS_TIME,
    MAX_ABS_VELOCITY,
    DataError,
    DataNote,
    check_file,
    file_head,
)
from calib.results import readonly


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
            if getattr(self, name) is not None:
                object.__setattr__(self, name, readonly(getattr(self, name)))

    @property
    def n(self) -> int:
        return int(self.tita.shape[0])


@dataclass(frozen=True)
class Acel:
    """A vehicle run: ``t`` (M,) s, uniformly sampled; ``aerr`` (M, 2) m/s², uncorrected;
    ``gyro`` (M,) measured yaw rate, rad/s, of a turning vehicle (body-frame ``aerr``), or
    None."""

    t: np.ndarray
    aerr: np.ndarray
    source: str = "<memory>"
    gyro: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("t", "aerr", "gyro"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, readonly(getattr(self, name)))


@dataclass(frozen=True)
class Datos:
    """Contents of the course ``datos.txt``: initial position (m), velocity (m/s), noise var."""

    p0: np.ndarray
    v0: np.ndarray
    noise_var: np.ndarray


CANDIDATES: tuple[str, ...] = ("A", "B", "C", "D")
"""Candidate points every ``puntos.mat`` must hold (course: four, 1×2 each, m)."""

_NUMERIC_CLASSES = frozenset({"double", "single", "int8", "uint8", "int16", "uint16", "int32",
                              "uint32", "int64", "uint64", "sparse"})
"""MATLAB classes that hold real numbers (``scipy.io.whosmat`` names; sparse is numeric unless
it is logical, which whosmat reports as ``logical``)."""

_CLASS_WORDS = {"logical": "logical (true/false)", "char": "text (char)",
                "cell": "a cell array", "struct": "a struct", "object": "a MATLAB object",
                "function": "a function handle", "opaque": "an opaque MATLAB object"}


@dataclass(frozen=True)
class _Mat:
    """A loaded .mat file: its variables and their MATLAB classes (``whosmat``)."""

    path: Path
    variables: dict
    classes: dict

    @property
    def names(self) -> list[str]:
        return sorted(k for k in self.variables if not k.startswith("__"))

    def __contains__(self, name: str) -> bool:
        return name in self.variables


def _file_kind(path: Path) -> str | None:
    """What a file that scipy cannot read as .mat is, in words (None: nothing recognisable):
    an empty file, a text file (the course ``datos.txt``, a JSON file) or another format."""
    head = file_head(path, 4096)
    if head is None:
        return None
    if not head:
        return "is an empty file"
    if head.startswith(b"MATLAB"):
        return None  # a .mat header: a damaged or truncated MATLAB file
    if head.startswith(b"\x89HDF"):
        return "is an HDF5 file"
    if head.startswith(b"PK\x03\x04"):
        return "is a zip archive (a .npz or an office document?)"
    if head.startswith(b"\x93NUMPY"):
        return "is a NumPy .npy file"
    if head.startswith(b"RRF") or path.suffix == ".rrd":
        return "is a rerun recording"
    if b"\x00" in head and not head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return None
    from calib.files.datos_txt import decode

    try:
        text = decode(head, str(path))
    except Exception:  # not text in any encoding the course files use
        return None
    folded = text.lower()
    if text.lstrip().startswith(("{", "[")):
        return "is a JSON text file (truth.json, cal.json or a --json output?)"
    if "inicial" in folded or "varianza" in folded:
        return "is a text file (it looks like the course datos.txt)"
    return "is a text file"


def _loadmat(path: Path, expected: str = "a MATLAB .mat file") -> _Mat:
    import scipy.io

    path = Path(path)
    check_file(path, "a MATLAB .mat file")
    try:
        variables = scipy.io.loadmat(str(path))
        # loadmat returns MATLAB logicals as uint8; the class in the header tells them apart
        classes = {name: cls for name, _, cls in scipy.io.whosmat(str(path))}
    except NotImplementedError as exc:  # MATLAB v7.3 (HDF5)
        raise DataError(f"{path}: a MATLAB v7.3 (HDF5) file, which cannot be read here; save "
                        f"it with save(..., '-v7') ({exc})") from exc
    except Exception as exc:  # scipy raises several types for a bad file
        kind = _file_kind(path)
        if kind is not None:  # say what the file is, not scipy's parser error
            raise DataError(f"{path}: {kind}, not a MATLAB .mat file; this input expects "
                            f"{expected}") from exc
        raise DataError(f"{path}: not a readable MATLAB .mat file (damaged or truncated? "
                        f"scipy says: {exc})") from exc
    return _Mat(path, variables, classes)


def _note_extra(mat: _Mat, expected: tuple[str, ...], what: str) -> None:
    """Name the variables a reader ignores (e.g. MATLAB's leftover ``ans``) in a
    :class:`DataNote`; they are never used."""
    extra = [k for k in mat.names if k not in expected]
    if extra:
        warnings.warn(DataNote(
            f"{mat.path}: ignored variable(s) {', '.join(repr(k) for k in extra)}; "
            f"{what} uses only {', '.join(expected)}"), stacklevel=3)


def _require(mat: _Mat, names: tuple[str, ...]) -> None:
    missing = [k for k in names if k not in mat]
    if missing:
        found = ", ".join(mat.names) or "no variables"
        raise DataError(
            f"{mat.path}: variable(s) {', '.join(repr(k) for k in missing)} missing "
            f"(found: {found}); the file must hold {', '.join(names)}")


def _get(mat: _Mat, path: Path, name: str) -> np.ndarray:
    _require(mat, (name,))
    return _numeric(mat.variables[name], path, name, mat.classes.get(name))


def _numeric(value, where, name: str, mclass: str | None = None) -> np.ndarray:
    """A .mat variable as a float64 array (single precision and integers converted exactly).

    Logical, text, cell, struct, object and complex variables are errors: none of them is a
    number a reader can use (a logical θ would be read as 0/1 rad).
    """
    if mclass is not None and mclass not in _NUMERIC_CLASSES:
        what = _CLASS_WORDS.get(mclass, f"of MATLAB class '{mclass}'")
        raise DataError(f"{where}: variable '{name}' is {what}; expected real numbers "
                        "(double or single)")
    if hasattr(value, "toarray"):  # scipy.sparse: a MATLAB sparse matrix
        value = value.toarray()
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        what = {"b": "logical (true/false)", "c": "complex", "U": "text (char)",
                "S": "text (char)", "O": "a cell array or struct",
                "V": "a struct"}.get(arr.dtype.kind, f"of type {arr.dtype}")
        raise DataError(f"{where}: variable '{name}' is {what}; expected real numbers "
                        "(double or single)")
    # float32 → float64 is exact: equal angles stay equal, distinct ones distinct, so every
    # comparison made later happens in the file's own precision
    return arr.astype(np.float64)


def _check_magnitude(arr: np.ndarray, limit: float, where: str, name: str, unit: str) -> None:
    refuse_beyond(arr, limit, lambda big: f"{where}: variable '{name}' reaches {big:.3g} "
                  f"{unit}, beyond {limit:.3g} {unit}; check the units or the file", DataError)


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
    """Refuse angles whose readings say they are degrees (rule: :mod:`calib.files.angles`).

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
    """Check shapes, finiteness, units, the data's content and time order; return an
    :class:`Ensayo`.

    Any finite ``tita`` in radians is accepted; it is refused as degrees only when the
    readings say so (:func:`check_angle_units`, rule in :mod:`calib.files.angles`). Data that
    cannot determine bias and scale — one distinct θ, a dead sensor, a column that does not
    follow gravity at all — are refused with a message about the data
    (:func:`calib.files.degeneracy.check_signal`).
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
    check_magnitudes(tita, datos, where)
    check_angle_units(tita, datos, where)
    check_signal(tita, datos, where)
    if t is not None:
        t = _column(np.asarray(t, dtype=float), where, "t")
        if t.shape[0] != tita.shape[0]:
            raise DataError(f"{where}: 't' has {t.shape[0]} samples, 'tita' {tita.shape[0]}")
        check_finite(t, where, "t")
        _check_magnitude(t, MAX_ABS_TIME, where, "t", "s")
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
    DataError : missing variable, a variable that is not real numbers (logical, char, cell,
        struct, complex), bad shape, NaN/Inf, non-monotonic ``t``, ``tita`` that the
        readings show to be in degrees (:mod:`calib.files.angles`), or data that cannot determine
        the errors (:mod:`calib.files.degeneracy`: one distinct θ, a dead sensor, no gravity
        signal). The message names the file, the variable and the fix. Any finite ``tita``
        in radians is valid: several turns, negative, oscillating or overshooting 2π; double
        or single precision. Other variables (MATLAB's ``ans``) are ignored and named in a
        :class:`DataNote` warning.

    Examples
    --------
    >>> from calib import read_ensayo
    >>> e = read_ensayo("ensayo.mat")  # doctest: +SKIP
    >>> e.n, e.datos.shape  # doctest: +SKIP
    (20001, (20001, 2))
    """
    path = Path(path)
    mat = _loadmat(path, "the ensayo .mat file (tita N×1 rad, datos N×2 m/s²)")
    _require(mat, ("tita", "datos"))
    tita, datos = _get(mat, path, "tita"), _get(mat, path, "datos")
    t = _get(mat, path, "t") if "t" in mat else None
    e = validate_ensayo(tita, datos, t, str(path))
    _note_extra(mat, ("tita", "datos", "t", "pose"), "a calibration run")
    return e


@dataclass(frozen=True)
class Fixes:
    """Position fixes of a receiver: ``t_gps`` (M,) s increasing, ``pos`` (M, 2) m, ``vel``
    (M, 2) m/s or None."""

    t_gps: np.ndarray
    pos: np.ndarray
    vel: np.ndarray | None = None
    source: str = "<memory>"


def uniformly_sampled(t: np.ndarray) -> bool:
    """Whether the times ``t`` (M,) s are evenly spaced, as a vehicle run's must be to be
    integrated: every step within ``1e-6·h̄ + 1e-9`` s of the mean step ``h̄``."""
    d = np.diff(t)
    if d.size == 0:
        return True
    return not bool(np.max(np.abs(d - d.mean())) > 1e-6 * max(d.mean(), 1e-12) + 1e-9)


def _time_and_pair(path: str | os.PathLike, expected: str, time: str, pair: str
                   ) -> tuple[_Mat, np.ndarray, np.ndarray]:
    """The .mat file of a run (``expected``: what it should hold, for the message when it is
    not one), its time variable ``time`` as (M,) s and its variable ``pair`` as (M', 2):
    both present and shaped (:func:`_column`, :func:`_two_columns`), nothing else checked."""
    path = Path(path)
    mat = _loadmat(path, expected)
    _require(mat, (time, pair))
    where = str(path)
    return (mat, _column(_get(mat, path, time), where, time),
            _two_columns(_get(mat, path, pair), where, pair))


def read_gps(path: str | os.PathLike) -> Fixes:
    """Read ``gps.mat``: ``t_gps`` (M×1, s, increasing), ``pos`` (M×2, m) and optionally
    ``vel`` (M×2, m/s) (``tiltbench generate vehicle|course --gps``, docs/gnss.md)."""
    mat, t, pos = _time_and_pair(
        path, "the gps .mat file (t_gps M×1 s, pos M×2 m, optional vel M×2 m/s)", "t_gps", "pos")
    where = str(mat.path)
    vel = _two_columns(_get(mat, mat.path, "vel"), where, "vel") if "vel" in mat else None
    for name, arr in (("pos", pos), ("vel", vel)):
        if arr is not None and arr.shape[0] != t.shape[0]:
            raise DataError(f"{where}: 't_gps' has {t.shape[0]} fixes but '{name}' has "
                            f"{arr.shape[0]}")
    check_finite(t, where, "t_gps")
    check_finite(pos, where, "pos")
    _check_magnitude(t, MAX_ABS_TIME, where, "t_gps", "s")
    _check_magnitude(pos, MAX_ABS_POSITION, where, "pos", "m")
    if vel is not None:
        check_finite(vel, where, "vel")
        _check_magnitude(vel, MAX_ABS_VELOCITY, where, "vel", "m/s")
    if t.shape[0] < 1:
        raise DataError(f"{where}: no fixes in 't_gps'")
    check_time(t, where, "t_gps")
    _note_extra(mat, ("t_gps", "pos", "vel"), "a receiver's fixes")
    return Fixes(t_gps=t, pos=pos, vel=vel, source=where)


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
    mat, t, aerr = _time_and_pair(path, "the acel .mat file (t M×1 s, Aerr M×2 m/s²)", "t",
                                  "Aerr")
    where = str(mat.path)
    if aerr.shape[0] != t.shape[0]:
        raise DataError(f"{where}: 't' has {t.shape[0]} samples but 'Aerr' has {aerr.shape[0]}")
    check_finite(t, where, "t")
    check_finite(aerr, where, "Aerr")
    _check_magnitude(t, MAX_ABS_TIME, where, "t", "s")
    _check_magnitude(aerr, MAX_ABS_ACCEL, where, "Aerr", "m/s²")
    if t.shape[0] < 3:
        raise DataError(f"{where}: only {t.shape[0]} samples in 't'; at least 3 are needed "
                        "to integrate")
    check_time(t, where)
    if not uniformly_sampled(t):
        raise DataError(f"{where}: 't' is not uniformly sampled; resample before integrating")
    gyro = None
    if "gyro" in mat:  # turning vehicle: yaw rate M×1, rad/s (docs/fusion.md)
        gyro = _column(_get(mat, mat.path, "gyro"), where, "gyro")
        if gyro.shape[0] != t.shape[0]:
            raise DataError(f"{where}: 't' has {t.shape[0]} samples but 'gyro' has "
                            f"{gyro.shape[0]}")
        check_finite(gyro, where, "gyro")
    _note_extra(mat, ("t", "Aerr", "gyro"), "a vehicle run")
    return Acel(t=t, aerr=aerr, source=where, gyro=gyro)


def read_puntos(path: str | os.PathLike,
                names: tuple[str, ...] = CANDIDATES) -> dict[str, np.ndarray]:
    """Read a course ``puntos.mat``: candidate points ``A``, ``B``, ``C``, ``D`` (1×2 each, m).

    Parameters
    ----------
    path : the MATLAB v5 file; each candidate is one variable ``[x, y]`` (1×2 or 2×1), m.
    names : the candidates the file must hold (course: ``A`` … ``D``, :data:`CANDIDATES`).

    Returns
    -------
    dict : name → (2,) position, m, in the order of ``names``.

    Raises
    ------
    DataError : a candidate missing (a file truncated after ``A`` and ``B`` is refused, the
        missing ones named), not real numbers, not 1×2, NaN/Inf or absurdly large.
        Other variables (MATLAB's leftover ``ans``) are ignored — never a further
        candidate — and named in a :class:`DataNote` warning.

    Examples
    --------
    >>> from calib import read_puntos
    >>> sorted(read_puntos("puntos.mat"))  # doctest: +SKIP
    ['A', 'B', 'C', 'D']
    """
    path = Path(path)
    names = tuple(names)
    if len(names) < 2:
        raise ValueError(f"read_puntos needs at least two candidate names, got {names}")
    mat = _loadmat(path, "the puntos .mat file (A, B, C, D, 1×2 m each)")
    missing = [k for k in names if k not in mat]
    if missing:
        found = ", ".join(mat.names) or "no variables"
        raise DataError(
            f"{path}: candidate point(s) {', '.join(missing)} missing (found: {found}); "
            f"puntos.mat must hold {', '.join(names)}, each 1×2 [x y] in m — is the file "
            "truncated?")
    out = {}
    for name in names:
        p = _numeric(mat.variables[name], path, name, mat.classes.get(name))
        if p.size != 2 or (p.ndim == 2 and 1 not in p.shape) or p.ndim > 2:
            raise DataError(f"{path}: variable '{name}' must be 1×2 [x y] in m, got shape "
                            f"{p.shape}")
        p = p.ravel()
        check_finite(p, str(path), name)
        _check_magnitude(p, MAX_ABS_POSITION, str(path), name, "m")
        out[name] = p
    _note_extra(mat, names, "the arrival decision")
    return out


def read_datos(path: str | os.PathLike) -> Datos:
    """Read the course ``datos.txt`` (Spanish wording; three bracketed pairs).

    Lines: ``Posición inicial = [x y]``, ``Velocidad inicial = [vx vy]``,
    ``varianza del ruido de los acelerómetros = [σx² σy²]``. Matching is by keyword
    (``posici``, ``velocidad``, ``varianza``), so case, accents and spacing do not matter.
    UTF-8 (BOM or not), UTF-16, Latin-1; CRLF; the Unicode minus and dashes as minus; decimal
    commas where unambiguous (rules: :mod:`calib.files.datos_txt`).

    Parameters
    ----------
    path : the text file.

    Returns
    -------
    Datos : ``p0`` (2,) m, ``v0`` (2,) m/s, ``noise_var`` (2,) (m/s²)².

    Raises
    ------
    DataError : a field missing or given twice, not two numbers, a bad number, a variance
        that is not positive — naming the file, the line and the field.

    Examples
    --------
    >>> from calib import read_datos
    >>> d = read_datos("datos.txt")  # doctest: +SKIP
    >>> d.v0.tolist(), d.noise_var.tolist()  # doctest: +SKIP
    ([1.0, 3.0], [0.25, 0.64])
    """
    path = Path(path)
    check_file(path, "the course datos.txt")
    found = parse_datos(path.read_bytes(), str(path))
    return Datos(**{k: np.array(v, dtype=float) for k, v in found.items()})


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
