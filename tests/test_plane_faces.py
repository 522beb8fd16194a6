"""A six-face log in the tilt-plane commands: θ of the holds on faces in the plane from the
course signs, the faces ±n set aside (:mod:`calib.calibration.plane_faces`), and ``gap`` on a
six-face CSV without hand cutting."""

from __future__ import annotations

import numpy as np
import pytest

from calib.calibration.plane_faces import face_angle, tilt_plane_faces
from calib.conventions import G
from calib.input_rules import DataError
from calib.logs.reader import ImuLog, LogOptions, read_log
from tests.cli import run
from tests.test_sixface_cli import write_six_face_log


@pytest.mark.parametrize("u, theta", [((1, 0, 0), -np.pi / 2), ((-1, 0, 0), np.pi / 2),
                                      ((0, -1, 0), 0.0), ((0, 1, 0), np.pi)])
def test_face_angle_gives_the_course_reference_reading(u, theta):
    """A_r = g·u must equal the course reference (−g sin θ, −g cos θ) at the face's θ."""
    th = face_angle(np.array(u, float))
    assert np.isclose(np.cos(th), np.cos(theta)) and np.isclose(np.sin(th), np.sin(theta))
    assert np.allclose([-G * np.sin(th), -G * np.cos(th)], G * np.array(u[:2]), atol=1e-12)


def test_six_face_log_keeps_the_in_plane_holds_with_their_face_angles(tmp_path):
    log = read_log(write_six_face_log(tmp_path / "faces.csv"), LogOptions())
    assert log.theta is None and log.pose.max() == 11  # 12 holds on 6 faces
    plane = tilt_plane_faces(log)
    faces = [r["face"] for r in plane.provenance["plane_faces"]]
    assert sorted(set(faces)) == ["+n", "+x", "+y", "-n", "-x", "-y"]
    kept = [r for r in plane.provenance["plane_faces"] if r["theta_rad"] != "out of the tilt plane"]
    assert len(kept) == 8 and plane.pose.max() == 7
    # every kept sample's reading matches its θ's course reference to within the errors
    ref = np.column_stack([-G * np.sin(plane.theta), -G * np.cos(plane.theta)])
    assert np.max(np.abs(plane.acc - ref)) < 0.6  # bias 0.2 + scale 2 % of g + noise
    assert np.all(np.abs(plane.acc_normal) < 1.0)  # the normal axis is horizontal
    assert plane.n == int(np.isin(log.pose, [r["hold"] for r in kept]).sum())
    assert "out of the plane set aside" in plane.provenance["held_samples_only"]


def test_logs_that_are_not_six_face_logs_are_left_alone(tmp_path):
    acc = np.tile([0.0, -G], (30, 1))
    assert tilt_plane_faces(ImuLog(acc=acc, theta=np.zeros(30))) is None  # θ known
    assert tilt_plane_faces(ImuLog(acc=acc, pose=np.zeros(30, int))) is None  # 2 axes
    one_hold = ImuLog(acc=np.zeros((30, 2)), acc_normal=np.full(30, G), pose=np.zeros(30, int))
    assert tilt_plane_faces(one_hold) is None  # a still log: θ unknown, not a six-face log
    tilted = np.tile([G * 0.6, -G * 0.8], (30, 1))  # 37° off the y face
    assert tilt_plane_faces(ImuLog(acc=tilted, acc_normal=np.zeros(30),
                                   pose=np.zeros(30, int))) is None


def test_a_log_with_one_in_plane_face_is_refused_naming_the_faces():
    acc = np.vstack([np.tile([0.0, -G], (30, 1)), np.zeros((60, 2))])
    normal = np.concatenate([np.zeros(30), np.full(30, G), np.full(30, -G)])
    pose = np.repeat([0, 1, 2], 30)
    with pytest.raises(DataError, match=r"1 face\(s\) in the tilt plane \(-y.*--axes"):
        tilt_plane_faces(ImuLog(acc=acc, acc_normal=normal, pose=pose, source="f.csv"))


def test_gap_takes_a_six_face_log_on_its_own(capsys, tmp_path):
    path = write_six_face_log(tmp_path / "faces.csv")
    rc, out, err = run(capsys, "gap", path, "--json")
    assert rc == 0, err
    assert "six-face log: the 8 holds on faces in the tilt plane kept" in err.replace("\n    ", " ")
