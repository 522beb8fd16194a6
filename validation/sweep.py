"""The MuJoCo dynamic sweep: a tilt table simulated directly with ``mujoco`` (not bench.model).

The model is this module's own MJCF string (:data:`XML`): a hinge about world +y through the
origin, a table body whose centre of mass lies on the hinge, a position servo driven by a
command with a varying rate (so ω and α are both non-zero), and four accelerometer sites:

* ``acc_x`` on the hinge axis, sensitive axis (local +x) = table +x → reads ``-g sin θ``;
* ``acc_y`` on the hinge axis, local +x = table -z (a +90° turn about +y) → ``-g cos θ``;
* ``arm_x`` / ``arm_y``: the same orientations at ``(pos_x, 0, pos_z)`` in the table frame
  (``docs/effects.md``: the lever arm), placed with ``MjSpec`` edits.

MuJoCo's accelerometer reports specific force (``a - g_vec``) in the site frame: at rest +g
along the local axis that points up, which with these frames is the course convention.
Off the hinge the site also feels the rigid-body acceleration ``α ŷ×p - ω² p``; with
``ŷ×(p_x, 0, p_z) = (p_z, 0, -p_x)`` the sensitive axes read

    x (table +x):  -g sin θ - ω²·pos_x + α·pos_z
    y (table -z):  -g cos θ + ω²·pos_z + α·pos_x

The integrator is explicit Euler without implicit damping: then the accelerometer uses the
same joint acceleration that moves the state (``qacc``), so ``α`` below is exactly what the
sensor saw.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import mujoco
import numpy as np

G: float = 9.80665
"""Standard gravity, m/s² (written here, not imported: the generator stands alone)."""

RATE: float = 100.0
"""Output sample rate, Hz."""

TIMESTEP: float = 0.001
"""Physics step, s (10 steps per output sample)."""

SUBSTEPS: int = int(round(1.0 / (RATE * TIMESTEP)))

OMEGA_MEAN, OMEGA_AMP, OMEGA_PERIOD, RAMP = 1.6, 1.0, 8.0, 2.0
"""Commanded rate ``ω_c(t) = w(t)·(1.6 + 1.0 sin(2πt/8 s))`` rad/s, ``w`` a raised-cosine
start over 2 s (the table starts at rest, so the record has no start-up transient)."""

XML = f"""
<mujoco model="validation_tilt_table">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{TIMESTEP}" gravity="0 0 -{G}" integrator="Euler">
    <flag eulerdamp="disable"/>
  </option>
  <worldbody>
    <body name="table">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.05" armature="0.01"/>
      <inertial pos="0 0 0" mass="2.0" diaginertia="0.04 0.08 0.04"/>
      <site name="acc_x" pos="0 0 0" quat="1 0 0 0"/>
      <site name="acc_y" pos="0 0 0" quat="0.7071067811865476 0 0.7071067811865476 0"/>
      <site name="arm_x" pos="0 0 0" quat="1 0 0 0"/>
      <site name="arm_y" pos="0 0 0" quat="0.7071067811865476 0 0.7071067811865476 0"/>
    </body>
  </worldbody>
  <actuator>
    <position name="servo" joint="hinge" kp="200" kv="20"/>
  </actuator>
  <sensor>
    <accelerometer name="acc_x" site="acc_x"/>
    <accelerometer name="acc_y" site="acc_y"/>
    <accelerometer name="arm_x" site="arm_x"/>
    <accelerometer name="arm_y" site="arm_y"/>
  </sensor>
</mujoco>
"""
"""The validation tilt table (see the module docstring for frames and signs)."""

SENSORS: tuple[str, ...] = ("acc_x", "acc_y", "arm_x", "arm_y")


@dataclass(frozen=True)
class SweepRun:
    """One simulated sweep, sampled at :data:`RATE`.

    tita : (N,) joint angle, rad (the encoder reads the simulated angle exactly).
    t : (N,) s.  omega, alpha : (N,) joint velocity and acceleration, rad/s, rad/s².
    force : (N, 2) specific force read by ``acc_x``, ``acc_y`` (on the hinge axis), m/s².
    arm_force : (N, 2) the same read by ``arm_x``, ``arm_y`` (at ``arm``), m/s².
    arm : ((pos_x, pos_z) of arm_x, (pos_x, pos_z) of arm_y), m.
    """

    tita: np.ndarray
    t: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    force: np.ndarray
    arm_force: np.ndarray
    arm: tuple[tuple[float, float], tuple[float, float]]

    def __post_init__(self) -> None:
        for name in ("tita", "t", "omega", "alpha", "force", "arm_force"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)


def command(t: np.ndarray) -> np.ndarray:
    """Commanded angle θ_c(t), rad: the integral of the commanded rate (trapezoid on ``t``)."""
    t = np.asarray(t, dtype=float)
    w = np.where(t < RAMP, 0.5 * (1.0 - np.cos(np.pi * np.minimum(t, RAMP) / RAMP)), 1.0)
    rate = w * (OMEGA_MEAN + OMEGA_AMP * np.sin(2.0 * np.pi * t / OMEGA_PERIOD))
    return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))])


def build_model(arm=((0.0, 0.0), (0.0, 0.0))) -> mujoco.MjModel:
    """Compile :data:`XML` with the offset sites at ``arm`` (MjSpec edit of their ``pos``)."""
    spec = mujoco.MjSpec.from_string(XML)
    for name, (px, pz) in zip(("arm_x", "arm_y"), arm, strict=True):
        spec.site(name).pos = [float(px), 0.0, float(pz)]
    return spec.compile()


@lru_cache(maxsize=16)
def simulate(n: int, arm=((0.0, 0.0), (0.0, 0.0))) -> SweepRun:
    """Simulate ``n`` samples of the sweep (cached: the run is deterministic).

    Each sample is taken at the state *before* a physics step: ``qpos``/``qvel`` are read
    before ``mj_step``, the sensors and ``qacc`` after it (``mj_step`` evaluates them at the
    start of the step), so angle, rates and readings belong to the same instant.
    """
    arm = tuple((float(px), float(pz)) for px, pz in arm)
    model = build_model(arm)
    data = mujoco.MjData(model)
    adr = [int(model.sensor(s).adr[0]) for s in SENSORS]  # local x of each site
    ctrl = command(np.arange(n * SUBSTEPS + 1) * TIMESTEP)
    tita, omega, alpha = np.empty(n), np.empty(n), np.empty(n)
    read = np.empty((n, 4))
    for k in range(n):
        for j in range(SUBSTEPS):
            data.ctrl[0] = ctrl[k * SUBSTEPS + j]
            if j == 0:
                tita[k], omega[k] = data.qpos[0], data.qvel[0]
            mujoco.mj_step(model, data)
            if j == 0:
                alpha[k] = data.qacc[0]
                read[k] = data.sensordata[adr]
    return SweepRun(tita=tita, t=np.arange(n) / RATE, omega=omega, alpha=alpha,
                    force=read[:, :2], arm_force=read[:, 2:], arm=arm)
