"""``tiltbench calibrate`` on measured logs: the log options, the lack-of-fit report, the
multi-position method (θ unknown) chosen automatically or given, and their refusals.

Logs with θ unknown are built in memory (:class:`calib.logs.reader.ImuLog`) and handed to the
command through ``calib.logs.reader.read_log`` (what ``--format`` readers return), so these tests do
not depend on any particular file reader.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import calib.logs.reader
from calib.calibration.calfile import load_calibration
from calib.conventions import G
from calib.logs.reader import ImuLog
from calib.units import missing_units
from tests.cli import one_line_error, run

TRUTH = np.array([0.08, -0.03, -0.02, 0.01])
SIGMA2 = np.array([0.25, 0.64])


def held_log(deg, n=300, seed=0, theta=False, k2=0.0, source="hand.csv"):
    """A log of poses held at ``deg`` (n samples each), course model and noise; θ kept
    (``theta=True``) or unknown; optional K2 term on x (an effect the model lacks)."""
    rng = np.random.default_rng(seed)
    th = np.repeat(np.radians(np.asarray(deg, float)), n)
    a_r = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    acc = TRUTH[[0, 2]] + (1 + TRUTH[[1, 3]]) * a_r
    acc = acc + rng.standard_normal(acc.shape) * np.sqrt(SIGMA2)
    acc[:, 0] += k2 * a_r[:, 0] ** 2
    return ImuLog(acc=acc, theta=th if theta else None,
                  pose=np.repeat(np.arange(len(deg)), n), source=source)


@pytest.fixture
def serve(monkeypatch):
    """``serve(log)``: every ``read_log`` returns ``log`` (whatever the path)."""
    def _serve(log: ImuLog) -> None:
        monkeypatch.setattr(calib.logs.reader, "read_log",
                            lambda path, options=None, expect=None: log)
    return _serve


def test_theta_unknown_chooses_multiposition_and_says_so(serve, capsys, tmp_path):
    serve(held_log([0, 60, 120, 180, 240, 300]))
    cal_path, png = tmp_path / "cal.json", tmp_path / "mp.png"
    src = tmp_path / "hand.csv"
    src.write_text("the log (its name and hash go into cal.json)\n")
    rc, out, err = run(capsys, "calibrate", src, "--noise-var", "0.25,0.64",
                       "--save", cal_path, "--plot", png)
    assert rc == 0, err
    assert "method: multiposition (automatic: θ unknown)" in out
    assert "6 poses" in out and "largest gap between pose directions" in out
    assert "compared with" not in out  # no θ: nothing to compare with
    cal = load_calibration(cal_path)
    assert cal.method == "multiposition"
    lo, hi = cal.params - 4 * cal.std, cal.params + 4 * cal.std
    assert np.all((lo <= TRUTH) & (TRUTH <= hi))
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_multiposition_json_carries_units_and_the_comparison(serve, capsys):
    """θ known and --method multiposition: both fits on the same readings; the difference
    in units of the combined std stays within 3 (|z| has sd < 1 under agreement)."""
    serve(held_log([0, 45, 90, 135, 180, 225, 270, 315], theta=True))
    rc, out, err = run(capsys, "calibrate", "run.mat", "--method", "multiposition", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert missing_units(d) == []
    assert d["chosen"] == "given" and d["method"] == "multiposition"
    assert d["fit"]["sigma2_source"] == "estimated"
    assert d["fit"]["sigma2_dof"] == 8 * 300 - 8
    assert np.all(np.abs(d["comparison"]["z"]) <= 3)


def test_four_poses_of_a_six_position_log(serve, capsys, tmp_path):
    """A 3-axis IMU's six-position log in the x–y plane: ±x and ±y poses on the circle,
    z-up / z-down reading ≈ 0 (left out with a warning). Four poses fit the ellipse exactly
    (dof 0), and the calibration file is still all finite numbers."""
    log = held_log([0, 90, 180, 270])
    rng = np.random.default_rng(1)
    acc = np.vstack([log.acc, rng.standard_normal((600, 2)) * np.sqrt(SIGMA2)])
    serve(ImuLog(acc=acc, pose=np.concatenate([log.pose, np.repeat([4, 5], 300)]),
                 source="six.csv"))
    src = tmp_path / "six.csv"
    src.write_text("the log\n")
    rc, out, err = run(capsys, "calibrate", src, "--save", tmp_path / "cal.json")
    assert rc == 0, err
    # lines may wrap at 100 columns (where depends on the path's length): compare the words
    words = " ".join(err.split())
    assert "poses 4, 5 left out" in words and "within the 4 poses" in words
    assert "dof = 0: 4 poses fit the ellipse exactly" in " ".join(out.split())
    text = (tmp_path / "cal.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    cal = load_calibration(tmp_path / "cal.json")
    assert np.all(np.abs(cal.params - TRUTH) <= 4 * cal.std)


def test_too_few_poses_is_one_line_naming_the_count(serve, capsys, tmp_path):
    serve(held_log([0, 120, 240]))
    save = tmp_path / "cal.json"
    msg = one_line_error(capsys, "calibrate", "hand.csv", "--save", save)
    assert "hand.csv: 3 held poses" in msg and "at least 4" in msg
    assert not save.exists()


def test_poses_that_do_not_turn_an_axis_name_its_scale(serve, capsys):
    serve(held_log([0, 180, 0.5, 180.5, 1, 181]))
    msg = one_line_error(capsys, "calibrate", "hand.csv", "--noise-var", "0.25,0.64",
                         ignore=("warning:",))
    assert "cannot identify scale_x" in msg


def test_least_squares_without_theta_points_to_multiposition(serve, capsys):
    serve(held_log([0, 90, 180, 270, 45]))
    msg = one_line_error(capsys, "calibrate", "hand.csv", "--method", "wls")
    assert "--method wls needs the table angle" in msg and "--method multiposition" in msg


def test_no_poses_and_no_theta_is_refused(serve, capsys):
    log = held_log([0, 90, 180, 270])
    serve(ImuLog(acc=log.acc, source="flat.csv"))
    msg = one_line_error(capsys, "calibrate", "flat.csv")
    assert "no held poses" in msg


def test_rrd_is_refused_with_multiposition(capsys, tmp_path):
    msg = one_line_error(capsys, "calibrate", "x.mat", "--method", "multiposition", "--rrd",
                         tmp_path / "f.rrd")
    assert "--rrd" in msg and "--plot" in msg


def test_lack_of_fit_is_one_line_when_the_model_misses(serve, capsys):
    """θ known, repeated poses, a K2 term on x: σ² from the pure error, the F test rejects on
    x and the command says so in one line pointing to ``tiltbench gap``."""
    serve(held_log(np.arange(0, 360, 45), n=400, theta=True, k2=0.01))
    rc, out, err = run(capsys, "calibrate", "run.mat")
    assert rc == 0, err
    warn = [ln for ln in err.splitlines() if ln.startswith("warning: axis")]
    assert len(warn) == 1 and warn[0].startswith(
        "warning: axis x: the model misses something (F = ")
    assert warn[0].endswith("); run `tiltbench gap`") and len(warn[0]) <= 100
    assert "pure error, dof 3192" in " ".join(err.split())  # the note may wrap
    assert "axis y: lack of fit F" in out  # reported for both axes
    rc, out, err = run(capsys, "calibrate", "run.mat", "--json")
    d = json.loads(out)
    assert missing_units(d) == [] and d["lack_of_fit"]["x"]["p_value"] < 0.01
    assert d["axes"]["x"]["sigma2_dof"] == 3192


def test_generated_positions_set_end_to_end(capsys, tmp_path, course_dir):
    """A bench set (8 held positions × 150, θ known) through the real reader: least squares
    with the lack-of-fit report, the multi-position fit agreeing with it, and its
    calibration file driving ``trajectory`` on the course vehicle run."""
    out = tmp_path / "set"
    rc, _, err = run(capsys, "generate", "calibration", "--positions", 8, "--per-position",
                     150, "--seed", 4, "--out", out)
    assert rc == 0, err
    rc, text, err = run(capsys, "calibrate", out / "ensayo.mat")
    assert rc == 0 and "axis x: lack of fit F" in text
    cal_path = tmp_path / "cal.json"
    rc, text, err = run(capsys, "calibrate", out / "ensayo.mat", "--method", "multiposition",
                        "--json", "--save", cal_path)
    assert rc == 0, err
    d = json.loads(text)
    assert np.all(np.abs(d["comparison"]["z"]) <= 3)
    rc, text, err = run(capsys, "trajectory", "--calibration", cal_path, "--acel",
                        course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat",
                        "--datos", course_dir / "datos.txt", "--json")
    assert rc == 0, err
    assert missing_units(json.loads(text)) == []


def test_course_file_is_unchanged(capsys, course_dir):
    """The course sweep (θ known, never repeated): the same output as the library's
    per-axis OLS, no lack-of-fit line, no method line."""
    from calib.calibration.tilt_plane import calibrate
    from calib.files.course import read_ensayo

    rc, out, err = run(capsys, "calibrate", course_dir / "ensayo.mat", "--noise-var",
                       "0.25,0.64")
    assert rc == 0 and "lack of fit" not in out + err and "method:" not in out
    cal = calibrate(read_ensayo(course_dir / "ensayo.mat"), [0.25, 0.64])
    assert out == f"{course_dir / 'ensayo.mat'}\n{cal.summary()}\n"
