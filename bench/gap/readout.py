"""The accelerometers of any edited table read along the recorded motion, without MuJoCo.

The catalog's physical effects (misalignment, tilt offset, lever arm) move or turn a
massless accelerometer site on the table: the table moves the same for every parameter
value (:class:`bench.gap.replay.Motion`), only the readout changes. For a point r fixed on a
rigid body turning about a fixed axis, the specific force in the body frame is affine in r,

    f_b(r) = f_b(0) + (α× + ω×ω×)·r,       f_b(0) = R_wbᵀ·(a_0 − g)

(α, ω the body's angular acceleration and rate, ``a_0`` the acceleration of the body
origin; Featherstone 2008, §2.11), and a site turned by R_bs reads f_s = R_bsᵀ·f_b(r) —
exactly what MuJoCo's accelerometer evaluates (``mj_objectAcceleration`` at the site, in the
site frame). So the motion's field is taken **from MuJoCo** once, with four probe
accelerometers on the table (at the body origin and one metre along each body axis,
:func:`probe_model`), and any site's reading is the linear combination
(:func:`readout`): no hand-written kinematics, and the probes see the same
α, ω and timing MuJoCo's sensors see in that run. :func:`readout_error` compares it with
MuJoCo's own sensors for a model; the workflow checks it at the fitted parameters.

A sensor the formula does not cover (not an accelerometer on the table body, with delay,
history or interval) raises :class:`ReadoutUnsupportedError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import mujoco
import numpy as np

from bench.gap.replay import (
    Motion,
    Replay,
    idle_stages,
    motion_sensordata,
    record_motion_read,
)
from bench.model import TABLE_BODY, TableEdits, edit_tilt_table, load_spec, tilt_table

PROBE_SITES = ("probe_o", "probe_x", "probe_y", "probe_z")
"""Probe sites on the table body: at its origin and 1 m along its +x, +y, +z axes."""

PROBE_POS = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])

READOUT_TOL = 1e-9
"""m/s²: largest accepted difference between :func:`readout` and MuJoCo's sensors for the
same model and motion (both are the same affine map evaluated in a different order:
rounding, ≲ 1e-13 m/s² on the bench's runs)."""


class ReadoutUnsupportedError(ValueError):
    """The model has a sensor the kinematic readout does not reproduce."""


def _physics_only(table: TableEdits) -> TableEdits:
    """``table`` with the site edits removed (same physics: sites have no mass)."""
    return replace(table, misalignment=(0.0, 0.0), tilt_offset=0.0,
                   lever_arm=((0.0, 0.0), (0.0, 0.0)), cutoff=(0.0, 0.0))


def probe_model(table: TableEdits | None = None) -> mujoco.MjModel:
    """The table of ``table``'s physics (no site edits) with the probe accelerometers
    :data:`PROBE_SITES` (identity orientation) added after its own sensors; the stages with
    nothing to act on switched off (:func:`bench.gap.replay.idle_stages`: the same values)."""
    spec = load_spec()
    edit_tilt_table(spec, _physics_only(table or TableEdits()))
    body = spec.body(TABLE_BODY)
    for name, pos in zip(PROBE_SITES, PROBE_POS, strict=True):
        body.add_site(name=name, pos=pos.tolist(), quat=[1.0, 0.0, 0.0, 0.0])
        spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_ACCELEROMETER,
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=name)
    model = spec.compile()
    model.opt.disableflags |= idle_stages(model)
    return model


@dataclass(frozen=True)
class AccelField:
    """Specific force on the table along a recorded motion, in the table (body) frame.

    origin : (N, 3) f_b(0), m/s², at the samples.
    gradient : (3, N, 3) ∂f_b/∂r_j = (α× + ω×ω×)·e_j, 1/s² (probe j − origin, per metre),
        stored by j so that ``origin + Σ_j gradient[j]·r_j`` runs on contiguous rows.
    sensordata : (N, nsensordata) the probe model's sensordata (its own sensors first: the
        nominal table's readings).
    state : (N, nstate) full-physics state at the samples (after the step read).
    motion : the recorded motion.  model : the probe model (:func:`probe_model`).
    """

    origin: np.ndarray
    gradient: np.ndarray
    sensordata: np.ndarray
    state: np.ndarray
    motion: Motion
    model: mujoco.MjModel
    _mujoco: dict = field(default_factory=dict, repr=False, compare=False)

    def mujoco_read(self, table: TableEdits) -> tuple[mujoco.MjModel, np.ndarray, float]:
        """The table ``table`` compiled, MuJoCo's sensordata (N, nsensordata) of it along the
        motion and the step error (:func:`bench.gap.replay.motion_sensordata`). Kept per
        table: the sysid confirmation and the extended gap read the same one. On one thread:
        the gap run reads it on its worker thread beside the analysis (``bench.gap.run``),
        whose core a second rollout thread would take (``docs/development.md``, stop 56)."""
        if table not in self._mujoco:
            model, _ = tilt_table(table)
            sd, _, step_error = motion_sensordata(self.motion, model, threads=1)
            self._mujoco.clear()  # one entry: the last table asked for
            self._mujoco[table] = (model, sd, step_error)
        return self._mujoco[table]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.model.sensor(i).name for i in range(self.model.nsensor))

    def column(self, name: str) -> np.ndarray:
        """The sensordata columns (N, dim) of sensor ``name`` of the probe model."""
        s = self.model.sensor(name)
        return self.sensordata[:, int(s.adr[0]):int(s.adr[0]) + int(s.dim[0])]


def accel_field(motion: Motion, table: TableEdits | None = None, threads: int = 2
                ) -> AccelField:
    """Read the probe accelerometers of :func:`probe_model` along ``motion`` (one batched
    ``nstep = 1`` rollout, :func:`bench.gap.replay.motion_sensordata`)."""
    model = probe_model(table)
    sd, state, _ = motion_sensordata(motion, model, threads)
    return _field(model, motion, sd, state)


def record_field(replay: Replay, table: TableEdits | None = None, threads: int = 2
                 ) -> AccelField:
    """``accel_field(record_motion(replay, table), table)`` in one rollout: the motion's
    steps are stepped on :func:`probe_model` and its sensordata kept
    (:func:`bench.gap.replay.record_motion_read`; the same states and sensordata bit for
    bit, one MuJoCo pass over the steps instead of two)."""
    model = probe_model(table)
    motion, sd = record_motion_read(replay, table, threads, read=model)
    if sd is None:  # a piece was rolled out whole: read its steps again, one by one
        sd, state, _ = motion_sensordata(motion, model, threads)
    else:
        sd, state = motion.at_samples(sd), motion.at_samples(motion.after)
    return _field(model, motion, sd, state)


def _field(model: mujoco.MjModel, motion: Motion, sd: np.ndarray, state: np.ndarray
           ) -> AccelField:
    """The :class:`AccelField` of the probe model's sensordata ``sd`` and states ``state``
    (N, …) at the samples."""
    cols = [sd[:, int(model.sensor(p).adr[0]):int(model.sensor(p).adr[0]) + 3]
            for p in PROBE_SITES]
    origin = cols[0]
    gradient = np.stack([c - origin for c in cols[1:]])  # / 1 m
    return AccelField(origin, gradient, sd, state, motion, model)


def _site_frame(model: mujoco.MjModel, data: mujoco.MjData, site: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """Site position (3,) and rotation (3, 3) in its body's frame, as MuJoCo places it
    (``mj_kinematics``: honours the compiler's same-frame simplifications)."""
    b = int(model.site_bodyid[site])
    rot_b = data.xmat[b].reshape(3, 3)
    pos = rot_b.T @ (data.site_xpos[site] - data.xpos[b])
    rot = rot_b.T @ data.site_xmat[site].reshape(3, 3)
    return pos, rot


def readout(field: AccelField, model: mujoco.MjModel) -> np.ndarray:
    """Sensordata (N, nsensordata) of ``model`` (same physics as the field's) along the
    field's motion: accelerometers on the table from the field (module docstring), with
    MuJoCo's ``cutoff`` clipping; every other sensor copied from the field's sensordata.

    Raises :class:`ReadoutUnsupportedError` for a sensor the formula does not cover.
    """
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    table = int(model.body(TABLE_BODY).id)
    out = np.empty((field.origin.shape[0], model.nsensordata))
    for i in range(model.nsensor):
        s = model.sensor(i)
        adr, dim = int(s.adr[0]), int(s.dim[0])
        if (model.sensor_delay[i] != 0 or np.any(model.sensor_interval[i] != 0)
                or model.sensor_history[i, 0] != 0):
            raise ReadoutUnsupportedError(f"sensor {s.name!r}: delay, history or interval")
        if model.sensor_type[i] != mujoco.mjtSensor.mjSENS_ACCELEROMETER:
            if s.name not in field.names:
                raise ReadoutUnsupportedError(f"sensor {s.name!r}: not in the probe model")
            out[:, adr:adr + dim] = field.column(s.name)
            continue
        site = int(model.sensor_objid[i])
        if int(model.site_bodyid[site]) != table:
            raise ReadoutUnsupportedError(f"sensor {s.name!r}: its site is not on the table")
        pos, rot = _site_frame(model, data, site)
        f_b = field.origin.copy()  # (N, 3), table frame
        for j in np.flatnonzero(pos):
            f_b += field.gradient[j] * pos[j]
        f_s = f_b @ rot  # row-wise R_bsᵀ·f_b
        cut = float(model.sensor_cutoff[i])
        out[:, adr:adr + dim] = np.clip(f_s, -cut, cut) if cut > 0 else f_s
    return out


def readout_error(field: AccelField, model: mujoco.MjModel, sensordata: np.ndarray) -> float:
    """Largest |readout − MuJoCo| (m/s²) over the accelerometers of ``model``, given
    MuJoCo's ``sensordata`` (N, nsensordata) of it along the same motion."""
    pred = readout(field, model)
    acc = [i for i in range(model.nsensor)
           if model.sensor_type[i] == mujoco.mjtSensor.mjSENS_ACCELEROMETER]
    cols = np.concatenate([np.arange(model.sensor_adr[i], model.sensor_adr[i] + 3)
                           for i in acc])
    return float(np.max(np.abs(pred[:, cols] - sensordata[:, cols]))) if cols.size else 0.0
