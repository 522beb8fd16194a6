"""Input domain of θ: any finite angle in radians is valid; degrees are told from the readings
(:mod:`calib.files.angles`), never from a range of θ.

Every file here is made from the course equations with numpy, not by the bench:
``A_rx = -g sin θ``, ``A_ry = -g cos θ``, ``datos = bias + (1 + scale)·A_r + v``,
``v ~ N(0, σ²)``, g = 9.8 m/s², bias (0.08, -0.02) m/s², scale (-0.03, 0.01), σ² = (0.25, 0.64)
(m/s²)² (the course noise), ``np.random.default_rng(SEED)`` per file. Commands run in process
through ``bench.cli.main`` as in ``tests/test_cli_audit.py``.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import scipy.io
from hypothesis import given, settings
from hypothesis import strategies as st

from calib.calibration.tilt_plane import calibrate
from calib.files.angles import compare_angle_units
from calib.files.course import DataError, read_ensayo
from tests.cli import run as _run
from tests.cli import unwrap

G = 9.8
BIAS = np.array([0.08, -0.02])
SCALE = np.array([-0.03, 0.01])
NOISE_VAR = np.array([0.25, 0.64])
SEED = 20240610
TWO_PI = 2.0 * np.pi


def readings(theta_rad: np.ndarray, seed: int = SEED, noise: float = 1.0) -> np.ndarray:
    """(N, 2) m/s²: the course sensor model at the true angles ``theta_rad`` (rad)."""
    rng = np.random.default_rng(seed)
    ref = np.column_stack([-G * np.sin(theta_rad), -G * np.cos(theta_rad)])
    return BIAS + (1.0 + SCALE) * ref + noise * rng.standard_normal(ref.shape) * np.sqrt(NOISE_VAR)


def _u(n: int = 400) -> np.ndarray:
    return np.linspace(0.0, 1.0, n)


RADIAN_SHAPES = {
    "overshoot_6.2841": np.linspace(0.0, 6.2841, 400),
    "two_turns_0_4pi": np.linspace(0.0, 4 * np.pi, 400),
    "oscillating_0_2pi": np.pi - np.pi * np.cos(TWO_PI * 3 * _u()),  # 0 → 2π → 0, three times
    "oscillating_about_0": 1.2 * np.sin(TWO_PI * 4 * _u()),
    "negative": np.linspace(-TWO_PI, 0.0, 400),
    "past_full_turn_2pi+0.3": np.linspace(0.0, TWO_PI + 0.3, 400),
    "many_turns_0_40pi": np.linspace(0.0, 40 * np.pi, 2000),
    "held_positions_two_turns": np.repeat(np.linspace(-np.pi, 3 * np.pi, 12, endpoint=False), 30),
}
"""Valid radian runs (rad): each must be read and every command must run on it."""

DEGREE_FILES = {
    "sweep_0_360deg": np.linspace(0.0, 360.0, 400),
    "held_positions_deg": np.repeat(np.arange(0.0, 360.0, 45.0), 25),
    "four_samples_deg": np.array([0.0, 90.0, 180.0, 270.0]),
    "small_range_0_30deg": np.linspace(0.0, 30.0, 2000),
    "negative_sweep_deg": np.linspace(-180.0, 90.0, 400),
}
"""θ stored in degrees by mistake (the readings follow the true angle, θ·π/180)."""


def _save(path, tita, datos, **extra):
    scipy.io.savemat(path, {"tita": np.asarray(tita, float)[:, None], "datos": datos, **extra})
    return path


@pytest.fixture
def course_like(tmp_path):
    """acel.mat (still vehicle), puntos.mat (four candidates), datos.txt in the course wording."""
    t = np.arange(300) * 0.01
    acel = tmp_path / "acel.mat"
    scipy.io.savemat(acel, {"t": t[:, None], "Aerr": np.tile(BIAS, (t.size, 1))})
    puntos = tmp_path / "puntos.mat"
    scipy.io.savemat(puntos, {"A": np.array([[3.0, 9.0]]), "B": np.array([[50.0, 50.0]]),
                              "C": np.array([[-50.0, 50.0]]), "D": np.array([[3.0, -60.0]])})
    datos = tmp_path / "datos.txt"
    datos.write_text("Posición inicial = [0 0]\nVelocidad inicial = [1 3]\n"
                     "varianza del ruido de los acelerómetros = [0.25 0.64]\n", encoding="utf-8")
    return acel, puntos, datos


def _commands(path, acel, puntos, datos) -> dict[str, list[str]]:
    """Every command that reads ``tita`` (a quick variant of each), ``--json``."""
    course = ["--ensayo", path, "--acel", acel, "--puntos", puntos, "--datos", datos, "--json"]
    return {
        "calibrate": ["calibrate", path, "--noise-var", "0.25,0.64", "--json"],
        "trajectory": ["trajectory", *course],
        "nmin": ["nmin", *course, "--steps", "1,4", "--mc-n", "3", "--runs", "0"],
        "gap": ["gap", path, "--noise-var", "0.25,0.64", "--json"],
    }


# ------------------------------------------------------------------ radians: all accepted
@pytest.mark.parametrize("shape", RADIAN_SHAPES)
def test_reader_accepts_any_finite_radians(shape, tmp_path):
    theta = RADIAN_SHAPES[shape]
    path = _save(tmp_path / f"{shape}.mat", theta, readings(theta))
    e = read_ensayo(path)
    np.testing.assert_array_equal(e.tita, theta)  # as stored: no wrapping, no rescaling
    units = compare_angle_units(e.tita, e.datos)
    assert not units.looks_like_degrees
    assert units.rss_ratio < 1  # the radian reading fits better
    cal = calibrate(e, NOISE_VAR)
    # the nominal model fits the run as given: estimates within 5 std of the truth
    std = np.sqrt(np.diag(cal.cov))  # [bias_x, scale_x, bias_y, scale_y]
    assert np.all(np.abs(cal.scale - SCALE) <= 5 * std[[1, 3]]), cal.scale
    assert np.all(np.abs(cal.bias - BIAS) <= 5 * std[[0, 2]]), cal.bias


@pytest.mark.parametrize("shape", RADIAN_SHAPES)
def test_every_command_runs_on_any_finite_radians(shape, tmp_path, capsys, course_like):
    theta = RADIAN_SHAPES[shape]
    path = _save(tmp_path / f"{shape}.mat", theta, readings(theta))
    for name, argv in _commands(path, *course_like).items():
        rc, out, err = _run(capsys, *argv)
        assert rc == 0, (name, err)
        doc = json.loads(out)
        if name == "calibrate":
            scale = [doc["axes"][a]["scale"] for a in "xy"]
            std = [doc["axes"][a]["scale_std"] for a in "xy"]
            assert np.all(np.abs(np.array(scale) - SCALE) <= 5 * np.array(std)), scale


def test_generate_takes_any_finite_radians(tmp_path, capsys):
    """Without readings there is nothing to tell degrees by: any finite value is radians."""
    values = [6.2841, -1.0, 7.0, 20.0, 0.5, -12.6, 4 * np.pi + 0.3]
    out = tmp_path / "list"
    rc, _, err = _run(capsys, *["generate", "calibration", "--theta-list",
                               ",".join(repr(v) for v in values), "--out", out])
    assert rc == 0, err
    np.testing.assert_allclose(read_ensayo(out / "ensayo.mat").tita, values, rtol=0, atol=1e-9)
    out = tmp_path / "range"
    rc, _, err = _run(capsys, *["generate", "calibration", "--theta-range", f"-3,{4 * np.pi!r}",
                               "--count", "120", "--out", out])
    assert rc == 0, err
    tita = read_ensayo(out / "ensayo.mat").tita
    assert tita.min() == pytest.approx(-3.0) and tita.max() == pytest.approx(4 * np.pi)
    rc, _, err = _run(capsys, *["calibrate", out / "ensayo.mat", "--noise-var", "0.25,0.64"])
    assert rc == 0, err


# ------------------------------------------------------------------ degrees: refused
@pytest.mark.parametrize("name", DEGREE_FILES)
def test_reader_refuses_degrees(name, tmp_path):
    deg = DEGREE_FILES[name]
    path = _save(tmp_path / f"{name}.mat", deg, readings(np.deg2rad(deg)))
    with pytest.raises(DataError) as info:
        read_ensayo(path)
    msg = str(info.value)
    assert isinstance(info.value, ValueError)
    assert str(path) in msg and "'tita'" in msg and "degrees" in msg and "radians" in msg
    assert "θ·π/180" in msg
    # both residual sums of squares, with units, radian reading first
    rss = [float(v) for v in re.findall(r"([-+0-9.e]+) \(m/s²\)²", msg)]
    units = compare_angle_units(deg, readings(np.deg2rad(deg)))
    assert rss == pytest.approx([units.rss_rad_total, units.rss_deg_total], rel=1e-3)
    assert rss[0] > rss[1]
    # the same numbers converted to radians are a valid run
    _save(path, np.deg2rad(deg), readings(np.deg2rad(deg)))
    assert read_ensayo(path).n == deg.size


@pytest.mark.parametrize("command", ["calibrate", "trajectory", "nmin", "gap"])
def test_every_command_refuses_degrees(command, tmp_path, capsys, course_like):
    deg = DEGREE_FILES["sweep_0_360deg"]
    path = _save(tmp_path / "deg.mat", deg, readings(np.deg2rad(deg)))
    rc, out, err = _run(capsys, *_commands(path, *course_like)[command])
    assert rc == 2 and out == ""
    lines = unwrap(err).splitlines()
    assert len(lines) == 1, err
    assert "deg.mat" in lines[0] and "'tita'" in lines[0] and "degrees" in lines[0]


def test_small_degree_range_is_refused_at_course_noise_over_seeds():
    """0 → 30° at the course noise: the RSS ratio is only ≈ 3 but the evidence is decisive."""
    deg = DEGREE_FILES["small_range_0_30deg"]
    for seed in range(5):
        units = compare_angle_units(deg, readings(np.deg2rad(deg), seed=SEED + seed))
        assert units.rss_ratio < 10 < units.log_lr  # caught by evidence, not by magnitude
        assert units.looks_like_degrees, units.summary()


# ------------------------------------------------------------------ edge cases
def test_undecidable_designs_are_read_as_radians(tmp_path):
    """Two poses: both readings fit the pose means exactly; a tiny range: both readings
    are the same line/parabola in θ. Nothing says degrees: accept. (One pose is refused, but
    for having one distinct θ — no calibration possible — never as degrees.)"""
    one = np.full(60, 40.0)
    path = _save(tmp_path / "one.mat", one, readings(one, noise=1.0))
    with pytest.raises(ValueError, match="only 1 distinct θ") as info:
        read_ensayo(path)
    assert "degrees, not radians" not in str(info.value)
    two = np.repeat([0.0, 90.0], 30)  # would be degrees, but two poses cannot tell
    tiny = np.linspace(0.3, 0.31, 400)
    for label, theta, noise in [("two", two, 1.0), ("two0", two, 0.0),
                                ("tiny", tiny, 1.0), ("tiny0", tiny, 0.0)]:
        path = _save(tmp_path / f"{label}.mat", theta, readings(np.deg2rad(theta) if
                                                                label.startswith("two")
                                                                else theta, noise=noise))
        assert read_ensayo(path).n == theta.size, label


def test_noiseless_files():
    """Exact readings: the radian run is accepted, even a 0 → 2° degree file is refused."""
    th = np.linspace(0.0, 4 * np.pi, 200)
    assert not compare_angle_units(th, readings(th, noise=0.0)).looks_like_degrees
    deg = np.linspace(0.0, 2.0, 200)
    assert compare_angle_units(deg, readings(np.deg2rad(deg), noise=0.0)).looks_like_degrees


def test_readings_unrelated_to_theta_are_not_called_degrees():
    rng = np.random.default_rng(SEED)
    deg = np.linspace(0.0, 360.0, 400)
    assert not compare_angle_units(deg, rng.standard_normal((400, 2))).looks_like_degrees
    assert not compare_angle_units(deg, np.zeros((400, 2))).looks_like_degrees


def test_nan_and_inf_still_refused(tmp_path):
    theta = np.linspace(0.0, 4 * np.pi, 100)
    for bad in (np.nan, np.inf, -np.inf):
        t = theta.copy()
        t[7] = bad
        path = _save(tmp_path / "bad.mat", t, readings(theta))
        with pytest.raises(DataError, match=r"'tita' has 1 NaN/Inf value\(s\), first at index"):
            read_ensayo(path)


def test_course_file_is_radians(course_dir):
    e = read_ensayo(course_dir / "ensayo.mat")
    units = compare_angle_units(e.tita, e.datos)
    assert not units.looks_like_degrees
    assert units.rss_ratio < 0.1 and units.log_lr < -1000


@settings(derandomize=True, max_examples=60, deadline=None)
@given(offset=st.floats(-60.0, 60.0), span=st.floats(1e-3, 150.0),
       n=st.integers(3, 300), kind=st.sampled_from(["sweep", "random", "held"]),
       noise=st.floats(0.0, 3.0), seed=st.integers(0, 2**31))
def test_radian_runs_are_never_called_degrees(offset, span, n, kind, noise, seed):
    """Whatever the offset, span (up to ~24 turns), sample count and noise level (0 to 3× the
    course σ), readings that follow θ in radians are never refused."""
    rng = np.random.default_rng(seed)
    if kind == "sweep":
        th = offset + np.linspace(0.0, span, n)
    elif kind == "random":
        th = offset + np.sort(rng.uniform(0.0, span, n))
    else:
        th = offset + np.repeat(np.linspace(0.0, span, max(1, n // 3)), 3)
    assert not compare_angle_units(th, readings(th, seed=seed, noise=noise)).looks_like_degrees
