"""calib.logs.reader.read_log: every format gives the same readings; units, axes, θ and labels.

The same simulated log (tests/logfixtures.py: five held poses, 3-axis accelerometer and
gyro, fixed seed) is written as CSV (comma; semicolon with decimal comma; tab; gzip), a
phyphox export, a Sensor Logger export, a ROS 2 bag, a ROS 1 bag and a .mat read with --map.
Text is written with ``repr`` and times come from integer ns, so the readings must agree to
1e-12 relative (in fact exactly).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from calib.files.course import read_acel, read_ensayo
from calib.input_rules import DataError
from calib.logs.reader import ImuLog, LogOptions, read_log, tilt_axis
from tests import logfixtures as fx

MAP = {"datos": "acc", "t": "time"}


def _close(a, b) -> bool:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= 1e-12 * np.maximum(1.0, np.abs(b))))


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("logs")
    with_gyro = {
        "csv": fx.write_csv(d / "a.csv"),
        "csv_semicolon_decimal_comma": fx.write_csv(d / "b.csv", sep=";", decimal_comma=True),
        "tsv": fx.write_csv(d / "c.tsv", sep="\t"),
        "csv_gz": fx.write_csv(d / "d.csv.gz", gz=True),
        "ros2": fx.write_ros2(d / "bag2"),
        "ros1": fx.write_ros1(d / "x.bag"),
    }
    without_gyro = {
        "csv_no_gyro": fx.write_csv(d / "e.csv", gyro=False),
        "phyphox": fx.write_phyphox(d / "Raw Data.csv"),
        "sensorlogger": fx.write_sensorlogger(d / "TotalAcceleration.csv"),
        "mat_map": fx.write_mat(d / "m.mat"),
    }
    return with_gyro, without_gyro


def _read(path, **kw) -> ImuLog:
    mapping = MAP if path.suffix == ".mat" else {}
    return read_log(path, LogOptions(mapping=mapping, **kw))


def test_every_format_gives_the_same_readings(logs):
    with_gyro, without_gyro = logs
    t_ns, _, acc, gyro, _ = fx.simulated()
    t = fx.seconds(t_ns)
    for name, path in {**with_gyro, **without_gyro}.items():
        log = _read(path)
        assert _close(log.acc, acc[:, :2]), name
        assert _close(log.t, t), name
        assert log.theta is None, name  # no angles given: θ unknown, poses labelled
        assert log.pose is not None and log.pose.max() + 1 == len(fx.ANGLES_DEG), name
        if name in with_gyro:
            assert _close(log.gyro, gyro[:, 2]), name  # about the tilt axis z (axes x,y)
        else:
            assert log.gyro is None, name


def test_same_log_with_pose_angles_gives_identical_imulogs(logs):
    """Held samples only, θ from --poses: identical within each group (the gyro joins the
    detector, so the gyro-less formats hold a few more samples)."""
    for group in logs:
        made = {n: _read(p, poses=fx.ANGLES_DEG, angle_unit="deg") for n, p in group.items()}
        ref = next(iter(made.values()))
        for name, log in made.items():
            for field in ("acc", "t", "theta", "pose", "gyro"):
                a, b = getattr(log, field), getattr(ref, field)
                assert (a is None) == (b is None), (name, field)
                if a is not None:
                    assert _close(a, b), (name, field)
        assert "held samples" in ref.provenance["held_samples_only"]


def test_held_samples_carry_the_true_angle(logs):
    _, theta, _, _, holds = fx.simulated()
    log = _read(logs[0]["csv"], poses=fx.ANGLES_DEG, angle_unit="deg")
    t_true = fx.seconds(fx.simulated()[0])
    idx = np.searchsorted(t_true, log.t)
    assert np.array_equal(t_true[idx], log.t)
    assert _close(log.theta, theta[idx])  # every kept sample lies in its true hold
    for k, (a, b) in enumerate(holds):
        assert np.all((idx[log.pose == k] >= a) & (idx[log.pose == k] < b))


def test_units_and_conversion_with_g(tmp_path):
    """g, mg and counts are converted with the unit g, standard gravity 9.80665 m/s², whatever
    local gravity ``g`` the sensor feels (issue 30: ``--g`` is the local gravity)."""
    rng = np.random.default_rng(0)
    n = 400
    theta = np.repeat([0.0, 1.0], n // 2)
    g_units = np.c_[-np.sin(theta), -np.cos(theta)] + 0.001 * rng.standard_normal((n, 2))
    t = np.arange(n) * 0.01
    body = "\n".join(",".join(repr(float(v)) for v in r) for r in np.c_[t, g_units])
    (tmp_path / "g.csv").write_text("t,acc_x [g],acc_y [g]\n" + body + "\n")
    mg = "\n".join(",".join(repr(float(v)) for v in r) for r in np.c_[t, 1000 * g_units])
    (tmp_path / "mg.csv").write_text("t,ax_mg,ay_mg\n" + mg + "\n")
    counts = np.round(g_units * 4096)
    cs = "\n".join(",".join(repr(float(v)) for v in r) for r in np.c_[t, counts])
    (tmp_path / "c.csv").write_text("t,ax,ay\n" + cs + "\n")
    log = read_log(tmp_path / "g.csv", LogOptions(g=9.81))
    assert np.allclose(log.acc, 9.80665 * g_units, rtol=1e-15, atol=0)
    assert log.provenance["units"]["acc"] == "g"
    log = read_log(tmp_path / "mg.csv")
    assert np.allclose(log.acc, 9.80665 * g_units, rtol=1e-12, atol=0)
    log = read_log(tmp_path / "c.csv", LogOptions(units="counts", sensitivity=4096.0))
    assert np.allclose(log.acc, counts / 4096.0 * 9.80665, rtol=1e-15, atol=0)
    with pytest.raises(DataError, match=r"'ax'.*--units"):
        read_log(tmp_path / "c.csv")  # unit neither stated nor recognized: refused
    with pytest.raises(DataError, match="states the acceleration in g but --units m/s2"):
        read_log(tmp_path / "g.csv", LogOptions(units="m/s2"))


def test_axes_pick_and_sign_and_the_gyro_follows(logs):
    t_ns, _, acc, gyro, _ = fx.simulated()
    log = read_log(logs[0]["ros2"], LogOptions(axes=("-y", "z")))
    assert _close(log.acc, np.c_[-acc[:, 1], acc[:, 2]])
    assert tilt_axis(("-y", "z")) == "-x"
    assert _close(log.gyro, -gyro[:, 0])  # right-handed about -y × z = -x
    assert tilt_axis(("x", "y")) == "z" and tilt_axis(("y", "x")) == "-z"
    two = _two_axis_mat(logs[1]["mat_map"].parent)
    with pytest.raises(DataError, match="no z acceleration"):
        read_log(two, LogOptions(axes=("x", "z"), mapping={"datos": "a"}))


def _two_axis_mat(d):
    p = d / "two.mat"
    scipy.io.savemat(p, {"a": np.c_[np.zeros(10), -9.8 * np.ones(10)]})
    return p


def test_theta_column_in_degrees_is_caught_by_the_data(tmp_path):
    rng = np.random.default_rng(2)
    deg = np.repeat([0.0, 30.0, 60.0, 90.0], 50)
    acc = np.c_[-9.8 * np.sin(np.deg2rad(deg)), -9.8 * np.cos(np.deg2rad(deg))]
    acc += 0.01 * rng.standard_normal(acc.shape)
    body = "\n".join(",".join(repr(float(v)) for v in r) for r in np.c_[deg, acc])
    (tmp_path / "th.csv").write_text("theta,ax (m/s^2),ay (m/s^2)\n" + body + "\n")
    with pytest.raises(DataError, match="look like degrees.*--angle-unit deg"):
        read_log(tmp_path / "th.csv")
    log = read_log(tmp_path / "th.csv", LogOptions(angle_unit="deg"))
    assert _close(log.theta, np.deg2rad(deg))
    (tmp_path / "th2.csv").write_text("theta (deg),ax (m/s^2),ay (m/s^2)\n" + body + "\n")
    assert _close(read_log(tmp_path / "th2.csv").theta, np.deg2rad(deg))


def test_label_column_mapped_to_angles(tmp_path):
    rng = np.random.default_rng(5)
    labels = ["a"] * 60 + ["moving"] * 5 + ["b"] * 60 + [""] * 5 + ["a"] * 60
    ang = {"a": 0.0, "b": 90.0}
    th = np.deg2rad([ang.get(v, 45.0) for v in labels])
    acc = np.c_[-9.8 * np.sin(th), -9.8 * np.cos(th)] + 0.01 * rng.standard_normal((190, 2))
    rows = [f"{lab},{float(acc[i, 0])!r},{float(acc[i, 1])!r}" for i, lab in enumerate(labels)]
    (tmp_path / "l.csv").write_text("label,ax (m/s^2),ay (m/s^2)\n" + "\n".join(rows) + "\n")
    log = read_log(tmp_path / "l.csv")
    assert log.theta is None and log.pose.tolist() == [0] * 60 + [-1] * 5 + [1] * 60 + \
        [-1] * 5 + [0] * 60  # a repeated label is the same pose
    log = read_log(tmp_path / "l.csv", LogOptions(label_angles=ang, angle_unit="deg"))
    assert log.n == 180 and _close(log.theta, np.deg2rad([0.0] * 60 + [90.0] * 60 + [0.0] * 60))


def test_course_files_read_unchanged(course_dir):
    e = read_ensayo(course_dir / "ensayo.mat")
    log = read_log(course_dir / "ensayo.mat")
    assert log.course is not None and log.to_ensayo() is log.course
    assert np.array_equal(log.acc, e.datos) and np.array_equal(log.theta, e.tita)
    a = read_acel(course_dir / "acel.mat")
    log = read_log(course_dir / "acel.mat", expect="acel")
    assert np.array_equal(log.to_acel().aerr, a.aerr) and np.array_equal(log.t, a.t)


def test_course_data_as_csv_gives_the_same_ensayo(tmp_path, course_dir):
    """The course ensayo written as a CSV (θ in rad, unstated: the degrees check passes it)."""
    e = read_ensayo(course_dir / "ensayo.mat")
    body = "\n".join(f"{th!r},{x!r},{y!r}" for th, (x, y) in zip(e.tita.tolist(),
                                                                 e.datos.tolist(), strict=True))
    (tmp_path / "e.csv").write_text("tita,ax (m/s^2),ay (m/s^2)\n" + body + "\n")
    got = read_log(tmp_path / "e.csv").to_ensayo()
    assert np.array_equal(got.tita, e.tita) and np.array_equal(got.datos, e.datos)


def test_ros2_topic_choice(tmp_path):
    bag = fx.write_ros2(tmp_path / "two", topics=("/imu/a", "/imu/b"))
    with pytest.raises(DataError, match=r"several sensor_msgs/Imu topics \(/imu/a, /imu/b\)"):
        read_log(bag)
    log = read_log(bag, LogOptions(columns={"topic": "/imu/b"}))
    assert log.provenance["reader"]["topic"] == "/imu/b"
    with pytest.raises(DataError, match="no such sensor_msgs/Imu topic"):
        read_log(bag, LogOptions(columns={"topic": "/nope"}))


def test_provenance_names_source_mapping_units(logs):
    log = _read(logs[0]["csv_semicolon_decimal_comma"])
    p = log.provenance
    assert p["source"]["name"] == "b.csv" and len(p["source"]["sha256"]) == 64
    assert p["reader"]["delimiter"] == ";" and p["reader"]["decimal"] == ","
    assert p["mapping"]["x"] == "ax (m/s^2)" and p["units"]["acc"] == "m/s2"
    assert p["poses"]["source"] == "detected"
    assert p["poses"]["detection"]["threshold"] > p["poses"]["detection"]["quiet_level"] > 0


def test_mat_map_with_angles_and_a_named_gyro_column(tmp_path):
    rng = np.random.default_rng(6)
    deg = np.repeat([0.0, 60.0, 120.0, 200.0], 40)
    acc = np.c_[-9.8 * np.sin(np.deg2rad(deg)), -9.8 * np.cos(np.deg2rad(deg))]
    acc += 0.01 * rng.standard_normal(acc.shape)
    scipy.io.savemat(tmp_path / "w.mat", {"angle": deg.reshape(-1, 1), "acc": acc})
    log = read_log(tmp_path / "w.mat", LogOptions(mapping={"tita": "angle", "datos": "acc"},
                                                  angle_unit="deg"))
    assert _close(log.theta, np.deg2rad(deg)) and _close(log.acc, acc)
    assert log.provenance["mapping"] == {"tita": "angle", "datos": "acc"}
    rate = rng.standard_normal(160)
    body = "\n".join(f"{0.01 * k!r},{x!r},{y!r},{w!r}" for k, (x, y, w) in
                     enumerate(np.c_[acc, rate].tolist()))
    (tmp_path / "w.csv").write_text("t,ax (m/s^2),ay (m/s^2),turn (deg/s)\n" + body + "\n")
    log = read_log(tmp_path / "w.csv", LogOptions(columns={"gyro": "turn (deg/s)"}))
    assert _close(log.gyro, np.deg2rad(rate))


def test_an_imported_ensayo_keeps_its_pose_labels_for_the_course_reader(tmp_path):
    """``tiltbench import`` writes ``pose`` beside ``tita``/``datos``: reading it back as a
    course input keeps the labels (lack of fit, pure-error σ²); a label per sample or a
    one-line error naming the file."""
    tita = np.repeat([0.0, 1.0, 2.0, 3.0], 5)
    noise = np.random.default_rng(5).standard_normal((20, 2)) * 0.01
    datos = np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)]) + noise
    pose = np.repeat([0, 1, 2, 3], 5)
    scipy.io.savemat(tmp_path / "ok.mat", {"tita": tita[:, None], "datos": datos,
                                           "pose": pose[:, None].astype(np.int32)})
    log = read_log(tmp_path / "ok.mat", expect="ensayo")
    assert log.pose is not None and np.array_equal(log.pose, pose)
    scipy.io.savemat(tmp_path / "bad.mat", {"tita": tita[:, None], "datos": datos,
                                            "pose": pose[:7, None]})
    with pytest.raises(DataError, match="bad.mat: 'pose' must hold one integer label"):
        read_log(tmp_path / "bad.mat", expect="ensayo")
