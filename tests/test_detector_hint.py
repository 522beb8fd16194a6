"""When too few held poses are found, the refusal says how the pose detector looked (its
window and minimum hold) and what to try on a hand-held or high-rate log."""

from __future__ import annotations

from tests.cli import one_line_error
from tests.reference.real_data import REAL_DIR


def test_too_few_detected_holds_name_the_detector_options(capsys):
    msg = one_line_error(capsys, "calibrate", REAL_DIR / "ngimu-sensors.csv",
                         ignore=("note: ",))
    assert "the pose detector found 1 hold(s) with a window of 0.501 s" in msg
    assert "try --window 0.1 --min-hold 0.5 (seconds)" in msg


def test_labelled_poses_get_no_detector_hint(capsys, tmp_path):
    rows = [f"{k * 0.01:.2f},0.0,-9.8,0.0,{'a' if k < 300 else 'b'}" for k in range(600)]
    path = tmp_path / "two.csv"
    path.write_text("t (s),ax (m/s2),ay (m/s2),az (m/s2),label\n" + "\n".join(rows) + "\n")
    msg = one_line_error(capsys, "calibrate", path, "--columns", "label=label",
                         "--allow-saturation", ignore=("note: ",))
    assert "pose detector" not in msg
