"""Readers for the logs people have: one entry point, :func:`read_log`, for every command that
reads readings (``calibrate``, ``gap``, ``trajectory``, ``fuse``, ``noise``, ``import``).

A log becomes an :class:`ImuLog`: the two tilt-plane axes in m/s² (after ``--axes`` picked and
signed them from a 3-axis IMU), optional sample times, optional table angle θ (rad), optional
held-pose labels, optional gyro rate about the tilt axis and, for a 3-axis log, the third
axis (``acc_normal``, along the tilt axis), plus a provenance record (source
name and sha256, format, column mapping, units, detected segments) that ``tiltbench import``
writes beside the course files.

Formats (``--format``, else recognized from the content; one module each in
:mod:`calib.logs`): the course MATLAB files (``ensayo.mat`` tita/datos[/t][/pose],
``acel.mat`` t/Aerr[/gyro], and the θ-unknown ``ensayo.mat`` of ``tiltbench import``: datos,
t, pose); CSV/TSV with a header, phyphox and Sensor Logger exports
(:mod:`calib.logs.csvlog`); ROS 1/2 bags of ``sensor_msgs/Imu``
(:mod:`calib.logs.rosbag`); any ``.mat`` with ``--map`` (:mod:`calib.logs.matlog`).

Conventions
-----------
* Units: SI. Acceleration units are stated (``--units``) or recognized from the header or the
  format's documentation, never guessed: ``m/s2``; ``g`` and ``mg`` converted with the
  command's g (:data:`calib.conventions.G` = 9.8 m/s² unless ``--g``); ``counts`` as
  ``a = counts / sensitivity · g`` (``--sensitivity`` counts per g).
* Axes: ``--axes a,b`` (each ``x``, ``y`` or ``z`` with an optional ``-``) makes the log's
  signed axis ``a`` the tilt plane's x and ``b`` its y, so that the course signs hold:
  ``A_rx = -g sin θ``, ``A_ry = -g cos θ``. The gyro rate kept is the one about the tilt axis
  ``n = â × b̂`` (right-handed: ``--axes x,y`` keeps ``ω_z``, ``--axes -y,z`` keeps
  ``-ω_x``); with the course signs θ grows by a right-handed turn about ``n``, so at rest
  between poses the kept rate is ``dθ/dt``.
* θ: a θ column in rad or deg (``--angle-unit``, or the header's unit); without either the
  data-based degrees check of :mod:`calib.files.angles` decides (never a range).
* Poses: a label column, or the detector of :mod:`calib.logs.poses` (thresholds from the log's own
  quiet level). ``--poses`` gives each detected (or labelled) pose's angle in order; the log
  then keeps only the held samples — they make the course ensayo — and its provenance says
  so. Without angles θ stays unknown (``theta`` None) and ``pose`` carries the labels.

Validation (one-line :class:`calib.input_rules.DataError` naming the file, the line, message
or index, and the fix): missing header, unknown units, non-numeric cells, NaN/Inf, time not
strictly increasing, gaps in time longer than :data:`GAP_FACTOR` median steps (refused unless
``--allow-gaps``, which the commands that can use the stretches between gaps pass themselves
or on request: held poses on both sides stay valid and ``noise`` pools its Allan variance over
the segments, while integration and an ``acel.mat`` import refuse a gap; the gaps are listed
in the provenance), saturated
stretches (:data:`SATURATION_RUN` or more equal samples at a column's extreme value, that
value at least g/2 in size; refused unless ``--allow-saturation``, for a sensor so coarse
that a held pose reads one constant value).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from calib.conventions import STANDARD_GRAVITY, G
from calib.input_rules import MAX_ABS_TIME, DataError, file_head
from calib.logs.physics import check_one_g
from calib.logs.poses import LOOSE, MARGIN
from calib.logs.table import ACCEL_UNITS, GAP_FACTOR, GYRO_UNITS, RawLog
from calib.results import readonly

LOG_FORMAT_VERSION = 1
"""Version of the provenance record (``provenance.json``)."""
PROVENANCE_UNITS: dict[str, str] = {
    "format_version": "—", "samples.*": "samples", "reader.messages": "count",
    "units.g": "m/s²", "units.acc_to_m_s2": "m/s² per log unit",
    "units.sensitivity_counts_per_g": "counts/g",
    "gaps.t": "s", "gaps.length_s": "s", "gaps.median_step_s": "s", "gaps.after": "—",
    "pose_angles_rad": "rad", "poses_out_of_plane": "—",
    "plane_faces.hold": "—", "plane_faces.theta_rad": "rad",
    "resampled.step_s": "s", "resampled.max_deviation_from_grid_s": "s",
    "resampled.samples_in": "samples", "resampled.samples_out": "samples",
    "written.*.*.*": "count (rows, columns of each variable of FILE.mat)"}
"""Unit of every number a provenance record can hold (key paths as :mod:`calib.units` writes
them; list items share their list's path). The detected poses and the gyro angle carry their
own maps (:func:`provenance_units`)."""
_BAG_SUFFIXES = (".bag", ".db3", ".mcap")
"""Names of ROS bag files: one that does not read as a bag is refused as such, not as a .mat."""
SATURATION_RUN = 10
"""This many equal consecutive samples at a column's extreme value are a saturated stretch."""
MOVING_LABELS = ("", "-1", "moving", "nan", "none")
"""Label cells that mean "moving" (compared in lower case)."""
FORMATS = ("auto", "course", "csv", "phyphox", "sensorlogger", "rosbag", "mat")
"""``--format`` values."""
_TEXT_SUFFIXES = (".csv", ".tsv", ".csv.gz", ".tsv.gz", ".txt.gz")


@dataclass(frozen=True)
class LogOptions:
    """How to read a log (the command line's ``--format --columns --axes --units
    --sensitivity --angle-unit --map --poses``). Every field may be left at its default: the
    reader then recognizes the format and columns from the content, or refuses with a message
    that names the option to give.

    Attributes
    ----------
    fmt : "auto" | "course" | "csv" | "phyphox" | "sensorlogger" | "rosbag" | "mat".
    columns : role → column name, roles ``t``, ``x``, ``y``, ``z``, ``theta``, ``label``,
        ``gyro`` (``--columns t=time,x=ax,y=ay``); ``topic`` for a bag.
    axes : the log's axis (``x``, ``y`` or ``z``, each with an optional leading ``-``) that
        becomes the tilt plane's x and y (``--axes x,y``; ``--axes -y,z``).
    units : acceleration unit: None (recognized from the header, else refused), ``m/s2``,
        ``g``, ``mg`` or ``counts`` (needs ``sensitivity``).
    sensitivity : counts per g, for raw counts.
    angle_unit : None (the data-based degrees check decides, :mod:`calib.files.angles`), ``rad``
        or ``deg``.
    mapping : ``.mat`` variable mapping, course name → file name (``--map tita=angle``).
    poses : angle of each held pose in the order they occur, in ``angle_unit`` (rad if
        None), or None: poses found in the log stay with unknown θ.
    label_angles : label value → angle (``angle_unit``), for a label column.
    g : m/s², converts ``g``/``mg``/``counts``; None: :data:`calib.conventions.G`.
    gyro_unit : ``rad/s`` or ``deg/s`` of the gyro columns; None: stated by the header or
        the format.
    time_unit : ``s``, ``ms``, ``us`` or ``ns`` of a CSV's time column; None: stated by the
        header, else s (:mod:`calib.logs.csvlog`).
    allow_gaps, allow_saturation : accept (and record) gaps in time / saturated stretches.
    window, min_hold : pose detector's window and minimum hold, s (samples without times);
        None: :mod:`calib.logs.poses` defaults.
    detect : look for held poses when θ is unknown (False for a vehicle run).
    rate : Hz, for a log without a time column: its samples are taken as evenly spaced at this
        rate from t = 0 (``import --rate``); refused for a log that has times.
    theta_source : where θ comes from when the poses' angles are given: ``poses`` (the held
        samples only, each at its pose's angle) or ``gyro`` (every sample, θ(t) integrated
        from the gyro about the tilt axis and anchored to the poses' angles:
        :func:`calib.logs.gyro_angle.theta_from_gyro`).
    """

    fmt: str = "auto"
    columns: dict[str, str] = field(default_factory=dict)
    axes: tuple[str, str] = ("x", "y")
    units: str | None = None
    sensitivity: float | None = None
    angle_unit: str | None = None
    mapping: dict[str, str] = field(default_factory=dict)
    poses: tuple[float, ...] | None = None
    label_angles: dict[str, float] | None = None
    g: float | None = None
    gyro_unit: str | None = None
    time_unit: str | None = None
    allow_gaps: bool = False
    allow_saturation: bool = False
    window: float | None = None
    min_hold: float | None = None
    detect: bool = True
    theta_source: str = "poses"
    rate: float | None = None


@dataclass(frozen=True)
class ImuLog:
    """Readings of one log, in the tilt plane.

    Attributes
    ----------
    acc : (N, 2) float, m/s² — ``[A_mx, A_my]`` (course signs after ``--axes``).
    t : (N,) float, s, strictly increasing, or None.
    theta : (N,) float, rad, table angle per sample, or None when unknown.
    pose : (N,) int, held-pose label per sample (0, 1, …; -1 while moving), or None when no
        poses were given or detected.
    gyro : (N,) float, rad/s, rate about the tilt axis, or None.
    acc_normal : (N,) float, m/s², the log's third acceleration axis — the one not in
        ``--axes``, signed as the tilt axis ``n = â × b̂`` so that (x, y, normal) is
        right-handed (``--axes x,y`` keeps ``+z``; ``--axes -y,z`` keeps ``-x``) — or None when
        the log has only the two axes (course files). The 3-axis multi-position calibration
        (:func:`calib.calibration.multiposition.fit_multiposition3d`) uses it; the provenance's
        ``normal_axis`` names the column.
    acc_s : (N, 3) float, m/s², the log's own x, y, z accelerometer axes in the sensor frame
        (as the log labels them: not signed or reordered by ``--axes``), or None when the log
        has fewer than three. The six-face test and the noise of every axis read these.
    gyro_s : (N, 3) float, rad/s, the log's own x, y, z gyro axes (sensor frame), or None when
        the log has no three gyro axes of stated unit.
    source : str — the file name, for messages.
    provenance : dict — source name and sha256, format, mapping, units, segments (JSON-able).
    """

    acc: np.ndarray
    t: np.ndarray | None = None
    theta: np.ndarray | None = None
    pose: np.ndarray | None = None
    gyro: np.ndarray | None = None
    acc_normal: np.ndarray | None = None
    acc_s: np.ndarray | None = None
    gyro_s: np.ndarray | None = None
    source: str = "<memory>"
    provenance: dict[str, Any] = field(default_factory=dict)
    course: Any = field(default=None, repr=False, compare=False)
    """The :class:`calib.files.course.Ensayo` / :class:`calib.files.course.Acel` when the log was a
    course file read by the course reader: :meth:`to_ensayo` / :meth:`to_acel` return it
    unchanged."""

    def __post_init__(self) -> None:
        for name, dtype in (("acc", float), ("t", float), ("theta", float), ("pose", int),
                            ("gyro", float), ("acc_normal", float), ("acc_s", float),
                            ("gyro_s", float)):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, readonly(getattr(self, name), dtype))

    @property
    def n(self) -> int:
        return int(self.acc.shape[0])

    def __repr__(self) -> str:
        """One short line: what the log holds (the arrays themselves are not printed)."""
        axes = ",".join(self.provenance.get("axes") or ("x", "y"))
        span = ("no t" if self.t is None or self.t.size == 0
                else f"t {self.t[0]:g}–{self.t[-1]:g} s")
        count = 0 if self.pose is None else len(set(self.pose[self.pose >= 0]))
        poses = "no poses" if self.pose is None else f"{count} pose{'' if count == 1 else 's'}"
        gyro = ("x, y, z" if self.gyro_s is not None
                else "tilt axis" if self.gyro is not None else "none")
        return (f"ImuLog({self.source!r}: {self.n} samples, axes {axes}"
                f"{' + normal' if self.acc_normal is not None else ''}"
                f"{' (3-axis accel)' if self.acc_s is not None else ''}, {span}, θ "
                f"{'unknown' if self.theta is None else 'known'}, {poses}, gyro {gyro})")

    def _course_as(self, kind: type, needed: str, why: str) -> Any:
        """The course file object this log was read as, when it is a ``kind`` (returned
        unchanged); else None, after refusing (DataError naming the source, ``why``) a log
        without the field ``needed``."""
        if isinstance(self.course, kind):
            return self.course
        if getattr(self, needed) is None:
            raise DataError(f"{self.source}: {why}")
        return None

    def to_ensayo(self):
        """The course :class:`calib.files.course.Ensayo` (θ known); DataError when θ is unknown."""
        from calib.files.course import Ensayo, validate_ensayo

        course = self._course_as(Ensayo, "theta", "the table angle is unknown; give the poses' "
                                 "angles (--poses …) or a θ column (--columns theta=…)")
        if course is not None:
            return course
        return validate_ensayo(self.theta, self.acc, self.t, self.source)

    def to_acel(self):
        """The course :class:`calib.files.course.Acel` (a vehicle run: uniform ``t`` needed)."""
        from calib.files.course import Acel, uniformly_sampled

        course = self._course_as(Acel, "t", "no sample times; a vehicle run needs them "
                                 "(--columns t=…)")
        if course is not None:
            return course
        if not uniformly_sampled(self.t):
            raise DataError(f"{self.source}: 't' is not uniformly sampled; a vehicle run is "
                            "integrated on a uniform grid: import it with tiltbench import "
                            "(resamples, recorded in provenance.json)")
        return Acel(t=self.t, aerr=self.acc, source=self.source, gyro=self.gyro)


def file_sha256(path: str | os.PathLike) -> str:
    """sha256 of a file's bytes (hex), for provenance records; of a ROS 2 bag directory, of
    its files' names and bytes in sorted order."""
    h = hashlib.sha256()
    path = Path(path)
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    for p in files:
        if path.is_dir():
            h.update(str(p.relative_to(path)).encode() + b"\0")
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


def _is_mat(path: Path) -> bool:
    return path.suffix.lower() == ".mat" or file_head(path, 6) == b"MATLAB"


def _mat_names(path: Path) -> list[str]:
    import scipy.io

    try:
        return [name for name, _, _ in scipy.io.whosmat(str(path))]
    except Exception:  # a damaged file: the course reader names the problem
        return []


def detect_format(path: Path, options: LogOptions) -> str:
    """The reader for ``path``: ``options.fmt`` unless ``auto``; else ``course`` (a .mat
    with the course names and no ``--map``), ``mat``, ``rosbag``, ``csv`` (a ``.csv``/``.tsv``
    name, gzipped or not, or a text file that reads as a table with a header), or ``unknown``.
    """
    from calib.logs.csvlog import looks_like_table
    from calib.logs.rosbag import is_bag
    from calib.logs.ziplog import is_zip

    if options.fmt in ("auto", "phyphox") and is_zip(path):  # phyphox's "CSV (zip)" export
        return "zip"
    if options.fmt in ("phyphox", "sensorlogger"):
        return "csv"
    if options.fmt != "auto":
        return options.fmt
    if not path.exists():
        return "unknown"
    if is_bag(path):
        return "rosbag"
    if path.is_dir():
        return "unknown"
    if _is_mat(path):
        return "mat" if options.mapping else "course"
    name = path.name.lower()
    if name.endswith(_TEXT_SUFFIXES) or looks_like_table(path):
        return "csv"
    return "unknown"


def read_log(path: str | os.PathLike, options: LogOptions | None = None,
             expect: str | None = None,
             progress: Callable[[int, int], None] | None = None) -> ImuLog:
    """Read a measured log into an :class:`ImuLog` (module docstring).

    Parameters
    ----------
    path : the log (a file, or a ROS 2 bag directory).
    options : how to read it; None: everything recognized from the content.
    expect : ``"ensayo"`` or ``"acel"`` when the caller reads a course input: a course
        ``.mat`` file — and any file not recognized as a log — then goes through
        :func:`calib.files.course.read_ensayo` / :func:`calib.files.course.read_acel` unchanged
        (same checks, same messages as before logs were read).
    progress : ``progress(done, total)``, bytes of a CSV/TSV log read so far (compressed,
        for gzip), called after each block the reader parses (:mod:`calib.logs.csvlog`);
        other formats do not call it.

    Raises
    ------
    DataError : a format not recognized, a missing column, units neither stated nor
        recognized, a log that does not read 1 g at rest (:mod:`calib.logs.physics`),
        non-monotone time, NaN/Inf; the message names the file, the line or
        column and what to do.
    """
    from calib.files.course import read_acel, read_ensayo

    options = options or LogOptions()
    path = Path(path)
    fmt = detect_format(path, options)
    if fmt == "unknown" and path.suffix.lower() in _BAG_SUFFIXES and path.is_file():
        raise DataError(f"{path}: not a readable ROS bag (a ROS 1 bag starts with '#ROSBAG "
                        "V2.0'; a ROS 2 bag is a folder with metadata.yaml): empty, cut short "
                        "at its start or not a bag; give --format if it is another format")
    if expect is not None and fmt in ("course", "unknown"):
        names = _mat_names(path) if fmt == "course" else []
        if not (expect == "ensayo" and "pose" in names and "tita" not in names):
            prov = {"source": {"name": path.name}, "format": "course"}
            return _course_log(path, expect, names, prov, read_ensayo, read_acel)
    if expect == "acel":  # a vehicle run: poses and their angles do not apply
        options = replace(options, poses=None, label_angles=None, detect=False)
    if not path.exists():
        raise DataError(f"{path}: file not found")
    if fmt == "unknown":
        raise DataError(f"{path}: not a log format read here (CSV/TSV with a header, phyphox "
                        "or Sensor Logger export, ROS bag, .mat); give --format")
    if fmt == "course":
        return _read_course(path, options, read_ensayo, read_acel)
    raw = _read_raw(path, fmt, options, progress)
    log = assemble(raw, options, path)
    # a vehicle run's in-plane readings are its motion, not gravity at rest: it is checked
    # only when it has the axis normal to its plane, where a planar vehicle feels g
    if expect != "acel" or log.acc_normal is not None:
        check_one_g(log.acc, log.acc_normal, log.pose, G if options.g is None else options.g,
                    str(path), tilt_plane=expect == "ensayo" or log.theta is not None,
                    units=(log.provenance.get("units") or {}).get("acc"),
                    sensitivity=options.sensitivity)
    return log


def _course_pose(path: Path, n: int) -> np.ndarray:
    """The ``pose`` labels (N×1 integers, -1 while moving) that ``tiltbench import`` writes
    beside ``tita``/``datos``; DataError naming the file when they do not fit."""
    import scipy.io

    pose = np.asarray(scipy.io.loadmat(path, variable_names=["pose"])["pose"], dtype=float)
    pose = pose.reshape(-1)
    if pose.size != n or not np.all(np.isfinite(pose)) or np.any(pose != np.round(pose)):
        raise DataError(f"{path}: 'pose' must hold one integer label per sample ({n}), "
                        f"got {pose.size} values; remove it or re-run `tiltbench import`")
    return pose.astype(int)


def _read_course(path: Path, options: LogOptions, read_ensayo, read_acel) -> ImuLog:
    """A course ``.mat``: ensayo (tita, datos), acel (t, Aerr) or the θ-unknown ensayo of
    ``tiltbench import`` (datos, t, pose)."""
    names = _mat_names(path)
    if "pose" in names or ("tita" not in names and "Aerr" not in names
                           and "datos" in names):
        return assemble(_read_raw(path, "mat", options), options, path)
    prov = {"source": {"name": path.name, "sha256": file_sha256(path)}, "format": "course"}
    kind = "acel" if "Aerr" in names and "tita" not in names else "ensayo"
    return _course_log(path, kind, names, prov, read_ensayo, read_acel)


def _course_log(path: Path, kind: str, names: list[str], prov: dict, read_ensayo,
                read_acel) -> ImuLog:
    """A course file read by its course reader (``kind`` "ensayo" or "acel"); an imported
    ensayo keeps its ``pose`` labels (lack of fit, pure-error σ²)."""
    if kind == "acel":
        a = read_acel(path)
        return ImuLog(acc=a.aerr, t=a.t, gyro=a.gyro, source=str(path), provenance=prov,
                      course=a)
    e = read_ensayo(path)
    pose = _course_pose(path, e.n) if "pose" in names else None
    return ImuLog(acc=e.datos, t=e.t, theta=e.tita, pose=pose, source=str(path),
                  provenance=prov, course=e)


def _read_raw(path: Path, fmt: str, options: LogOptions,
              progress: Callable[[int, int], None] | None = None) -> RawLog:
    if fmt == "zip":
        from calib.logs.ziplog import choose_member, extracted

        member = choose_member(path)
        with extracted(path, member) as inner:
            raw = _read_raw(inner, "csv", options, progress)
        # the member's hash is not the file's: the provenance hashes the zip itself
        return replace(raw, notes=dict(raw.notes, zip_member=member), sha256=None)
    if fmt == "csv":
        from calib.logs.csvlog import read_csv

        if path.is_dir():
            raise DataError(f"{path}: is a directory; expected a CSV/TSV file")
        return read_csv(path, options.columns, options.fmt, units=options.units,
                        gyro_unit=options.gyro_unit, time_unit=options.time_unit,
                        progress=progress)
    if options.time_unit is not None:
        raise DataError(f"{path}: --time-unit applies to CSV/TSV logs only; drop it (the "
                        "time of a ROS bag or a .mat is in seconds)")
    if fmt == "rosbag":
        from calib.logs.rosbag import read_bag

        return read_bag(path, options.columns.get("topic"))
    if fmt in ("mat", "course"):
        from calib.logs.matlog import read_mat

        return read_mat(path, options.mapping)
    raise DataError(f"{path}: --format {fmt}: not a format read here ({', '.join(FORMATS)})")


# --- assembling an ImuLog from a RawLog -----------------------------------------------------

def _axis_vector(spec: str) -> np.ndarray:
    sign = -1.0 if spec.startswith("-") else 1.0
    v = np.zeros(3)
    v["xyz".index(spec.lstrip("+-"))] = sign
    return v


def tilt_axis(axes: tuple[str, str]) -> str:
    """The signed log axis about which the tilt turns: ``â × b̂`` (``x,y`` → ``z``;
    ``-y,z`` → ``-x``)."""
    n = np.cross(_axis_vector(axes[0]), _axis_vector(axes[1]))
    k = int(np.argmax(np.abs(n)))
    return ("-" if n[k] < 0 else "") + "xyz"[k]


def accel_factor(unit: str, g: float, sensitivity: float | None, where: str) -> float:
    """m/s² per unit of the log: 1, g, g/1000 or g/sensitivity, where the unit g is
    ``g`` = :data:`calib.conventions.STANDARD_GRAVITY` (9.80665 m/s²) as the callers pass it —
    never the local gravity (``--g``, ``--latitude``), which is what the sensor feels."""
    if unit == "m/s2":
        return 1.0
    if unit == "g":
        return float(g)
    if unit == "mg":
        return float(g) / 1000.0
    if unit == "counts":
        if sensitivity is None:
            raise DataError(f"{where}: raw counts need --sensitivity (counts per g)")
        return float(g) / float(sensitivity)
    raise DataError(f"{where}: unit {unit!r} not read here ({', '.join(ACCEL_UNITS)})")


def _check_finite(raw: RawLog, arr: np.ndarray, what: str, path: Path) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"{path}: {what}: {int(bad.sum())} NaN/Inf value(s), first at "
                        f"{raw.where(i)}; remove or repair those samples")


def _check_time(raw: RawLog, t: np.ndarray, path: Path, allow_gaps: bool) -> list[dict]:
    """Strictly increasing, no gaps (unless allowed: then they are returned)."""
    col = raw.mapping.get("t", "t")
    big = float(np.max(np.abs(t))) if t.size else 0.0
    if big > MAX_ABS_TIME:
        raise DataError(f"{path}: time column '{col}' reaches {big:.3g} s; state its unit in "
                        "the header (e.g. 'time (ns)' or time_ns) or with --time-unit")
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0)) + 1
        raise DataError(f"{path}: time column '{col}' does not increase at {raw.where(i)} "
                        f"(t = {t[i]:.9g} s after {t[i - 1]:.9g} s); samples must be in "
                        "time order, without repeats")
    gaps = []
    if d.size:
        step = float(np.median(d))
        for i in np.flatnonzero(d > GAP_FACTOR * step):
            gaps.append({"after": raw.where(int(i)), "t": float(t[i]),
                         "length_s": float(d[i]), "median_step_s": step})
        if gaps and not allow_gaps:
            g0 = gaps[0]
            raise DataError(f"{path}: {len(gaps)} gap(s) in time, the first {g0['length_s']:.4g}"
                            f" s long (median step {step:.4g} s) after {g0['after']} (t = "
                            f"{g0['t']:.6g} s); pass --allow-gaps to read it anyway (a gap "
                            "is never filled: held poses and `noise` use the stretches between "
                            "gaps; integration and an acel.mat import refuse a gapped log)")
    return gaps


def _check_saturation(raw: RawLog, arr: np.ndarray, what: str, path: Path, factor: float,
                      g: float) -> None:
    """Refuse runs of ≥ :data:`SATURATION_RUN` equal samples at the column's extreme when
    that extreme is at least g/2 in size (a reading near zero that does not move is an axis
    across the tilt plane, not a clipped one)."""
    for extreme in (float(np.max(arr)), float(np.min(arr))):
        if abs(extreme * factor) < 0.5 * g:
            continue
        at = arr == extreme
        m = np.concatenate(([False], at, [False]))
        edges = np.flatnonzero(m[1:] != m[:-1])
        for a, b in zip(edges[0::2], edges[1::2], strict=True):
            if b - a >= SATURATION_RUN:
                raise DataError(f"{path}: {what} sits at its extreme value {extreme:g} for "
                                f"{b - a} samples ({raw.where(int(a))} to "
                                f"{raw.where(int(b) - 1)}): saturated? Record with a range "
                                "beyond ±1 g, drop those samples, or pass --allow-saturation "
                                "if the sensor is so coarse that a held pose reads one value")


def _scaled_columns(columns: list[np.ndarray], factors: list[float]) -> np.ndarray:
    """(N, k) float array of ``columns[j] · factors[j]``, written in place: no temporary
    copy of a long log per column."""
    out = np.empty((columns[0].shape[0], len(columns)))
    for j, (col, f) in enumerate(zip(columns, factors, strict=True)):
        np.multiply(col, f, out=out[:, j])
    return out


def provenance_units(prov: dict[str, Any], prefix: str = "provenance") -> dict[str, str]:
    """The units of the numbers of the provenance record ``prov`` embedded in a JSON output
    under ``prefix``: :data:`PROVENANCE_UNITS` plus the detected poses' and the gyro angle's
    own maps."""
    from calib.units import nest

    units = dict(PROVENANCE_UNITS)
    detection = (prov.get("poses") or {}).get("detection") or {}
    if isinstance(detection.get("units"), dict):
        units.update(nest("poses.detection", detection["units"]))
    gyro = prov.get("theta_from_gyro") or {}
    if isinstance(gyro.get("units"), dict):
        units.update(nest("theta_from_gyro", gyro["units"]))
    return nest(prefix, units)


def provenance_line(prov: dict[str, Any]) -> str | None:
    """One line saying how a log was read — format, which column became what, the units and
    their factor to SI — from its provenance record; None for a course file (read as the
    course defines it)."""
    if not prov or prov.get("format") == "course":
        return None
    mapping = prov.get("mapping") or {}
    units = prov.get("units") or {}
    axes = prov.get("axes") or ["x", "y"]
    member = (prov.get("reader") or {}).get("zip_member")
    cols = [f"{role} ← {mapping[role]!r}" for role in ("t", "theta", "label") if role in mapping]
    acc = ", ".join(f"{a} ← {mapping.get(a.lstrip('-'), a)!r}" for a in axes)
    if prov.get("normal_axis"):
        acc += f", n ← {prov['normal_axis']!r}"
    factor = units.get("acc_to_m_s2")
    conv = "" if factor in (None, 1.0) else f" × {factor:.9g} → m/s²"
    gyro = units.get("gyro_from") or "none"
    three = [mapping[k] for k in ("gyro_x", "gyro_y", "gyro_z") if k in mapping]
    if len(three) > 1 and units.get("gyro_from"):  # every gyro axis read; one is the tilt's
        gyro = ", ".join(three) + f" (about the tilt axis: {units['gyro_from']})"
    if units.get("gyro"):
        gyro += f" in {units['gyro']}"
    elif units.get("gyro_note"):
        gyro += f" ({units['gyro_note']})"
    name = (prov.get("source") or {}).get("name")
    return (f"read {name} as {prov.get('format')}{f' (member {member})' if member else ''}: "
            f"{', '.join(cols + [acc])} in {units.get('acc')}{conv}; gyro {gyro}")


def _angles(values, unit: str | None) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    return np.deg2rad(arr) if unit == "deg" else arr


def assemble(raw: RawLog, options: LogOptions, path: Path) -> ImuLog:
    """Axes, units, checks, θ and poses: a :class:`RawLog` as an :class:`ImuLog` (module
    docstring)."""
    g = G if options.g is None else float(options.g)
    where = str(path)
    # the two tilt-plane axes, signed
    acc_cols = []
    for spec in options.axes:
        axis = spec.lstrip("+-")
        if axis not in raw.acc:
            have = ", ".join(sorted(raw.acc)) or "none"
            raise DataError(f"{path}: --axes {','.join(options.axes)}: the log has no {axis} "
                            f"acceleration (axes read: {have}); choose two of them")
        acc_cols.append((spec, axis))
    stated = raw.acc_unit
    if options.units is not None and stated is not None and options.units != stated:
        raise DataError(f"{path}: the header states the acceleration in {stated} but --units "
                        f"{options.units}; drop --units or fix the header")
    unit = options.units or stated or raw.notes.get("default_unit")
    if unit is None:
        cols = ", ".join(repr(raw.mapping.get(a, a)) for _, a in acc_cols)
        raise DataError(f"{path}: the unit of column(s) {cols} is neither stated in the header "
                        "nor known for this format; give --units m/s2|g|mg|counts")
    # the unit g is standard gravity whatever --g says (that is the local gravity felt)
    factor = accel_factor(unit, STANDARD_GRAVITY, options.sensitivity, where)
    for _, axis in acc_cols:
        what = f"column '{raw.mapping.get(axis, axis)}'"
        _check_finite(raw, raw.acc[axis], what, path)
        if not options.allow_saturation:
            _check_saturation(raw, raw.acc[axis], what, path, factor, g)
    # the sensor frame first: for the default axes the tilt-plane view and the normal axis
    # are views of it (no second copy of a long log, not even a temporary one)
    acc_s = None
    if all(k in raw.acc for k in "xyz"):
        for k in "xyz":
            _check_finite(raw, raw.acc[k], f"column '{raw.mapping.get(k, k)}'", path)
        acc_s = _scaled_columns([raw.acc[k] for k in "xyz"], [factor] * 3)
    shared = acc_s is not None and tuple(options.axes) == ("x", "y")
    if shared:
        acc = acc_s[:, :2]
    else:
        acc = _scaled_columns([raw.acc[a] for _, a in acc_cols],
                              [(-1.0 if spec.startswith("-") else 1.0) * factor
                               for spec, _ in acc_cols])
    # the third axis, signed as the tilt axis â × b̂: (x, y, normal) right-handed
    normal_spec = tilt_axis(tuple(options.axes))
    normal_axis = normal_spec.lstrip("-")
    acc_normal, normal_from = None, None
    if normal_axis in raw.acc:
        what = f"column '{raw.mapping.get(normal_axis, normal_axis)}'"
        # finite values only; not the saturation check: the commands that read the tilt
        # plane alone must not start refusing a log for an axis they ignore (a flat board's
        # z sits still at +g); the 3-axis fit's lack-of-fit test shows a clipped pose
        _check_finite(raw, raw.acc[normal_axis], what, path)
        sign = -1.0 if normal_spec.startswith("-") else 1.0
        acc_normal = (acc_s[:, 2] if shared else
                      np.multiply(raw.acc[normal_axis], sign * factor, dtype=float))
        normal_from = f"{'-' if sign < 0 else ''}{raw.mapping.get(normal_axis, normal_axis)}"
    # the acceleration columns are in acc / acc_s / acc_normal now (scaled): a long log's
    # originals go before the gyro's arrays are built
    raw.acc.clear()
    n = acc.shape[0]
    if n < 3:
        raise DataError(f"{path}: only {n} samples; at least 3 are needed")
    # time
    t, gaps = raw.t, []
    if t is not None and options.rate is not None:
        raise DataError(f"{path}: the log has sample times (column "
                        f"'{raw.mapping.get('t', 't')}'); drop --rate")
    if t is None and options.rate is not None:  # evenly sampled at the stated rate, from 0
        t = np.arange(acc.shape[0]) / float(options.rate)
    elif t is not None:
        _check_finite(raw, t, f"time column '{raw.mapping.get('t', 't')}'", path)
        gaps = _check_time(raw, t, path, options.allow_gaps)
    # gyro about the tilt axis
    gyro, gyro_from, gyro_s = None, None, None
    g_unit = options.gyro_unit or raw.gyro_unit
    gyro_note = None
    if raw.gyro and g_unit not in GYRO_UNITS:
        if "tilt" in raw.gyro:  # named on purpose with --columns gyro=…: say what is missing
            raise DataError(f"{path}: the unit of gyro column '{raw.mapping.get('gyro')}' is "
                            "not stated; give --gyro-unit rad/s|deg/s")
        gyro_note = "gyro columns ignored: their unit is not stated (give --gyro-unit)"
    elif raw.gyro:
        gfac = np.pi / 180.0 if g_unit == "deg/s" else 1.0
        if all(k in raw.gyro for k in "xyz"):
            for k in "xyz":
                _check_finite(raw, raw.gyro[k], f"gyro '{raw.mapping.get('gyro_' + k, k)}'",
                              path)
            gyro_s = _scaled_columns([raw.gyro[k] for k in "xyz"], [gfac] * 3)
        if "tilt" in raw.gyro:
            gyro, gyro_from = raw.gyro["tilt"] * gfac, raw.mapping.get("gyro", "gyro")
        else:
            n_axis = tilt_axis(tuple(options.axes))
            k = n_axis.lstrip("-")
            if k in raw.gyro:
                sign = -1.0 if n_axis.startswith("-") else 1.0
                if gyro_s is not None and sign > 0:  # a view: no copy of a long log
                    gyro = gyro_s[:, "xyz".index(k)]
                else:
                    gyro = np.multiply(raw.gyro[k], sign * gfac, dtype=float)
                gyro_from = f"{'-' if sign < 0 else ''}{raw.mapping.get('gyro_' + k, k)}"
        if gyro is not None:
            _check_finite(raw, gyro, f"gyro '{gyro_from}'", path)
    # the gyro columns are in gyro / gyro_s now (or ignored): the originals go too, before
    # the pose detector needs its own working memory (only labels and names are read later)
    raw.gyro.clear()
    # θ
    theta = None
    theta_unit = None
    if raw.theta is not None:
        if options.angle_unit and raw.theta_unit and options.angle_unit != raw.theta_unit:
            raise DataError(f"{path}: the header states θ in {raw.theta_unit} but --angle-unit "
                            f"{options.angle_unit}; drop one")
        theta_unit = options.angle_unit or raw.theta_unit
        _check_finite(raw, raw.theta, f"θ column '{raw.mapping.get('theta', 'theta')}'", path)
        theta = _angles(raw.theta, theta_unit)
    prov: dict[str, Any] = {
        "format_version": LOG_FORMAT_VERSION,
        "source": {"name": path.name, "sha256": raw.sha256 or file_sha256(path)},
        "format": raw.fmt,
        "mapping": dict(raw.mapping),
        "axes": list(options.axes),
        "tilt_axis": tilt_axis(tuple(options.axes)),
        "normal_axis": normal_from,
        "units": {"acc": unit, "acc_to_m_s2": factor, "g": g,
                  "sensitivity_counts_per_g": options.sensitivity,
                  "gyro": g_unit if gyro is not None or gyro_s is not None else None,
                  "gyro_from": gyro_from,
                  "gyro_note": gyro_note,
                  "theta": None if theta is None else (theta_unit or "rad (degrees check)"),
                  "t": "s" if options.rate is None else f"s, from --rate {options.rate:g} Hz"},
        "reader": dict(raw.notes),
        "samples": {"read": n},
        "gaps": gaps,
    }
    if raw.fmt == "mat" and options.units is None:
        prov["units"]["acc_note"] = "the course variable's unit (m/s²)"
    # the arrays are this function's own (built above, or the raw log's, dropped on return):
    # frozen in place, the record shares them instead of copying a long log once more
    for arr in (acc, t, theta, gyro, acc_normal, acc_s, gyro_s):
        if isinstance(arr, np.ndarray) and arr.dtype == float:
            arr.setflags(write=False)
    log = ImuLog(acc=acc, t=t, theta=theta, gyro=gyro, acc_normal=acc_normal, acc_s=acc_s,
                 gyro_s=gyro_s, source=where, provenance=prov)
    return _poses(log, raw, options, path)


def _sub(log: ImuLog, keep: np.ndarray, theta: np.ndarray, pose: np.ndarray,
         prov: dict) -> ImuLog:
    def cut(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else a[keep]

    return replace(log, acc=log.acc[keep], t=cut(log.t), theta=theta, pose=pose,
                   gyro=cut(log.gyro), acc_normal=cut(log.acc_normal), acc_s=cut(log.acc_s),
                   gyro_s=cut(log.gyro_s), provenance=prov)


def _poses(log: ImuLog, raw: RawLog, options: LogOptions, path: Path) -> ImuLog:
    """Pose labels (label column or detector) and θ from ``--poses`` / label angles."""
    from calib.logs.poses import detect_poses

    prov = dict(log.provenance)
    if log.theta is not None:
        if options.poses is not None or options.label_angles:
            raise DataError(f"{path}: the log has a θ column; --poses / label angles would "
                            "give θ twice: drop one")
        if options.angle_unit is None and raw.theta_unit is None:
            _degrees_check(log.theta, log.acc, path,
                           f"θ column '{raw.mapping.get('theta', 'theta')}'")
        pose = None
        if raw.label is not None:
            pose, _ = _labels(raw.label)
        return replace(log, pose=pose, provenance=prov)
    if raw.label is not None:
        pose, values = _labels(raw.label)
        _check_labels_still(log, pose, values, path, raw.mapping.get("label", "label"))
        prov["poses"] = {"source": f"label column '{raw.mapping.get('label', 'label')}'",
                         "labels": values}
    elif not options.detect:
        pose, values = None, None
    else:
        det = detect_poses(log.acc, log.t, log.gyro, more_acc=log.acc_normal,
                           window=options.window,
                           min_hold=options.min_hold)
        pose, values = det.labels, None
        prov["poses"] = {"source": "detected", "detection": det.to_dict(),
                         "thresholds": det.thresholds_line()}
        if det.count == 0:
            pose = None
    angles = None
    count = 0 if pose is None else int(pose.max()) + 1
    if options.label_angles:
        if raw.label is None:
            raise DataError(f"{path}: label angles given but the log has no label column "
                            "(--columns label=…)")
        missing = [v for v in values if v not in options.label_angles]
        if missing:
            raise DataError(f"{path}: label(s) {', '.join(missing)} have no angle; give one "
                            "for each label")
        angles = [options.label_angles[v] for v in values]
    elif options.poses is not None:
        if len(options.poses) != count:
            found = ("detected" if raw.label is None else "labelled")
            raise DataError(f"{path}: --poses gives {len(options.poses)} angle(s) but "
                            f"{count} held pose(s) were {found}; give one angle per pose "
                            "in order (the poses found are in the provenance / tiltbench "
                            "import output)")
        angles = list(options.poses)
    if angles is None:
        if options.theta_source == "gyro":
            raise DataError(f"{path}: --theta-source gyro anchors the integrated gyro to the "
                            "held poses' angles: give them (--poses … or --label-angles …)")
        return replace(log, pose=pose, provenance=prov)
    rad = _angles(angles, options.angle_unit)
    out_of_plane = np.flatnonzero(np.isnan(rad))  # --poses '-': a pose outside the tilt plane
    if options.theta_source == "gyro":
        if out_of_plane.size:
            raise DataError(f"{path}: --theta-source gyro anchors θ(t) to every held pose: "
                            "give each an angle (no '-' in --poses)")
        return _theta_from_gyro(log, pose, rad, prov, options, path)
    if np.sum(np.isfinite(rad)) < 2:
        raise DataError(f"{path}: --poses gives fewer than two poses in the tilt plane; give "
                        "the angles of at least two")
    keep = (pose >= 0) & np.isin(pose, np.flatnonzero(np.isfinite(rad)))
    # the poses in the plane keep their order, numbered 0, 1, … without the gaps
    new_label = np.cumsum(np.isfinite(rad)) - 1
    theta = rad[pose[keep]]
    prov["samples"] = dict(prov["samples"], kept=int(keep.sum()))
    aside = "" if not out_of_plane.size else (
        f"; {out_of_plane.size} pose(s) marked '-' (outside the tilt plane: "
        f"{', '.join(str(int(k)) for k in out_of_plane)}) set aside")
    prov["held_samples_only"] = ("θ comes from the poses' angles: only the held samples "
                                 f"({int(keep.sum())} of {log.n}) are kept{aside}")
    prov["units"]["theta"] = options.angle_unit or "rad"
    prov["pose_angles_rad"] = [None if np.isnan(r) else float(r) for r in rad]
    if out_of_plane.size:
        prov["poses_out_of_plane"] = [int(k) for k in out_of_plane]
    out = _sub(log, keep, theta, new_label[pose[keep]], prov)
    if options.angle_unit is None:
        _degrees_check(out.theta, out.acc, path, "the pose angles")
    return out


def _theta_from_gyro(log: ImuLog, pose: np.ndarray | None, rad: np.ndarray, prov: dict,
                     options: LogOptions, path: Path) -> ImuLog:
    """Every sample kept, θ(t) integrated from the gyro and anchored to the poses' angles
    (:mod:`calib.logs.gyro_angle`); the provenance says how, with the closure errors."""
    from calib.logs.gyro_angle import theta_from_gyro

    if log.gyro is None:
        note = prov["units"].get("gyro_note")
        raise DataError(f"{path}: --theta-source gyro needs a gyro about the tilt axis "
                        f"{prov['tilt_axis']} (from --axes); "
                        + (note if note else "the log has none (--columns gyro=…)"))
    g = prov["units"]["g"]
    res = theta_from_gyro(log.t, log.gyro, pose, rad, acc=log.acc, g=g, where=str(path),
                          gyro_from=prov["units"].get("gyro_from") or "gyro")
    prov["theta"] = res.summary()
    prov["theta_from_gyro"] = res.to_dict(with_theta=False)
    prov["units"]["theta"] = "rad (integrated gyro)"
    prov["pose_angles_rad"] = rad.tolist()
    prov["samples"] = dict(prov["samples"], kept=log.n)
    return replace(log, theta=res.theta, pose=pose, provenance=prov)


def _degrees_check(theta: np.ndarray, acc: np.ndarray, path: Path, what: str) -> None:
    """θ of unstated unit: refuse when the readings say degrees (:mod:`calib.files.angles`)."""
    from calib.files.angles import compare_angle_units

    units = compare_angle_units(theta, acc)
    if units.looks_like_degrees:
        raise DataError(f"{path}: {what} look like degrees, not radians: the nominal model "
                        f"fits θ·π/180 far better than θ ({units.summary()}); give "
                        "--angle-unit deg")


LABEL_STILL_RATIO = LOOSE * MARGIN
"""(20) A labelled hold whose scatter (variance summed over the axes) exceeds this many times the
quietest label's is not held still: the pose detector's own allowance for holds that differ
in noise (:data:`calib.logs.poses.LOOSE` × :data:`calib.logs.poses.MARGIN`: a hand-held pose
beside one on a table), while a turn spreads the readings over a good part of g."""


def _check_labels_still(log: ImuLog, pose: np.ndarray, values: list[str], path: Path,
                        column: str) -> None:
    """Refuse a label column whose labelled stretches are not all held still (a rotation
    labelled as a pose would enter every fit as a hold with a hundred times the scatter)."""
    acc = log.acc if log.acc_normal is None else np.column_stack([log.acc, log.acc_normal])
    var = np.array([acc[pose == k].var(axis=0).sum() if np.sum(pose == k) > 1 else 0.0
                    for k in range(len(values))])
    floor = float(np.min(var[var > 0])) if np.any(var > 0) else 0.0
    if floor <= 0:
        return
    loud = np.flatnonzero(var > LABEL_STILL_RATIO * floor)
    if loud.size:
        k = int(loud[np.argmax(var[loud])])
        raise DataError(
            f"{path}: label column '{column}': label {values[k]!r} is not held still (its "
            f"readings scatter {var[k] / floor:.3g}× the quietest label's variance, more than "
            f"{LABEL_STILL_RATIO:g}×; {loud.size} such label(s)); label only the held "
            "stretches (moving rows empty, -1 or 'moving'), or remove the label column and "
            "let the pose detector find the holds")


def _labels(label: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """Pose indices in order of first appearance; moving cells (:data:`MOVING_LABELS`) -1."""
    codes: dict[str, int] = {}
    out = np.empty(label.size, dtype=int)
    for i, v in enumerate(label.tolist()):
        key = str(v).strip()
        if key.lower() in MOVING_LABELS or key.startswith("-"):
            out[i] = -1
            continue
        try:  # "1" and "1.0" are one label
            f = float(key)
            key = str(int(f)) if f == int(f) else key
        except ValueError:
            pass
        out[i] = codes.setdefault(key, len(codes))
    return out, list(codes)


__all__ = ["FORMATS", "GAP_FACTOR", "LOG_FORMAT_VERSION", "SATURATION_RUN", "ImuLog",
           "LogOptions", "accel_factor", "assemble", "detect_format", "file_sha256",
           "provenance_line",
           "read_log", "tilt_axis"]
