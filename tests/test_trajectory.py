"""Trajectory reconstruction: course answer, integration weights, exactness, the CLI."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from bench.cli import main
from calib.vehicle.trajectory import (
    INTEGRATORS,
    Trajectory,
    compute_trajectory,
    correct_and_integrate,
    double_integral_weights,
    integrate_twice,
    trapezoid_sum_w2_uniform,
    trapezoid_weights_uniform,
)
from tests.checks import assert_frozen_and_serialisable
from tests.reference import course_2009 as ref

EPS = np.finfo(float).eps

# Course answer for the trajectory (issue 3): final positions to the digits given.
COURSE_CORRECTED = (468.6, 42.1)
COURSE_RAW = (594.3, 9.25)
COURSE_TOL = 0.5  # m, as stated in the issue



def test_course_final_positions(course):
    _, acel, puntos, cal, _ = course
    traj = compute_trajectory(acel, cal)
    assert np.linalg.norm(traj.final_corrected - COURSE_CORRECTED) <= COURSE_TOL
    assert np.linalg.norm(traj.final_raw - COURSE_RAW) <= COURSE_TOL
    # the uncorrected run ends next to B (course reports: "la trayectoria sin corregir termina
    # en el punto B")
    d = {k: np.linalg.norm(traj.final_raw - p) for k, p in puntos.items()}
    assert min(d, key=d.get) == "B"


def test_course_simpson_differs_from_trapezoid_by_the_noise_it_weights_differently(course):
    """Both rules integrate the smooth profile almost exactly, but they weight the white
    noise differently (Simpson's 1-4-2-4 pattern): the difference of the final positions is
    Σ (w_S - w_T)_k v_k / k, normal with std σ ‖w_S - w_T‖ / (1 + s). Check it within 4σ
    (and that Simpson's noise variance Σ w² is the larger one)."""
    _, acel, _, cal, _ = course
    a = compute_trajectory(acel, cal, integrator="trapezoid").final_corrected
    b = compute_trajectory(acel, cal, integrator="simpson").final_corrected
    ws, wt = (double_integral_weights(acel.t, i) for i in ("simpson", "trapezoid"))
    std = np.sqrt(ref.NOISE_VAR) * np.linalg.norm(ws - wt) / (1 + cal.scale)
    assert np.all(np.abs(a - b) <= 4 * std)
    assert ws @ ws > wt @ wt


# --- weights of the double integral --------------------------------------------------------

def _brute_weights(t: np.ndarray, integrator: str) -> np.ndarray:
    """Final position for each unit impulse (linearity): column k = P_end(A = e_k)."""
    m = t.size
    eye = np.eye(m)
    w = np.empty(m)
    for k in range(m):
        a = np.column_stack([eye[k], np.zeros(m)])
        w[k] = integrate_twice(t, a, [0, 0], [0, 0], integrator)[0][-1, 0]
    return w


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("m", [3, 4, 11, 12])
def test_weights_equal_impulse_responses(integrator, m):
    rng = np.random.default_rng(m)
    for t in (np.arange(m) * 0.01, np.cumsum(rng.uniform(0.5, 1.5, m))):
        w = double_integral_weights(t, integrator)
        wb = _brute_weights(t, integrator)
        scale = (t[-1] - t[0]) ** 2
        np.testing.assert_allclose(w, wb, atol=50 * m * EPS * scale, rtol=0)
        assert w.sum() == pytest.approx((t[-1] - t[0]) ** 2 / 2, rel=50 * m * EPS)


def test_trapezoid_closed_form_weights_and_sum_of_squares():
    for m, h in ((3, 0.5), (10, 0.1), (6000, 0.01)):
        t = np.arange(m) * h
        w = trapezoid_weights_uniform(m, h)
        np.testing.assert_allclose(double_integral_weights(t), w, rtol=0,
                                   atol=50 * m * EPS * (m * h) ** 2)
        assert trapezoid_sum_w2_uniform(m, h) == pytest.approx(float(w @ w), rel=1e-12)
    # large-n limit h·T³/3 (integrated random walk)
    m, h = 6000, 0.01
    T = (m - 1) * h
    assert trapezoid_sum_w2_uniform(m, h) == pytest.approx(h * T**3 / 3, rel=2 / m)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_final_position_is_the_weighted_sum(integrator):
    rng = np.random.default_rng(5)
    t = np.arange(600) * 0.01
    a = rng.normal(size=(600, 2))
    pos, _ = integrate_twice(t, a, [1.0, -2.0], [0.5, 3.0], integrator)
    w = double_integral_weights(t, integrator)
    expect = np.array([1.0, -2.0]) + np.array([0.5, 3.0]) * t[-1] + w @ a
    np.testing.assert_allclose(pos[-1], expect, rtol=0, atol=1e-11)


# --- exactness ---------------------------------------------------------------------------------

def test_trapezoid_exact_for_constant_acceleration():
    t = np.arange(101) * 0.1
    a = np.tile([0.7, -1.3], (101, 1))
    pos, vel = integrate_twice(t, a, [2.0, 1.0], [1.0, 3.0])
    np.testing.assert_allclose(vel, [1.0, 3.0] + a * t[:, None], atol=1e-12)
    np.testing.assert_allclose(pos, [2.0, 1.0] + [1.0, 3.0] * t[:, None]
                               + 0.5 * a * t[:, None] ** 2, atol=1e-11)


def test_simpson_exact_for_linear_acceleration_trapezoid_is_not():
    """Simpson integrates quadratics exactly: a = c·t gives v = c t²/2, p = c t³/6 exactly;
    the trapezoid errs by O(h²)."""
    t = np.arange(201) * 0.05
    a = np.column_stack([0.3 * t, -0.2 * t])
    exact = np.column_stack([0.3 * t**3 / 6, -0.2 * t**3 / 6])
    ps, _ = integrate_twice(t, a, [0, 0], [0, 0], "simpson")
    pt, _ = integrate_twice(t, a, [0, 0], [0, 0], "trapezoid")
    np.testing.assert_allclose(ps, exact, atol=1e-10)
    assert np.max(np.abs(pt - exact)) > 1e-4


def test_correction_inverts_the_sensor_model():
    """Readings (1 + s)a + b corrected with (b, s) integrate to the true trajectory."""
    t = np.arange(1000) * 0.01
    a = np.column_stack([np.sin(t), np.cos(2 * t)])
    b, s = np.array([0.1, -0.05]), np.array([0.02, -0.03])
    traj = correct_and_integrate(t, (1 + s) * a + b, b, s, [0, 0], [1, 3])
    pos, _ = integrate_twice(t, a, [0, 0], [1, 3])
    np.testing.assert_allclose(traj.pos_corrected, pos, atol=1e-10)
    raw = correct_and_integrate(t, a, [0, 0], [0, 0], [0, 0], [1, 3])
    np.testing.assert_array_equal(raw.pos_raw, raw.pos_corrected)


def test_result_is_frozen_and_serialisable(course):
    _, acel, _, cal, _ = course
    traj = compute_trajectory(acel, cal)
    assert isinstance(traj, Trajectory)
    d = assert_frozen_and_serialisable(traj, "integrator", traj.pos_corrected)
    assert set(d) >= {"final_raw", "final_corrected", "final_velocity_corrected"}
    assert "final position, corrected" in traj.summary()


def test_bad_inputs_raise():
    t = np.arange(10) * 0.1
    with pytest.raises(ValueError, match="integrator"):
        integrate_twice(t, np.zeros((10, 2)), [0, 0], [0, 0], "euler")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="accelerations"):
        correct_and_integrate(t, np.zeros((9, 2)), [0, 0], [0, 0])


def test_calib_never_imports_bench_or_mujoco():
    code = ("import sys, calib.vehicle.trajectory, calib.vehicle.region, calib.vehicle.nmin; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('bench', 'mujoco')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


# --- the command line --------------------------------------------------------------------------

def _files(course_dir):
    return ["--ensayo", str(course_dir / "ensayo.mat"), "--acel", str(course_dir / "acel.mat"),
            "--puntos", str(course_dir / "puntos.mat")]


def test_cli_json_is_one_object_with_documented_keys(course_dir, capsys):
    assert main(["trajectory", *_files(course_dir), "--datos", str(course_dir / "datos.txt"),
                 "--json"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    for key in ("final_raw", "final_corrected", "final_velocity_corrected", "cov", "ellipse",
                "candidates", "decision", "course_box_bound"):
        assert key in out
    assert set(out["ellipse"]) >= {"level", "semi_axes", "angle_rad"}
    assert set(out["candidates"]) == {"A", "B", "C", "D"}
    assert set(out["candidates"]["C"]) >= {"pos", "mahalanobis", "likelihood"}
    assert out["decision"] == "C"
    assert np.linalg.norm(np.array(out["final_corrected"]) - COURSE_CORRECTED) <= COURSE_TOL
    assert np.array(out["cov"]).shape == (2, 2)
    assert cap.err == ""


def test_cli_without_datos_notes_estimated_noise(course_dir, capsys):
    assert main(["trajectory", *_files(course_dir), "--json", "--level", "0.95"]) == 0
    cap = capsys.readouterr()
    assert "estimated" in cap.err and "V0" in cap.err
    out = json.loads(cap.out)
    assert out["noise_var_source"] == "estimated" and out["decision"] == "C"


def test_cli_table_and_plots(course_dir, tmp_path, capsys):
    png, svg = tmp_path / "t.png", tmp_path / "t.svg"
    assert main(["trajectory", *_files(course_dir), "--plot", str(png)]) == 0
    assert "decision: C" in capsys.readouterr().out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["trajectory", *_files(course_dir), "--plot", str(svg)]) == 0
    assert b"<svg" in svg.read_bytes()[:2000]
    assert main(["trajectory", *_files(course_dir), "--plot", str(png)]) == 2  # no --force
    assert main(["trajectory", *_files(course_dir), "--plot", str(tmp_path / "t.jpg")]) == 2


def test_cli_errors_name_the_file(course_dir, tmp_path, capsys):
    args = _files(course_dir)
    args[3] = str(tmp_path / "missing.mat")
    assert main(["trajectory", *args]) == 2
    assert "missing.mat" in capsys.readouterr().err
    assert main(["trajectory", *_files(course_dir), "--level", "99.7"]) == 2
    assert "--level" in capsys.readouterr().err
