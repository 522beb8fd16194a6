"""A label column is checked for stillness before its labels are trusted as held poses: a
rotation labelled as a pose is refused in one line naming the label (the imucal-style
annotated session labels its turns ``x_rot`` …)."""

from __future__ import annotations

import numpy as np
import pytest

from calib.input_rules import DataError
from calib.logs.reader import LABEL_STILL_RATIO, LogOptions, read_log
from tests.cli import one_line_error

G_UNIT = 9.80665


def _write(path, blocks, rng):
    """blocks: (label, (n, 3) specific force in m/s²) in order; noise 0.02 m/s²."""
    rows, t = [], 0.0
    for label, acc in blocks:
        for a in acc + rng.normal(0, 0.02, acc.shape):
            rows.append(f"{t:.3f},{a[0]:.5f},{a[1]:.5f},{a[2]:.5f},{label}")
            t += 0.01
    path.write_text("t (s),ax (m/s2),ay (m/s2),az (m/s2),label\n" + "\n".join(rows) + "\n")
    return path


def _hold(u, n=300):
    return np.tile(G_UNIT * np.asarray(u, float), (n, 1))


def _turn(n=300):
    a = np.linspace(0, np.pi, n)
    return G_UNIT * np.column_stack([np.sin(a), np.zeros(n), np.cos(a)])


def test_a_labelled_turn_is_refused_naming_the_label(tmp_path, capsys):
    rng = np.random.default_rng(1)
    path = _write(tmp_path / "annotated.csv", [("z_p", _hold((0, 0, 1))), ("x_rot", _turn()),
                                              ("z_a", _hold((0, 0, -1))),
                                              ("x_p", _hold((1, 0, 0)))], rng)
    with pytest.raises(DataError, match=r"label 'x_rot' is not held still"):
        read_log(path, LogOptions(columns={"label": "label"}))
    msg = one_line_error(capsys, "calibrate", path, "--columns", "label=label")
    assert "'x_rot'" in msg and "moving rows" in msg


def test_still_labels_and_moving_marks_pass(tmp_path):
    """Holds that differ in noise within the detector's allowance pass; a turn marked moving
    (-1) is not a label."""
    rng = np.random.default_rng(2)
    noisy = _hold((1, 0, 0)) + rng.normal(0, 0.02 * np.sqrt(LABEL_STILL_RATIO / 4), (300, 3))
    path = _write(tmp_path / "ok.csv", [("a", _hold((0, 0, 1))), ("-1", _turn()),
                                        ("b", noisy), ("c", _hold((0, -1, 0)))], rng)
    log = read_log(path, LogOptions(columns={"label": "label"}))
    assert log.pose.max() == 2 and np.sum(log.pose == -1) == 300
