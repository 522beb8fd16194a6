"""When too few held poses are found, the refusal says how the pose detector looked (its
window and minimum hold) and what to try on a hand-held or high-rate log."""

from __future__ import annotations

from tests.cli import one_line_error
from tests.reference.real_data import REAL_DIR


def test_too_few_detected_holds_name_the_detector_options(capsys):
    msg = one_line_error(capsys, "calibrate", REAL_DIR / "ngimu-sensors.csv",
                         ignore=("note: ",))
    assert "the pose detector found 1 hold(s) with a window of 0.501 s" in msg
    assert "try --static-window 0.1 --min-hold 0.5 (seconds)" in msg


def test_labelled_poses_get_no_detector_hint(capsys, tmp_path):
    rows = [f"{k * 0.01:.2f},0.0,-9.8,0.0,{'a' if k < 300 else 'b'}" for k in range(600)]
    path = tmp_path / "two.csv"
    path.write_text("t (s),ax (m/s2),ay (m/s2),az (m/s2),label\n" + "\n".join(rows) + "\n")
    msg = one_line_error(capsys, "calibrate", path, "--columns", "label=label",
                         "--allow-saturation", ignore=("note: ",))
    assert "pose detector" not in msg


def test_the_hinted_options_exist_and_are_taken(capsys):
    """The options the hint names are the command's own (a renamed option would leave the
    hint pointing at nothing): calibrate with them reads the log and refuses for poses, not
    for an unknown option."""
    msg = one_line_error(capsys, "calibrate", REAL_DIR / "ngimu-sensors.csv",
                         "--static-window", "0.1", "--min-hold", "0.5", ignore=("note: ",))
    assert "unrecognized" not in msg and "pose" in msg


def test_many_holds_get_no_shorter_window_hint():
    """With at least FEW_HOLDS holds found, detection is not what failed: no hint to shorten
    the window (a still phone log cut into thousands of holds by bursts got one)."""
    from dataclasses import replace

    from calib.logs.poses import FEW_HOLDS, PoseDetection
    from calib.logs.reader import read_log

    det = PoseDetection.from_dict(
        read_log(REAL_DIR / "ngimu-sensors.csv").provenance["poses"]["detection"])
    assert "try --static-window" in det.few_poses_hint(100.0)
    many = replace(det, segments=det.segments * FEW_HOLDS)
    hint = many.few_poses_hint(100.0)
    assert hint.startswith(f"the pose detector found {FEW_HOLDS} hold(s)") and "try" not in hint
