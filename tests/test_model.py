"""The MJCF tilt table: compiles, names, the course convention from MuJoCo, MjSpec edits."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from bench.model import (
    ACC_SENSORS,
    ACC_SITES,
    ENCODER,
    SERVO,
    TILT_JOINT,
    TableEdits,
    load_spec,
    tilt_table,
)
from bench.tilt import SweepProfile, static_readings, sweep_readings
from calib.conventions import reference_accel


def test_model_compiles_and_elements_are_named():
    model, _ = tilt_table()
    for name in (*ACC_SENSORS.values(), ENCODER):
        assert model.sensor(name).id >= 0
    for name in ACC_SITES.values():
        assert model.site(name).id >= 0
    assert model.joint(TILT_JOINT).id >= 0 and model.actuator(SERVO).id >= 0
    assert np.all(model.sensor_noise == 0)  # noise belongs to our seeded sensor model


@pytest.mark.parametrize("g", [9.8, 9.81, 3.71])
def test_static_readings_equal_course_formulas(g):
    theta = np.linspace(-2 * np.pi, 2 * np.pi, 1001)
    a, enc = static_readings(theta, TableEdits(g=g))
    np.testing.assert_allclose(enc, theta, atol=1e-12)
    np.testing.assert_allclose(a, reference_accel(theta, g), atol=1e-9, rtol=0)


def test_repeated_poses_share_one_evaluation_and_keep_order():
    theta = np.array([0.5, 1.0, 0.5, 2.0, 1.0])
    a, enc = static_readings(theta)
    np.testing.assert_array_equal(enc, theta)
    np.testing.assert_array_equal(a[0], a[2])


def test_sweep_theta_is_the_simulated_joint_angle():
    t, a, enc = sweep_readings(SweepProfile(duration=5.0, rate=100.0))
    cmd = SweepProfile(duration=5.0).command(t)
    assert np.max(np.abs(enc - cmd)) > 1e-3  # the servo lags: θ is not the command
    # sites on the hinge axis: the specific force is gravity's projection at the encoder angle
    np.testing.assert_allclose(a, reference_accel(enc), atol=1e-9)


def test_lever_arm_sweep_reads_centripetal_acceleration():
    """A site off the axis reads extra specific force in a sweep (MuJoCo dynamics)."""
    edits = TableEdits(lever_arm=((0.2, 0.0), (0.0, 0.0)))
    t, a, enc = sweep_readings(SweepProfile(kind="accel", duration=4.0, rate=100.0), edits)
    extra = a - reference_accel(enc)
    assert np.max(np.abs(extra[:, 0])) > 1e-2


def test_edit_to_xml_reload_keeps_names_and_edits(tmp_path):
    spec = load_spec()
    from bench.model import edit_tilt_table

    edit_tilt_table(spec, TableEdits(g=9.81, misalignment=(0.01, 0.0)))
    path = tmp_path / "edited.xml"
    path.write_text(spec.to_xml())
    model = mujoco.MjModel.from_xml_path(str(path))
    assert model.opt.gravity[2] == pytest.approx(-9.81)
    for name in ACC_SITES.values():
        assert model.site(name).id >= 0


def test_misalignment_rotates_the_sensitive_axis():
    theta = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    a, _ = static_readings(theta, TableEdits(misalignment=(0.02, 0.0)))
    np.testing.assert_allclose(a[:, 0], reference_accel(theta + 0.02)[:, 0], atol=1e-9)
    np.testing.assert_allclose(a[:, 1], reference_accel(theta)[:, 1], atol=1e-9)


def test_batched_poses_equal_one_forward_per_pose_exactly():
    """The batched (multi-threaded) rollout gives exactly the mj_forward reading of each pose,
    so the thread split cannot change a byte."""
    theta = np.linspace(0, 2 * np.pi, 4001)
    a, _ = static_readings(theta)
    model, _ = tilt_table()
    data = mujoco.MjData(model)
    cols = [model.sensor(ACC_SENSORS[k]).adr[0] for k in "xy"]
    for i in range(0, theta.size, 400):
        data.qpos[0] = data.ctrl[0] = theta[i]
        data.qvel[0] = 0.0
        mujoco.mj_forward(model, data)
        np.testing.assert_array_equal(a[i], data.sensordata[cols])


