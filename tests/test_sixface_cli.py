"""``tiltbench calibrate`` on a 3-axis log held on the faces of its case (the six-face test),
local gravity (``--latitude/--height``, ``--g``, or a stated assumption) and the unit g.

The log is written here from the physics (a rotated specific force read by three slightly
misaligned axes with bias and scale errors, moves between the holds, a bias that changes from
hold to hold), not by the bench: the CLI must find the holds, recognize the faces and recover
the geometry inside its stated intervals.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from calib.conventions import STANDARD_GRAVITY, normal_gravity
from tests.cli import one_line_error, run, unwrap

K_TRUE = np.array([[1.01, 0.004, -0.002], [0.001, 0.99, 0.003], [0.002, -0.001, 1.02]])
B_TRUE = np.array([0.1, -0.05, 0.2])
FACES = np.vstack([np.eye(3), -np.eye(3)])


def _path(p, u, n):
    if p @ u < -0.5:  # through a perpendicular direction: never through the zero vector
        mid = np.cross(p, [0.3, 0.5, 0.8])
        mid /= np.linalg.norm(mid)
        return _path(p, mid, n // 2) + _path(mid, u, n - n // 2)
    out = []
    for j in range(n):
        v = (1 - (j + 1) / n) * p + (j + 1) / n * u
        out.append(v / np.linalg.norm(v))
    return out


def write_six_face_log(path, g=STANDARD_GRAVITY, unit="m/s^2", seed=4, order=None):
    """A 100 Hz CSV: holds of 8 s on the faces in ``order`` joined by 2 s moves."""
    rng = np.random.default_rng(seed)
    order = [0, 1, 2, 3, 4, 5, 0, 2, 4, 1, 3, 5] if order is None else order
    rows, t, prev = [], 0.0, FACES[order[0]]
    for f in order:
        u = FACES[f]
        for v in _path(prev, u, 200):
            rows.append((t, *(B_TRUE + g * K_TRUE @ v + rng.normal(0, 0.5, 3))))
            t += 0.01
        bias_h = rng.normal(0, 0.01, 3)
        for _ in range(800):
            rows.append((t, *(B_TRUE + bias_h + g * K_TRUE @ u + rng.normal(0, 0.03, 3))))
            t += 0.01
        prev = u
    scale = 1.0 if unit == "m/s^2" else 1.0 / STANDARD_GRAVITY
    with open(path, "w") as fh:
        fh.write(f"time (s),acc_x ({unit}),acc_y ({unit}),acc_z ({unit})\n")
        for r in rows:
            fh.write(f"{r[0]:.2f}," + ",".join(f"{scale * x:.7f}" for x in r[1:]) + "\n")
    return path


@pytest.fixture(scope="module")
def six_face_csv(tmp_path_factory):
    return write_six_face_log(tmp_path_factory.mktemp("six") / "sixface.csv")


def _fit(capsys, *argv):
    rc, out, err = run(capsys, "calibrate", *argv, "--json")
    assert rc == 0, err
    return json.loads(out), err


def test_six_face_log_gives_three_axes_with_misalignment_inside_the_intervals(capsys,
                                                                              six_face_csv):
    doc, err = _fit(capsys, six_face_csv, "--g", STANDARD_GRAVITY)
    fit = doc["fit"]
    assert doc["method"] == "six-face" and len(fit["faces"]) == 12
    params, std = np.array(fit["params"]), np.sqrt(np.diag(fit["cov"]))
    truth = []
    for a in range(3):
        others = [j for j in range(3) if j != a]
        truth += [B_TRUE[a], K_TRUE[a, a] - 1, *(K_TRUE[a, j] / K_TRUE[a, a] for j in others)]
    z = (params - np.array(truth)) / std
    assert np.all(np.abs(z) < 4.0), dict(zip(fit["param_names"], np.round(z, 2), strict=True))
    # faces held twice: σ_B measured for both classes of every axis (axis vertical / level)
    assert all(v is not None for row in fit["sigma_between"] for v in row)
    assert all(max(row) > 0 for row in fit["sigma_between"])
    assert fit["g"] == STANDARD_GRAVITY and fit["g_source"] == "--g"
    assert "assumed" not in err


def test_latitude_and_height_set_the_wgs84_gravity(capsys, six_face_csv):
    doc, _ = _fit(capsys, six_face_csv, "--latitude", 55, "--height", 5000)
    assert abs(doc["fit"]["g"] - normal_gravity(55.0, 5000.0)) <= 1e-6
    assert abs(doc["fit"]["g"] - 9.7997) <= 5e-5  # MATLAB gravitywgs84(5000, 55, 'Taylor…')
    assert "WGS84" in doc["fit"]["g_source"] and "55" in doc["fit"]["g_source"]


def test_without_g_the_assumption_is_said(capsys, six_face_csv):
    doc, err = _fit(capsys, six_face_csv)
    assert doc["fit"]["g_source"] == "assumed"
    assert "g = 9.8 m/s² assumed" in unwrap(err) and "--latitude" in unwrap(err)


@pytest.mark.parametrize("argv, words", [
    (("--latitude", 45, "--g", 9.81), "--g and --latitude both"),
    (("--height", 100), "--height needs --latitude"),
    (("--latitude", 91), "expected degrees in [-90, 90]"),
])
def test_gravity_refusals_are_one_line(capsys, six_face_csv, tmp_path, argv, words):
    msg = one_line_error(capsys, "calibrate", six_face_csv, *argv, ignore=("note:",))
    assert words in msg


def test_a_log_in_g_is_converted_with_standard_gravity(capsys, tmp_path):
    """The same readings written in m/s² and in g (÷ 9.80665) give the same fit: the unit g is
    standard gravity, whatever the local gravity is."""
    si = write_six_face_log(tmp_path / "si.csv")
    in_g = write_six_face_log(tmp_path / "g.csv", unit="g")
    a, _ = _fit(capsys, si, "--latitude", 10)
    b, _ = _fit(capsys, in_g, "--latitude", 10)
    np.testing.assert_allclose(a["fit"]["params"], b["fit"]["params"], atol=2e-6)


def test_plot_writes_the_six_face_figure(capsys, six_face_csv, tmp_path):
    rc, out, err = run(capsys, "calibrate", six_face_csv, "--g", 9.81, "--plot",
                       tmp_path / "six.png")
    assert rc == 0, err
    assert (tmp_path / "six.png").stat().st_size > 10_000
    assert "intervals widened" in out and "misalignment_xy" in out
