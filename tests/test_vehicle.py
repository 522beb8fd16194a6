"""The MuJoCo vehicle and the vehicle / course-set generators."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest
import scipy.io

import bench.model as elements
from bench.cli import main
from bench.course import (
    COURSE_FILES,
    CourseConfig,
    generate_course,
    make_course_set,
    place_candidates,
)
from bench.sensors import SensorErrorModel
from bench.tilt import ThetaDesign
from bench.vehicle import (
    COURSE_PROFILE,
    Segment,
    VehicleConfig,
    generate_vehicle,
    make_vehicle_run,
    simulate_vehicle,
    vehicle_model,
)
from calib.files.course import read_acel, read_datos, read_ensayo, read_puntos
from calib.vehicle.trajectory import integrate_twice

EPS = np.finfo(float).eps
SMALL_THETA = ThetaDesign(count=501)  # calibration size does not matter for these checks


def _exact_piecewise(config: VehicleConfig) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form position/velocity at the sample times for the piecewise-constant profile,
    segment by segment: ``v = v_j + a_j τ``, ``p = p_j + v_j τ + a_j τ²/2``."""
    t = config.t
    p = np.empty((t.size, 2))
    v = np.empty((t.size, 2))
    p_j, v_j, t_j = np.array(config.p0, float), np.array(config.v0, float), 0.0
    edges = []
    for seg in config.profile:
        edges.append((t_j, t_j + seg.duration, np.array(seg.accel, float)))
        t_j += seg.duration
    edges.append((t_j, np.inf, np.zeros(2)))
    for start, stop, a in edges:
        sel = (t >= start - 1e-9) & (t < stop - 1e-9)
        tau = (t[sel] - start)[:, None]
        p[sel] = p_j + v_j * tau + 0.5 * a * tau**2
        v[sel] = v_j + a * tau
        if np.isfinite(stop):
            d = stop - start
            p_j, v_j = p_j + v_j * d + 0.5 * a * d * d, v_j + a * d
    return p, v


# --- the model -----------------------------------------------------------------------------

def test_model_compiles_all_elements_named_and_no_mjcf_noise():
    model, _ = vehicle_model()
    for kind, n in (("body", model.nbody), ("joint", model.njnt), ("geom", model.ngeom),
                    ("site", model.nsite), ("actuator", model.nu), ("sensor", model.nsensor)):
        for i in range(1 if kind == "body" else 0, n):  # body 0 is the world
            assert getattr(model, kind)(i).name, f"unnamed {kind} {i}"
    for name in (*elements.VEHICLE_SLIDE_JOINTS.values(),):
        assert model.joint(name).id >= 0
    for names, getter in ((elements.VEHICLE_DRIVES, model.actuator),
                          (elements.VEHICLE_ACC_SITES, model.site),
                          (elements.VEHICLE_ACC_SENSORS, model.sensor)):
        for name in names.values():
            assert getter(name).id >= 0
    assert model.body(elements.VEHICLE_BODY).id >= 0
    assert np.all(model.sensor_noise == 0)
    assert "noise=" not in elements.VEHICLE_XML.read_text()


def test_sites_read_world_x_and_y_as_their_local_x():
    """A static push along +x shows on the x sensor's local x only; +y on the y sensor's."""
    model, _ = vehicle_model()
    data = mujoco.MjData(model)
    m = float(model.body_subtreemass[model.body(elements.VEHICLE_BODY).id])
    data.ctrl[model.actuator(elements.VEHICLE_DRIVES["x"]).id] = 2.0 * m
    data.ctrl[model.actuator(elements.VEHICLE_DRIVES["y"]).id] = -3.0 * m
    mujoco.mj_forward(model, data)
    ax = data.sensor(elements.VEHICLE_ACC_SENSORS["x"]).data
    ay = data.sensor(elements.VEHICLE_ACC_SENSORS["y"]).data
    assert ax[0] == pytest.approx(2.0, abs=1e-12) and ay[0] == pytest.approx(-3.0, abs=1e-12)
    assert ax[2] == pytest.approx(9.8, abs=1e-12)  # gravity only on the vertical axis


# --- the simulated run -----------------------------------------------------------------------

def test_mujoco_state_matches_double_integral_of_commanded_profile():
    """RK4 with a force constant over each step integrates a constant acceleration exactly,
    so MuJoCo's state equals the closed-form double integral up to rounding: the tolerance is
    the accumulated rounding of M steps, 4 RK4 stages each, on |p| ≤ max|p|."""
    cfg = VehicleConfig()
    truth = simulate_vehicle(cfg)
    p, v = _exact_piecewise(cfg)
    m = cfg.n_samples
    assert truth.t.shape == (m,) and truth.t[-1] == pytest.approx(59.99, abs=1e-12)
    tol_p = 8 * m * EPS * np.max(np.abs(p))
    tol_v = 8 * m * EPS * np.max(np.abs(v))
    assert np.max(np.abs(truth.pos - p)) <= tol_p
    assert np.max(np.abs(truth.vel - v)) <= tol_v


def test_trapezoid_of_true_samples_differs_by_the_derived_zoh_term():
    """The course integrates samples with the trapezoid; MuJoCo's acceleration is held over
    each step. Exactly: v_trap[k] - v[k] = h/2 (a_k - a_0), and the position (trapezoid of v is
    exact for a piecewise-linear v) is off by h · trapz(h/2 (a - a_0))."""
    cfg = VehicleConfig()
    truth = simulate_vehicle(cfg)
    h = 1.0 / cfg.rate
    pos, vel = integrate_twice(truth.t, truth.acc, cfg.p0, cfg.v0)
    e_v = h / 2 * (truth.acc - truth.acc[0])
    e_p = h * (e_v[1:-1].sum(axis=0) + 0.5 * (e_v[0] + e_v[-1]))
    tol = 8 * cfg.n_samples * EPS * np.max(np.abs(truth.pos))
    np.testing.assert_allclose(vel - truth.vel, e_v, atol=tol, rtol=0)
    np.testing.assert_allclose(pos[-1] - truth.pos[-1], e_p, atol=tol, rtol=0)


def test_zero_error_readings_equal_true_acceleration():
    cfg = VehicleConfig(sensor=SensorErrorModel())
    run = make_vehicle_run(cfg, seed=3)
    np.testing.assert_array_equal(run.aerr, run.truth.acc)
    # the accelerometer is MuJoCo's acceleration: the command, and the velocity increments
    np.testing.assert_allclose(run.truth.acc, run.truth.acc_cmd, atol=1e-12, rtol=0)
    dv = np.diff(run.truth.vel, axis=0) * cfg.rate
    np.testing.assert_allclose(dv, run.truth.acc[:-1], atol=1e-9, rtol=0)


def test_sensor_errors_follow_the_course_model():
    """A_m - [(1 + s) A_r + b] is white noise with the configured variance (4σ bands)."""
    sensor = SensorErrorModel.from_pairs((0.3, -0.2), (0.05, -0.04), (0.25, 0.64))
    run = make_vehicle_run(VehicleConfig(sensor=sensor), seed=1)
    v = run.aerr - ((1 + np.array([0.05, -0.04])) * run.truth.acc + [0.3, -0.2])
    m = v.shape[0]
    var = np.array([0.25, 0.64])
    assert np.all(np.abs(v.mean(axis=0)) <= 4 * np.sqrt(var / m))
    assert np.all(np.abs(v.var(axis=0) / var - 1) <= 4 * np.sqrt(2 / m))


def test_segment_off_the_sample_grid_is_rejected():
    with pytest.raises(ValueError, match="whole number of samples"):
        VehicleConfig(profile=(Segment(10.005, (1.0, 0.0)),)).command()


# --- files and seeds -------------------------------------------------------------------------

def test_vehicle_same_seed_same_bytes(tmp_path):
    for d in ("a", "b"):
        generate_vehicle(tmp_path / d, seed=7)
    generate_vehicle(tmp_path / "c", seed=8)
    for name in ("acel.mat", "datos.txt", "truth.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert (tmp_path / "a/acel.mat").read_bytes() != (tmp_path / "c/acel.mat").read_bytes()
    acel = read_acel(tmp_path / "a" / "acel.mat")
    assert acel.t.shape == (6000,) and acel.t[-1] == pytest.approx(59.99)
    d = read_datos(tmp_path / "a" / "datos.txt")
    np.testing.assert_array_equal(d.p0, [0, 0])
    np.testing.assert_array_equal(d.v0, [1, 3])
    np.testing.assert_array_equal(d.noise_var, [0.25, 0.64])
    with pytest.raises(FileExistsError):
        generate_vehicle(tmp_path / "a", seed=7)


def test_generate_vehicle_cli(tmp_path, capsys):
    args = ["generate", "vehicle", "--seed", "2", "--profile", "10:1,0;10:0,-1",
            "--duration", "20"]
    assert main([*args, "--out", str(tmp_path / "a"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    truth = json.loads((tmp_path / "a" / "truth.json").read_text())
    # closed form at t = 19.99 s (τ = 9.99 s into the second segment, V0 = (1, 3)):
    # x = (10 + 50) + 11 τ,  y = 30 + 3 τ - τ²/2
    tau = 9.99
    expect = [60 + 11 * tau, 30 + 3 * tau - tau**2 / 2]
    np.testing.assert_allclose(out["final_position"], expect, rtol=0, atol=1e-9)
    np.testing.assert_allclose(truth["trajectory"]["final_position"], expect, rtol=0, atol=1e-9)
    assert truth["seed"] == 2 and truth["kind"] == "vehicle"
    assert main([*args, "--out", str(tmp_path / "a")]) == 2  # exists, no --force


COURSE_CFG = CourseConfig(theta=SMALL_THETA)


def test_course_set_same_seed_same_bytes_and_layout(tmp_path):
    for d in ("a", "b"):
        generate_course(tmp_path / d, seed=11, config=COURSE_CFG)
    generate_course(tmp_path / "c", seed=12, config=COURSE_CFG)
    for name in COURSE_FILES:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
        if name != "datos.txt":  # P0, V0 and σ² are the course's for every seed
            assert (tmp_path / "a" / name).read_bytes() != (tmp_path / "c" / name).read_bytes()
    a = tmp_path / "a"
    e = read_ensayo(a / "ensayo.mat")
    assert e.n == 501
    acel = scipy.io.loadmat(a / "acel.mat")
    assert acel["t"].shape == (6000, 1) and acel["Aerr"].shape == (6000, 2)
    pts = scipy.io.loadmat(a / "puntos.mat")
    assert sorted(k for k in pts if not k.startswith("__")) == ["A", "B", "C", "D"]
    assert all(pts[k].shape == (1, 2) for k in "ABCD")
    assert read_datos(a / "datos.txt").noise_var.tolist() == [0.25, 0.64]
    truth = json.loads((a / "truth.json").read_text())
    cands = read_puntos(a / "puntos.mat")
    np.testing.assert_array_equal(cands[truth["answer"]], truth["true_final_position"])
    for name in COURSE_FILES[:-1]:  # the answer never leaks into the student's files
        assert b"answer" not in (a / name).read_bytes()


@pytest.mark.parametrize("seed", range(6))
def test_course_candidates_truth_one_decoy_near_raw_end_separated(seed):
    c = make_course_set(COURSE_CFG, seed)
    truth = c.vehicle.truth.final_position
    raw = c.vehicle.raw_final_position()
    pts = np.array([c.candidates[k] for k in "ABCD"])
    exact = [k for k in "ABCD" if np.array_equal(c.candidates[k], truth)]
    assert exact == [c.answer]
    dist = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    assert np.min(dist[np.triu_indices(4, 1)]) >= COURSE_CFG.min_separation
    near = c.candidates[c.raw_decoy]
    if np.linalg.norm(raw - truth) >= COURSE_CFG.min_separation + COURSE_CFG.raw_jitter:
        assert np.linalg.norm(near - raw) <= COURSE_CFG.raw_jitter
    # the vehicle and the calibration carry the same sensor
    assert c.calibration.config.sensor == c.vehicle.config.sensor == c.sensor


def test_answer_letter_is_drawn_from_the_seed():
    """Over 40 seeds every letter appears (P(a letter never drawn) ≤ 4·(3/4)^40 ≈ 4e-5)."""
    rng_letters = set()
    for seed in range(40):
        ss = np.random.SeedSequence(seed).spawn(3)[2]
        _, answer, _ = place_candidates([0, 0], [300, 0], np.random.default_rng(ss))
        rng_letters.add(answer)
    assert rng_letters == {"A", "B", "C", "D"}


def test_truth_is_not_the_geometric_centre_of_the_decoys():
    """The truth must not be identifiable from geometry alone. Among the candidates other than
    the raw-end decoy (k - 1 = 3 points), pick the one closest to the others' centroid: if
    the truth is exchangeable with the decoys this picks it with probability 1/3. R = 600
    placements: |rate - 1/3| <= 4 sqrt((1/3)(2/3)/R) = 0.077."""
    R = 600
    hits = 0
    for ss in np.random.SeedSequence(99).spawn(R):
        cands, answer, raw_letter = place_candidates([0, 0], [400, 0], np.random.default_rng(ss))
        names = [n for n in cands if n != raw_letter]
        pts = np.array([cands[n] for n in names])
        score = [np.linalg.norm(pts[i] - np.delete(pts, i, 0).mean(0)) for i in range(len(pts))]
        hits += names[int(np.argmin(score))] == answer
    assert abs(hits / R - 1 / 3) <= 4 * np.sqrt((1 / 3) * (2 / 3) / R)


def test_course_profile_is_the_default_for_vehicle_runs():
    assert VehicleConfig().profile == COURSE_PROFILE
    truth = simulate_vehicle()
    # closed form of the course-like profile at t = 60 s is (460, 60); at 59.99 s one
    # step of the final velocity (1, -1) m/s earlier
    np.testing.assert_allclose(truth.final_position, [460 - 0.01 * 1.0 - 0.5 * 0.5 * 1e-4,
                                                      60 + 0.01 * 1.0], atol=1e-9)
