"""``--poses`` marks a held pose outside the tilt plane with ``-``: a six-face log goes
through the tilt-plane commands with its ±z faces set aside, no hand cutting."""

from __future__ import annotations

import json

import numpy as np
import pytest

from calib.logs.reader import LogOptions, read_log
from tests.cli import one_line_error, run, unwrap
from tests.test_sixface_cli import write_six_face_log

# write_six_face_log's order: +x +y +z -x -y -z, then +x +z -y +y -x -z
ANGLES = "-90,180,-,90,0,-,-90,-,0,180,90,-"  # course signs: +x up is θ = -90°, +y up 180°


def test_marked_poses_are_set_aside_and_the_rest_keep_their_angles(tmp_path):
    path = write_six_face_log(tmp_path / "faces.csv")
    log = read_log(path, LogOptions(poses=tuple(float("nan") if a == "-" else float(a)
                                                for a in ANGLES.split(",")),
                                    angle_unit="deg"))
    assert log.provenance["poses_out_of_plane"] == [2, 5, 7, 11]
    assert log.pose.max() == 7  # the eight in-plane holds, renumbered in order
    assert set(np.round(np.degrees(log.theta)).astype(int)) == {-90, 0, 90, 180}
    # every kept sample reads its θ's course reference within the sensor's errors
    g = 9.80665
    ref = np.column_stack([-g * np.sin(log.theta), -g * np.cos(log.theta)])
    assert np.max(np.abs(log.acc - ref)) < 0.6


def test_the_cli_takes_the_marks_and_refuses_all_marks(capsys, tmp_path):
    path = write_six_face_log(tmp_path / "faces.csv")
    rc, out, err = run(capsys, "calibrate", path, "--poses", ANGLES, "--angle-unit", "deg",
                       "--json")
    assert rc == 0, err
    assert json.loads(out)["axes"]["x"]["n"] == 6010  # the 8 in-plane holds
    msg = one_line_error(capsys, "calibrate", path, "--poses=-,-,-", "--angle-unit", "deg")
    assert "every pose is marked '-'" in msg


@pytest.mark.parametrize("poses", ["-90,-,-,-,-,-,-,-,-,-,-,-"])
def test_one_pose_in_the_plane_is_refused(capsys, tmp_path, poses):
    path = write_six_face_log(tmp_path / "faces.csv")
    msg = one_line_error(capsys, "calibrate", path, "--poses", poses, "--angle-unit", "deg")
    assert "fewer than two poses in the tilt plane" in msg


def test_every_command_that_reads_a_log_says_how_it_read_it(capsys, tmp_path):
    """One note on stderr: the format, which column became what, the unit and its factor."""
    path = write_six_face_log(tmp_path / "faces.csv", unit="g")
    rc, out, err = run(capsys, "calibrate", path, "--json")
    assert rc == 0, err
    note = next(ln for ln in unwrap(err).splitlines() if ln.startswith("note: read "))
    assert "faces.csv as csv" in note and "x ← 'acc_x (g)'" in note
    assert "n ← 'acc_z (g)'" in note and "in g × 9.80665 → m/s²" in note
    json.loads(out)  # stdout stays one JSON object
