"""Measured-log fixtures for the reader tests: one simulated multi-pose IMU log (numpy only,
fixed seed, known pose boundaries) written in every format :func:`calib.logs.reader.read_log` reads.

The log: a 3-axis accelerometer and gyro at 100 Hz, held at :data:`ANGLES_DEG` in turn for
:data:`HOLD` samples each, turned between them in :data:`TURN` samples; the tilt plane is the
sensor's x, y (course signs ``a_x = -g sin θ``, ``a_y = -g cos θ``), the tilt axis z. Times
come from integer nanoseconds (as a ROS header stamp) so that every format holds the same
float64 values: text formats are written with ``repr`` (round-trips exactly).
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np

from validation.fuzz.logfiles import hold_and_turn

ANGLES_DEG = (0.0, 90.0, 180.0, 270.0, 45.0)
HOLD, TURN = 300, 80
RATE_NS = 10_000_000  # 100 Hz
T0_NS = 1_000_000_000_000  # 1000 s
G = 9.8
NOISE = 0.02  # m/s², per axis


def seconds(t_ns: np.ndarray) -> np.ndarray:
    """s from integer ns, computed as the bag reader does."""
    return (t_ns // 1_000_000_000).astype(float) + (t_ns % 1_000_000_000).astype(float) * 1e-9


def simulated(seed: int = 3):
    """``(t_ns, theta, acc (N,3) m/s², gyro (N,3) rad/s, holds)``; ``holds`` lists each pose's
    true ``[start, stop)`` sample range."""
    rng = np.random.default_rng(seed)
    theta, holds = hold_and_turn(np.deg2rad(ANGLES_DEG), HOLD, TURN)
    n = theta.size
    t_ns = T0_NS + RATE_NS * np.arange(n, dtype=np.int64)
    acc = np.c_[-G * np.sin(theta), -G * np.cos(theta), 0.05 * np.ones(n)]
    acc = acc + NOISE * rng.standard_normal((n, 3))
    rate = np.gradient(theta, seconds(t_ns))
    gyro = np.c_[0.002 * rng.standard_normal(n), 0.002 * rng.standard_normal(n),
                 rate + 0.002 * rng.standard_normal(n)]
    return t_ns, theta, acc, gyro, holds


def _rows(cols) -> list[list[str]]:
    return [[repr(float(v)) for v in row] for row in np.column_stack(cols)]


def write_csv(path: Path, sep: str = ",", decimal_comma: bool = False, gz: bool = False,
              gyro: bool = True, seed: int = 3) -> Path:
    """A generic table: ``time (s)``, ``ax (m/s^2)`` … and, with ``gyro``, ``gx (rad/s)`` …"""
    t_ns, _, acc, rate, _ = simulated(seed)
    head = ["time (s)", "ax (m/s^2)", "ay (m/s^2)", "az (m/s^2)"]
    cols = [seconds(t_ns), acc]
    if gyro:
        head += ["gx (rad/s)", "gy (rad/s)", "gz (rad/s)"]
        cols.append(rate)
    lines = [sep.join(head)]
    for row in _rows(cols):
        if decimal_comma:
            row = [c.replace(".", ",") for c in row]
        lines.append(sep.join(row))
    text = "\n".join(lines) + "\n"
    if gz:
        path.write_bytes(gzip.compress(text.encode(), mtime=0))
    else:
        path.write_text(text)
    return path


def write_phyphox(path: Path, linear: bool = False, seed: int = 3) -> Path:
    """phyphox "Acceleration with g" export (comma, decimal point, quoted header); no gyro."""
    t_ns, _, acc, _, _ = simulated(seed)
    word = "Linear Acceleration" if linear else "Acceleration"
    head = ['"Time (s)"'] + [f'"{word} {a} (m/s^2)"' for a in "xyz"] + [
        '"Absolute acceleration (m/s^2)"']
    lines = [",".join(head)]
    for row in _rows([seconds(t_ns), acc, np.linalg.norm(acc, axis=1)]):
        lines.append(",".join(row))
    path.write_text("\n".join(lines) + "\n")
    return path


def write_sensorlogger(path: Path, seed: int = 3) -> Path:
    """Sensor Logger export: ``time`` ns since the epoch, ``seconds_elapsed``, z, y, x."""
    t_ns, _, acc, _, _ = simulated(seed)
    lines = ["time,seconds_elapsed,z,y,x"]
    for k, row in enumerate(_rows([seconds(t_ns), acc[:, 2], acc[:, 1], acc[:, 0]])):
        lines.append(",".join([str(1_700_000_000_000_000_000 + int(t_ns[k])), *row]))
    path.write_text("\n".join(lines) + "\n")
    return path


def _imu_messages(typestore, seed: int):
    t_ns, _, acc, gyro, _ = simulated(seed)
    # bag time differs from the stamp: the stamp is used
    yield from imu_messages(typestore, t_ns, acc, gyro, bag_offset_ns=1234)


def imu_messages(typestore, t_ns: np.ndarray, acc: np.ndarray, gyro: np.ndarray,
                 bag_offset_ns: int = 0):
    """``(bag time ns, sensor_msgs/Imu)`` of each sample: stamp ``t_ns``, acceleration
    ``acc`` (N, 3) m/s², rate ``gyro`` (N, 3) rad/s; ROS 1 headers get a ``seq``."""
    Imu = typestore.types["sensor_msgs/msg/Imu"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    Quat = typestore.types["geometry_msgs/msg/Quaternion"]
    Vec = typestore.types["geometry_msgs/msg/Vector3"]
    for k in range(t_ns.size):
        stamp = Time(sec=int(t_ns[k] // 1_000_000_000), nanosec=int(t_ns[k] % 1_000_000_000))
        kw = {"seq": k} if "seq" in Header.__dataclass_fields__ else {}
        msg = Imu(header=Header(stamp=stamp, frame_id="imu", **kw),
                  orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0),
                  orientation_covariance=np.zeros(9),
                  angular_velocity=Vec(x=gyro[k, 0], y=gyro[k, 1], z=gyro[k, 2]),
                  angular_velocity_covariance=np.zeros(9),
                  linear_acceleration=Vec(x=acc[k, 0], y=acc[k, 1], z=acc[k, 2]),
                  linear_acceleration_covariance=np.zeros(9))
        yield int(t_ns[k]) + bag_offset_ns, msg


def write_ros2(path: Path, topics=("/imu",), seed: int = 3) -> Path:
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    msgtype = "sensor_msgs/msg/Imu"
    with Writer(path, version=8) as w:
        conns = [w.add_connection(tp, msgtype, typestore=ts) for tp in topics]
        for t, msg in _imu_messages(ts, seed):
            for c in conns:
                w.write(c, t, ts.serialize_cdr(msg, msgtype))
    return path


def write_ros1(path: Path, seed: int = 3) -> Path:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    msgtype = "sensor_msgs/msg/Imu"
    with Writer(path) as w:
        conn = w.add_connection("/imu/data", msgtype, typestore=ts)
        for t, msg in _imu_messages(ts, seed):
            w.write(conn, t, ts.serialize_ros1(msg, msgtype))
    return path


def write_mat(path: Path, seed: int = 3) -> Path:
    """A .mat with its own names: ``acc`` N×3 m/s², ``time`` N×1 s (read with --map)."""
    import scipy.io

    t_ns, _, acc, _, _ = simulated(seed)
    scipy.io.savemat(path, {"acc": acc, "time": seconds(t_ns).reshape(-1, 1)})
    return path
