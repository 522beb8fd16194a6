"""Measured-log files for the front-door cases: simulated IMU signals (numpy only, seeded)
written in every format ``docs/real-data.md`` says the readers take — CSV/TSV (gzipped or
not, any delimiter, decimal comma), phyphox's "CSV (zip)" export, a Sensor Logger export,
ROS 1 and ROS 2 bags of ``sensor_msgs/Imu`` (with ``rosbags``) and a ``.mat`` with its own
variable names — in any unit, stated or not.

Like the rest of the harness this imports neither ``bench`` nor ``calib``: the files are made
from the documented formats, and the true values stay with the harness (the truth checks).

Signals (course signs: ``a_x = -g sin θ``, ``a_y = -g cos θ``, the tilt axis z; g = 9.8
m/s², the commands' default local gravity, so that a gain ``k`` reads as ``scale = k − 1``):

- :func:`poses`: held poses at the given angles, turned between them (a calibration run);
- :func:`still`: one held pose (a static log for ``noise``);
- :func:`vehicle`: a moving log (no pose; not checked for 1 g).
"""

from __future__ import annotations

import gzip
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

G_LOCAL = 9.8
"""The local gravity the simulated sensor feels (the commands' default ``--g``)."""
G_UNIT = 9.80665
"""The unit g (standard gravity) that converts g and mg to m/s² (docs/real-data.md)."""
RATE = 100.0
"""Sample rate of every simulated log, Hz."""
T0_NS = 1_700_000_000_000_000_000
"""The first stamp of a nanosecond time column (ns since the epoch, as phones write it)."""


def ns_stamps(t: np.ndarray) -> np.ndarray:
    """Integer nanosecond stamps since the epoch of times ``t`` (s from 0), exact (int64)."""
    return T0_NS + np.round(np.asarray(t) * 1e9).astype(np.int64)


@dataclass
class Signal:
    """A simulated log: ``t`` (N,) s from 0, ``acc`` (N, 3) m/s², ``gyro`` (N, 3) rad/s,
    ``theta`` (N,) rad (NaN where not defined), ``holds`` the [start, stop) of each pose."""

    t: np.ndarray
    acc: np.ndarray
    gyro: np.ndarray
    theta: np.ndarray
    holds: list[tuple[int, int]]


def hold_and_turn(angles_rad, hold: int, turn: int) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """θ (rad) held ``hold`` samples at each angle and turned linearly to the next in ``turn``
    samples, and each hold's ``[start, stop)``."""
    theta: list[float] = []
    holds = []
    for k, a in enumerate(angles_rad):
        holds.append((len(theta), len(theta) + hold))
        theta += [a] * hold
        if k + 1 < len(angles_rad):
            theta += list(np.linspace(a, angles_rad[k + 1], turn + 2)[1:-1])
    return np.array(theta), holds


def poses(rng: np.random.Generator, angles_deg=(0, 60, 120, 180, 240, 300), hold: int = 300,
          turn: int = 80, gain=(1.0, 1.0, 1.0), bias=(0.0, 0.0, 0.0), noise: float = 0.02,
          gyro_bias: float = 0.003) -> Signal:
    """Held poses at ``angles_deg`` (``hold`` samples each) turned between in ``turn``
    samples; readings ``gain·a + bias + noise``; gyro z = dθ/dt + ``gyro_bias``."""
    th, holds = hold_and_turn(np.radians(np.asarray(angles_deg, float)), hold, turn)
    n = th.size
    t = np.arange(n) / RATE
    true = np.c_[-G_LOCAL * np.sin(th), -G_LOCAL * np.cos(th), np.full(n, 0.05)]
    acc = true * np.asarray(gain) + np.asarray(bias) + rng.normal(0.0, noise, (n, 3))
    rate = np.gradient(th, t)
    gyro = np.c_[rng.normal(0, 0.002, n), rng.normal(0, 0.002, n),
                 rate + gyro_bias + rng.normal(0, 0.002, n)]
    return Signal(t, acc, gyro, th, holds)


def still(rng: np.random.Generator, n: int = 3000, theta_deg: float = 30.0,
          gain=(1.0, 1.0, 1.0), noise: float = 0.02, gyro_bias=(0.001, -0.002, 0.02)
          ) -> Signal:
    """One held pose at ``theta_deg`` for ``n`` samples (white noise ``noise`` m/s²; the gyro
    a constant bias plus noise, rad/s)."""
    th = np.full(n, np.radians(theta_deg))
    t = np.arange(n) / RATE
    true = np.c_[-G_LOCAL * np.sin(th), -G_LOCAL * np.cos(th), np.full(n, 0.05)]
    acc = true * np.asarray(gain) + rng.normal(0.0, noise, (n, 3))
    gyro = np.asarray(gyro_bias) + rng.normal(0.0, 0.001, (n, 3))
    return Signal(t, acc, gyro, th, [(0, n)])


def vehicle(rng: np.random.Generator, n: int = 2000) -> Signal:
    """A planar vehicle run (x, y in the plane, z up and reading +g): speeding up, turning,
    braking; the readings are its motion, never still."""
    t = np.arange(n) / RATE
    ax = 1.5 * np.sin(2 * np.pi * t / 8.0) + 0.3
    ay = 0.8 * np.sin(2 * np.pi * t / 5.0)
    acc = np.c_[ax, ay, np.full(n, G_LOCAL)] + rng.normal(0.0, 0.05, (n, 3))
    gyro = np.c_[rng.normal(0, 0.002, (n, 2)), 0.2 * np.sin(2 * np.pi * t / 5.0)]
    return Signal(t, acc, gyro, np.full(n, np.nan), [])


# ---------------------------------------------------------------- text tables
def _cell(v: float, fmt: str) -> str:
    return format(float(v), fmt)


def table_text(header: list[str], columns: list[np.ndarray], sep: str = ",",
               fmt: str = ".6f", decimal_comma: bool = False,
               int_columns: tuple[int, ...] = (), fmts: dict[int, str] | None = None) -> str:
    """A header line plus one row per sample; ``columns`` 1-D or 2-D arrays side by side;
    ``int_columns``: indices (after stacking) written as integers; ``fmts``: a format of its
    own for some columns (e.g. a time column of nanosecond stamps)."""
    fmts = fmts or {}
    texts: list[list[str]] = []  # the cells of each column
    for c in columns:
        a = np.asarray(c)
        for col in (a[:, None] if a.ndim == 1 else a).T:
            j = len(texts)
            if np.issubdtype(col.dtype, np.integer):  # exact, e.g. nanosecond stamps
                texts.append([str(int(v)) for v in col])
            elif j in int_columns:
                texts.append([str(int(round(v))) for v in col])
            else:
                texts.append([_cell(v, fmts.get(j, fmt)) for v in col])
    lines = [sep.join(header)]
    for cells in zip(*texts, strict=True):
        if decimal_comma:
            cells = tuple(c.replace(".", ",") for c in cells)
        lines.append(sep.join(cells))
    return "\n".join(lines) + "\n"


def write_text(path: Path, text: str, gz: bool = False) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if gz:
        path.write_bytes(gzip.compress(text.encode(), mtime=0))
    else:
        path.write_text(text)
    return path


def csv_log(path: Path, sig: Signal, acc_head=("ax", "ay", "az"), gyro_head=None,
            time_head: str | None = "t", acc_factor: float = 1.0, gyro_factor: float = 1.0,
            time_values: np.ndarray | None = None, sep: str = ",", fmt: str = ".6f",
            decimal_comma: bool = False, gz: bool = False, counts: bool = False,
            time_fmt: str | None = None) -> Path:
    """``sig`` as a table: the acceleration times ``acc_factor`` (m/s² → the file's numbers),
    the gyro (if ``gyro_head``) times ``gyro_factor``, the time column ``time_values`` (s
    from 0 if not given, written with ``time_fmt``, else ``fmt``); ``counts``: acceleration
    written as integers."""
    header: list[str] = []
    cols: list[np.ndarray] = []
    if time_head is not None:
        header.append(time_head)
        cols.append(sig.t if time_values is None else time_values)
    header += list(acc_head)
    cols.append(sig.acc * acc_factor)
    first = 0 if time_head is None else 1  # the acceleration's first column
    ints = (first, first + 1, first + 2) if counts else ()
    if gyro_head is not None:
        header += list(gyro_head)
        cols.append(sig.gyro * gyro_factor)
    fmts = {0: time_fmt} if time_head is not None and time_fmt else None
    text = table_text(header, cols, sep=sep, fmt=fmt, decimal_comma=decimal_comma,
                      int_columns=ints, fmts=fmts)
    return write_text(path, text, gz=gz)


def edit_row(text: str, line: int, edit) -> str:
    """``text`` with its 1-based ``line`` replaced by ``edit(line_text)``."""
    lines = text.splitlines()
    lines[line - 1] = edit(lines[line - 1])
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- phone exports
PHYPHOX_HEADER = ('"Time (s)","{w} x (m/s^2)","{w} y (m/s^2)","{w} z (m/s^2)",'
                  '"Absolute acceleration (m/s^2)"')


def phyphox_text(sig: Signal, linear: bool = False, acc_factor: float = 1.0) -> str:
    """phyphox's "Acceleration with g" (or, ``linear``, "Linear Acceleration") CSV: comma,
    decimal point, quoted header stating m/s²."""
    head = PHYPHOX_HEADER.format(w="Linear Acceleration" if linear else "Acceleration")
    acc = sig.acc * acc_factor
    rows = [",".join(f"{v:.6E}" for v in (t, *a, np.linalg.norm(a)))
            for t, a in zip(sig.t, acc, strict=True)]
    return head + "\n" + "\n".join(rows) + "\n"


def phyphox_zip(path: Path, member_text: str) -> Path:
    """phyphox's "CSV (zip)" export: ``Accelerometer.csv`` plus its ``meta/`` files."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in (("Accelerometer.csv", member_text),
                           ("meta/device.csv", '"property","value"\n"deviceModel","Pixel"\n'),
                           ("meta/time.csv", '"event","experiment time"\n"START",0.0\n')):
            info = zipfile.ZipInfo(name, date_time=(2026, 1, 1, 0, 0, 0))
            z.writestr(info, text, compress_type=zipfile.ZIP_DEFLATED)
    return path


def sensorlogger(path: Path, sig: Signal, acc_factor: float = 1.0) -> Path:
    """A Sensor Logger accelerometer export: ``time`` (ns since the epoch),
    ``seconds_elapsed``, then ``z, y, x`` (its column order)."""
    acc = sig.acc * acc_factor
    rows = [f"{T0_NS + int(round(t * 1e9))},{t:.4f},{a[2]:.6f},{a[1]:.6f},{a[0]:.6f}"
            for t, a in zip(sig.t, acc, strict=True)]
    return write_text(path, "time,seconds_elapsed,z,y,x\n" + "\n".join(rows) + "\n")


# ---------------------------------------------------------------- ROS bags
def _imu_messages(typestore, sig: Signal, acc_factor: float):
    Imu = typestore.types["sensor_msgs/msg/Imu"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    Quat = typestore.types["geometry_msgs/msg/Quaternion"]
    Vec = typestore.types["geometry_msgs/msg/Vector3"]
    seq = "seq" in Header.__dataclass_fields__
    for k in range(sig.t.size):
        ns = 1_000_000_000_000 + int(round(sig.t[k] * 1e9))
        stamp = Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        a, w = sig.acc[k] * acc_factor, sig.gyro[k]
        msg = Imu(header=Header(stamp=stamp, frame_id="imu", **({"seq": k} if seq else {})),
                  orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0),
                  orientation_covariance=np.zeros(9),
                  angular_velocity=Vec(x=w[0], y=w[1], z=w[2]),
                  angular_velocity_covariance=np.zeros(9),
                  linear_acceleration=Vec(x=a[0], y=a[1], z=a[2]),
                  linear_acceleration_covariance=np.zeros(9))
        yield ns + 1234, msg


def ros1_bag(path: Path, sig: Signal, acc_factor: float = 1.0) -> Path:
    """A ROS 1 ``.bag`` with one ``sensor_msgs/Imu`` topic ``/imu/data``."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.exists():
        path.unlink()
    with Writer(path) as w:
        conn = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=ts)
        for t, msg in _imu_messages(ts, sig, acc_factor):
            w.write(conn, t, ts.serialize_ros1(msg, "sensor_msgs/msg/Imu"))
    return path


def ros2_bag(path: Path, sig: Signal, acc_factor: float = 1.0) -> dict[str, Path]:
    """A ROS 2 bag directory (sqlite3 storage) with one Imu topic ``/imu``; returns its files
    by name inside the directory (``metadata.yaml``, ``<name>.db3``)."""
    import shutil

    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    if path.exists():
        shutil.rmtree(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with Writer(path, version=8) as w:
        conn = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
        for t, msg in _imu_messages(ts, sig, acc_factor):
            w.write(conn, t, ts.serialize_cdr(msg, "sensor_msgs/msg/Imu"))
    return {p.name: p for p in sorted(path.iterdir())}


# ---------------------------------------------------------------- damage
def truncated(src: Path, dst: Path, fraction: float = 0.5) -> Path:
    """The first ``fraction`` of ``src``'s bytes."""
    data = src.read_bytes()
    dst.write_bytes(data[: int(len(data) * fraction)])
    return dst


def flipped(src: Path, dst: Path, where: float = 0.5, count: int = 64) -> Path:
    """``src`` with ``count`` bytes inverted (XOR 0xFF) from ``where`` of its length."""
    data = bytearray(src.read_bytes())
    start = int(len(data) * where)
    for k in range(start, min(start + count, len(data))):
        data[k] ^= 0xFF
    dst.write_bytes(bytes(data))
    return dst


# ---------------------------------------------------------------- .mat
def mat_log(path: Path, sig: Signal, acc_factor: float = 1.0, dtype=float) -> Path:
    """A ``.mat`` with its own names: ``acc`` N×3 (× ``acc_factor``, cast to ``dtype``: e.g.
    ``np.int16`` raw counts) and ``time`` N×1 s (read with ``--map datos=acc,t=time``)."""
    import scipy.io

    acc = sig.acc * acc_factor
    if np.issubdtype(np.dtype(dtype), np.integer):
        acc = np.round(acc)
    path.parent.mkdir(parents=True, exist_ok=True)
    scipy.io.savemat(path, {"acc": acc.astype(dtype), "time": sig.t.reshape(-1, 1)})
    # the 116-byte text of the MAT 5 header holds the time of writing: a fixed text instead,
    # so that the same seed gives the same bytes
    data = bytearray(path.read_bytes())
    data[:116] = b"MATLAB 5.0 MAT-file, written by validation.fuzz".ljust(116)
    path.write_bytes(bytes(data))
    return path
