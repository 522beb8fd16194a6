"""ROS 1 (``.bag``) and ROS 2 (a bag directory, or its ``.db3``/``.mcap`` file) logs of
``sensor_msgs/Imu`` messages, read with ``rosbags`` (pure Python, no ROS install).

Per message: time from ``header.stamp`` (s + ns·10⁻⁹), or the bag's receive time when every
stamp is zero (a driver that does not stamp); ``linear_acceleration`` x, y, z in m/s² and
``angular_velocity`` x, y, z in rad/s — the units the message definition states (REP 103).
The topic is the only ``sensor_msgs/Imu`` topic in the bag, else the one named by
``--columns topic=/imu``; with several and none named the error lists them.

A damaged bag — one that cannot be opened, or whose messages cannot be read or decoded
(``rosbags`` raises its own errors, and also ``AssertionError``, ``KeyError``,
``UnicodeDecodeError`` … on flipped bytes) — is refused in one line naming the file, the
message that failed and the error, never with a traceback.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from calib.input_rules import DataError, file_head
from calib.logs.table import RawLog

IMU = ("sensor_msgs/msg/Imu", "sensor_msgs/Imu")


def is_bag(path: Path) -> bool:
    """A ROS 1 bag (``#ROSBAG V2.0`` header), a ROS 2 bag directory (``metadata.yaml``) or a
    ROS 2 storage file (``.db3``, ``.mcap``)."""
    if path.is_dir():
        return (path / "metadata.yaml").exists()
    return (path.suffix.lower() in (".db3", ".mcap")
            or file_head(path, 13) == b"#ROSBAG V2.0\n")


def read_bag(path: Path, topic: str | None = None) -> RawLog:
    """Read the ``sensor_msgs/Imu`` messages of one topic (module docstring).

    Raises
    ------
    DataError : not a readable bag, a message that cannot be read or decoded, no Imu topic,
        several and none chosen, the chosen topic absent or empty.
    """
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    bag = path.parent if path.suffix.lower() in (".db3", ".mcap") and (
        path.parent / "metadata.yaml").exists() else path
    try:
        reader = AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except Exception as exc:  # rosbags raises its own types for damaged or foreign files
        raise DataError(f"{path}: not a readable ROS bag ({' '.join(str(exc).split())})"
                        ) from exc
    failed = True
    try:
        topic, stamp, recv, acc, rate = _messages(reader, path, topic)
        failed = False
    finally:
        try:
            reader.close()
        except Exception as exc:  # noqa: BLE001 — rosbags' own types, and more on damage
            if not failed:
                raise DataError(f"{path}: a damaged ROS bag: closing it failed "
                                f"({_why(exc)})") from exc
    if not acc:
        raise DataError(f"{path}: topic {topic} holds no messages")
    version = "rosbag2" if bag.is_dir() or bag.suffix.lower() in (".db3", ".mcap") else "rosbag1"
    stamped = any(stamp)
    t_ns = np.array(stamp if stamped else recv, dtype=np.int64)
    # seconds from integer ns: exact to the float's precision, the same as writing s + ns·1e-9
    t = (t_ns // 1_000_000_000).astype(float) + (t_ns % 1_000_000_000).astype(float) * 1e-9
    acc_a, rate_a = np.array(acc, dtype=float), np.array(rate, dtype=float)
    field = "header.stamp" if stamped else "bag receive time"
    return RawLog(
        fmt=version, acc={k: acc_a[:, i] for i, k in enumerate("xyz")}, acc_unit="m/s2",
        t=t, gyro={k: rate_a[:, i] for i, k in enumerate("xyz")}, gyro_unit="rad/s",
        rows=np.arange(len(acc)), row_word="message",
        mapping={"t": f"{topic}: {field}", **{k: f"{topic}: linear_acceleration.{k}"
                                              for k in "xyz"},
                 **{f"gyro_{k}": f"{topic}: angular_velocity.{k}" for k in "xyz"}},
        notes={"topic": topic, "messages": len(acc), "time": field})


def _why(exc: BaseException) -> str:
    """An exception as one short line: its type and message."""
    text = " ".join(str(exc).split())
    text = text if len(text) <= 120 else text[:117] + "..."
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _messages(reader, path: Path, topic: str | None
              ) -> tuple[str, list[int], list[int], list[tuple], list[tuple]]:
    """The chosen topic and its messages' stamps (ns), receive times (ns), accelerations
    and rates; any error while reading or decoding a message is a one-line DataError."""
    imu = [c for c in reader.connections if c.msgtype in IMU]
    topics = sorted({c.topic for c in imu})
    if not topics:
        found = sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})
        raise DataError(f"{path}: no sensor_msgs/Imu topic (topics: "
                        f"{', '.join(found) or 'none'})")
    if topic is None:
        if len(topics) > 1:
            raise DataError(f"{path}: several sensor_msgs/Imu topics ({', '.join(topics)});"
                            " choose one with --columns topic=NAME")
        topic = topics[0]
    elif topic not in topics:
        raise DataError(f"{path}: --columns topic={topic}: no such sensor_msgs/Imu topic "
                        f"(Imu topics: {', '.join(topics)})")
    conns = [c for c in imu if c.topic == topic]
    stamp: list[int] = []
    recv: list[int] = []
    acc: list[tuple] = []
    rate: list[tuple] = []
    try:
        for conn, t_ns, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            s = msg.header.stamp
            a, w = msg.linear_acceleration, msg.angular_velocity
            row_a, row_w = (float(a.x), float(a.y), float(a.z)), (float(w.x), float(w.y),
                                                                  float(w.z))
            stamp.append(int(s.sec) * 1_000_000_000 + int(s.nanosec))
            recv.append(int(t_ns))
            acc.append(row_a)
            rate.append(row_w)
    except Exception as exc:  # noqa: BLE001 — rosbags' own types, and more on damage
        raise DataError(f"{path}: a damaged ROS bag: message {len(acc) + 1} of {topic} "
                        f"cannot be read ({_why(exc)}); the {len(acc)} before it can: cut "
                        "the bag before it or record again") from exc
    return topic, stamp, recv, acc, rate


__all__ = ["IMU", "is_bag", "read_bag"]
