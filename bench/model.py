"""The MJCF models: where they live, the names of their elements, load / edit / compile.

``models/*.xml`` is the only hand-edited source. Everything that changes a model goes
``MjSpec.from_file`` → edit → ``compile()``; an edited model is written with ``to_xml()`` to an
output directory, never to ``models/``. Elements are looked up by the names defined here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from calib.conventions import G

# A source checkout (and an editable install) reads models/ beside bench/; a wheel carries the
# same files as bench/models/ (pyproject.toml maps one to the other).
_BENCH_DIR = Path(__file__).resolve().parent
_CANDIDATES = (_BENCH_DIR / "models", _BENCH_DIR.parent / "models")
MODELS_DIR = next((d for d in _CANDIDATES if d.is_dir()), _CANDIDATES[-1])
TILT_TABLE_XML = MODELS_DIR / "tilt_table.xml"
VEHICLE_XML = MODELS_DIR / "vehicle.xml"
SIX_FACE_XML = MODELS_DIR / "six_face_fixture.xml"

# Tilt table element names (models/tilt_table.xml).
TILT_JOINT = "tilt"
TABLE_BODY = "table"
SERVO = "servo"
ENCODER = "encoder"
TABLE_ACC_SITES = {"x": "acc_x", "y": "acc_y"}
TABLE_ACC_SENSORS = {"x": "accel_x", "y": "accel_y"}
ACC_SITES = TABLE_ACC_SITES
"""The tilt table's accelerometer sites (short name kept for existing importers)."""
ACC_SENSORS = TABLE_ACC_SENSORS
"""The tilt table's accelerometer sensors (short name kept for existing importers)."""

# Planar vehicle element names (models/vehicle.xml). Its accelerometer *sites* are named
# acc_x_site / acc_y_site and its *sensors* acc_x / acc_y: not the tilt table's names.
VEHICLE_BODY = "vehicle"
VEHICLE_SLIDE_JOINTS = {"x": "slide_x", "y": "slide_y"}
VEHICLE_DRIVES = {"x": "drive_x", "y": "drive_y"}
VEHICLE_ACC_SITES = {"x": "acc_x_site", "y": "acc_y_site"}
VEHICLE_ACC_SENSORS = {"x": "acc_x", "y": "acc_y"}

# Six-face fixture element names (models/six_face_fixture.xml): three nested hinges, outer to
# inner (about world x, then y, then the case's z), their position servos and encoders, and the
# case's 3-axis accelerometer and gyro on the site "imu" (site frame = case axes).
FIXTURE_JOINTS = ("tumble_x", "tumble_y", "tumble_z")
FIXTURE_SERVOS = ("servo_x", "servo_y", "servo_z")
FIXTURE_ENCODERS = ("enc_x", "enc_y", "enc_z")
CASE_BODY = "case"
IMU_SITE = "imu"
IMU_ACCEL = "imu_accel"
IMU_GYRO = "imu_gyro"


def load_spec(path: Path = TILT_TABLE_XML) -> mujoco.MjSpec:
    """Load an MJCF file as an editable :class:`mujoco.MjSpec`."""
    if not Path(path).exists():
        raise FileNotFoundError(f"{path}: model file not found (models/ must sit beside bench/)")
    return mujoco.MjSpec.from_file(str(path))


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, np.asarray(a, float), np.asarray(b, float))
    return out


def _axis_angle_quat(axis, angle: float) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, np.asarray(axis, float), float(angle))
    return q


@dataclass(frozen=True)
class TableEdits:
    """Physical edits of the tilt table, applied through ``MjSpec``.

    Attributes
    ----------
    g : magnitude of gravity, m/s² (option gravity = (0, 0, -g)).
    misalignment : per axis, rotation (rad) of the accelerometer site about the hinge axis
        (+y, right-handed); the sensitive axis tips towards the other axis' direction.
    tilt_offset : rad; the table (both sites) is mounted rotated by this angle about the hinge
        relative to the encoder zero: the sensors see θ_encoder + tilt_offset.
    lever_arm : per axis, site position (x, z) in the table frame, m, off the hinge axis.
    cutoff : per axis, sensor range (MuJoCo ``cutoff``: readings clipped to ±cutoff), m/s²;
        0 means unlimited.
    """

    g: float = G
    misalignment: tuple[float, float] = (0.0, 0.0)
    tilt_offset: float = 0.0
    lever_arm: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0), (0.0, 0.0))
    cutoff: tuple[float, float] = (0.0, 0.0)


def edit_tilt_table(spec: mujoco.MjSpec, edits: TableEdits) -> mujoco.MjSpec:
    """Apply :class:`TableEdits` to a tilt-table spec in place and return it."""
    spec.option.gravity = [0.0, 0.0, -float(edits.g)]
    hinge_axis = np.array([0.0, 1.0, 0.0])
    for k, axis in enumerate(("x", "y")):
        site = spec.site(TABLE_ACC_SITES[axis])
        rot = _axis_angle_quat(hinge_axis, edits.misalignment[k] + edits.tilt_offset)
        site.quat = _quat_mul(rot, np.asarray(site.quat, float))
        px, pz = edits.lever_arm[k]
        site.pos = [float(px), 0.0, float(pz)]
        if edits.cutoff[k] > 0:
            spec.sensor(TABLE_ACC_SENSORS[axis]).cutoff = float(edits.cutoff[k])
    return spec


def tilt_table(edits: TableEdits | None = None) -> tuple[mujoco.MjModel, mujoco.MjSpec]:
    """Compile the tilt table (optionally edited). Returns ``(model, spec)``."""
    spec = load_spec(TILT_TABLE_XML)
    edit_tilt_table(spec, edits or TableEdits())
    return spec.compile(), spec


def six_face_fixture(g: float = G) -> tuple[mujoco.MjModel, mujoco.MjSpec]:
    """Compile the six-face tumble fixture with gravity ``(0, 0, -g)``, g in m/s² (an
    ``MjSpec`` edit). Returns ``(model, spec)``."""
    spec = load_spec(SIX_FACE_XML)
    spec.option.gravity = [0.0, 0.0, -float(g)]
    return spec.compile(), spec


def sensor_slice(model: mujoco.MjModel, name: str) -> slice:
    """Columns of ``sensordata`` that hold sensor ``name``."""
    s = model.sensor(name)
    adr = int(s.adr[0])
    return slice(adr, adr + int(s.dim[0]))


def full_state(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """``mjSTATE_FULLPHYSICS`` state vector of ``data`` (the rollout initial-state layout)."""
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    return state
