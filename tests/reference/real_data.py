"""Independent reference values for the real IMU logs described in data/real/README.md.

Computed here with the standard library's ``csv`` and plain numpy only — never with ``calib``
or ``bench`` — so that the readers, ``calibrate`` and the twin loop can be tested against
numbers the code under test did not make.

Held poses
----------
Each log's held poses are listed once in ``SPECS``: a pose is a half-open range of data rows
(0-based, header excluded). Where the ranges come from (the source's own annotation, or read
by eye from a plot) is stated per log in ``LogSpec.pose_source`` and in data/real/README.md.
A pose either has one axis along the vertical (``axis``, ``sign``: the tumble-test poses) or is
an arbitrary tilt (``axis`` None: a sensor left lying at some orientation); the per-pose
means are computed alike. For each pose and axis:

    mean  m = (1/n)·Σ a_i,    std  s = sqrt(Σ (a_i − m)² / (n − 1)),    norm = |(m_x, m_y, m_z)|

in m/s². Files in g are converted with ``g_unit`` m/s² per g, by default 9.80665 (the unit's
definition, standard gravity); files in raw counts with the sensitivity the source states, then
the same. A command that converts g with another value (``tiltbench … --g 9.8``) is compared
with ``pose_means(path, g_unit=9.8)``.

Six-position method
-------------------
The classic six-position (up/down) test: the multipoint tumble test of IEEE Std 1293 (linear
accelerometers) reduced to its two points per axis, as in the six-position calibration of
MEMS IMUs (Ferraris et al. 1995). With the axis pointing up
(reading +g) and down (reading −g) and the model  a_m = (1 + scale)·a_true + bias,

    bias  = (m_up + m_down) / 2                      [m/s²]
    scale = (m_up − m_down) / (2·g) − 1              [dimensionless, 0 for a perfect sensor]

where g is the local gravity the caller states (m/s²). Standard deviations assume independent
samples within a pose (white noise), var(m) = s²/n:

    std(bias)  = ½·sqrt(s_up²/n_up + s_down²/n_down),    std(scale) = std(bias) / g

A real sensor's noise is not white over long poses (bias instability, see IEEE Std 952 Allan
practice): positively correlated samples make these stds optimistic, so compare with them
using a stated multiple. The model ignores cross-axis terms (misalignment), which the
two-point form cannot identify.

Six-face least squares (bias, scale and misalignment of three axes)
-------------------------------------------------------------------
With poses on the faces of the case (each pose's ``axis`` and ``sign`` give the unit vector
``u_h = sign·e_axis`` that points up), every axis a reads, per pose mean,

    m_h,a = b_a + g·(K_ax·u_h,x + K_ay·u_h,y + K_az·u_h,z) + e_h,a,
    K_aa = 1 + scale_a,    misalignment_ab = K_ab / K_aa   (rad, small angle; a ≠ b)

(the linear terms of the IEEE Std 1293 model, K = (I + S)(I + M)). ``six_face`` fits each
axis' row ``[b_a, K_ax, K_ay, K_az]`` by ordinary least squares on the H pose means, design
``X = [1, g·u_h]``: ``p = (XᵀX)⁻¹ Xᵀ m``. For the six faces held once each, ``XᵀX =
diag(6, 2g², 2g², 2g²)``, so

    b_a  = mean of the six readings of axis a
    K_ak = (m_a(+k) − m_a(−k)) / (2g):   scale_a = K_aa − 1 is the six-position scale above,

and b_a is the mean of the three midpoints ``(m_a(+k) + m_a(−k))/2``, of which the six-position
bias takes only the one along the axis (the two agree when the linear model holds).

Uncertainty. A pose mean's error e_h,a is the within-pose noise (s²/n) plus how differently
the case sits and the bias reads from one hold to the next (hold-to-hold repeatability) —
and whatever the linear model misses. The residuals of the fit measure all of it:
``σ̂_a² = RSS_a / (H − 4)`` (2 dof for six faces), with ``cov = σ̂_a²·(XᵀX)⁻¹`` (``std``).
``std_within`` is the covariance of the same estimates from the within-pose white noise only,
``(XᵀX)⁻¹Xᵀ·diag(s_h²/n_h)·X(XᵀX)⁻¹``: a lower bound, optimistic whenever holds do not repeat.
Misalignment stds by the delta method through ``K_ab / K_aa``.
"""

from __future__ import annotations

import csv
import functools
import gzip
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

G_UNIT = 9.80665
"""m/s² per g: the definition of the unit g (standard gravity), used to convert files in g."""

REPO = Path(__file__).resolve().parents[2]
REAL_DIR = REPO / "data" / "real"


@dataclass(frozen=True)
class Pose:
    """One held pose in data rows ``[start, stop)``: ``axis`` reads ``sign``·g, or, with
    ``axis`` None (and ``sign`` 0), a tilt with no axis along the vertical."""

    name: str
    axis: str | None  # "x", "y" or "z": the axis that points along the vertical; None: tilted
    sign: int  # +1: the axis points up (reads +g); -1: down (reads -g); 0: tilted
    start: int
    stop: int


@dataclass(frozen=True)
class LogSpec:
    """How to read one log with plain csv: header lines, columns by index, units."""

    header_lines: int
    acc_columns: tuple[int, int, int]  # x, y, z
    acc_names: tuple[str, str, str]  # text each header cell contains (checked by the tests)
    acc_in_g: float | None  # g per unit of the file (1: g; 0.061e-3: those counts); None: m/s²
    acc_unit: str  # the file's own unit, as the source states it
    time_column: int | None  # None: the log has no time column (see sample_column)
    time_to_s: float  # multiply the time column by this to get seconds
    sample_column: int | None  # a sample counter (0, 1, 2, …) standing in for time, or None
    rate_hz: float | None  # the sample rate the source states, for a log timed by its counter
    gyro_columns: tuple[int, int, int] | None
    gyro_to_rads: float
    poses: tuple[Pose, ...]
    pose_source: str
    norm_tolerance: float = 0.05  # |norm/g − 1| a held pose's mean stays within (see the log)


# Every log's layout stated in full (no defaults hide a file's facts): alike in shape only.
SPECS: dict[str, LogSpec] = {
    # YEI 3-Space sensor, uncalibrated ("Raw") channels: gyro rad/s, compass gauss, accel g;
    # ~110 Hz (ChipTimeUS in µs). Poses read by eye from a plot of the three acceleration
    # axes and the gyro (data/real/README.md): flat, turned over, flat again.
    "yei-3space-z-flip.csv": LogSpec(
        header_lines=1,
        acc_columns=(7, 8, 9),
        acc_names=("RawAccelX", "RawAccelY", "RawAccelZ"),
        acc_in_g=1.0,
        acc_unit="g",
        time_column=0,
        time_to_s=1e-6,
        sample_column=None,
        rate_hz=None,
        gyro_columns=(1, 2, 3),
        gyro_to_rads=1.0,
        poses=(
            Pose("z_up", "z", +1, 0, 100),
            Pose("z_down", "z", -1, 1090, 1250),
            Pose("z_up_end", "z", +1, 2650, 2715),
        ),
        pose_source="by eye from a plot (README): quiet stretches of acceleration and gyro",
    ),
    # x-io NGIMU export (firmware v1.8), 50 Hz: gyro deg/s, accel g (device-calibrated).
    # Moved by hand for the first ~3.5 s, then laid flat (z up) until the end.
    "ngimu-sensors.csv": LogSpec(
        header_lines=1,
        acc_columns=(4, 5, 6),
        acc_names=("Accelerometer X (g)", "Accelerometer Y (g)", "Accelerometer Z (g)"),
        acc_in_g=1.0,
        acc_unit="g",
        time_column=0,
        time_to_s=1.0,
        sample_column=None,
        rate_hz=None,
        gyro_columns=(1, 2, 3),
        gyro_to_rads=math.pi / 180.0,
        poses=(Pose("z_up", "z", +1, 180, 499),),
        pose_source="by eye from a plot (README): the quiet stretch after the last motion",
    ),
    # Pololu MinIMU-9 v5 (LSM6DS33), held by hand: x up, turned over, x down; ~150 Hz. Raw
    # counts, 0.061 mg per count (the source's loader; LSM6DS33 at ±2 g). Time in ms.
    "pololu-minimu9-x-flip.csv": LogSpec(
        header_lines=1,
        acc_columns=(1, 2, 3),
        acc_names=("acc_x (counts)", "acc_y (counts)", "acc_z (counts)"),
        acc_in_g=0.061e-3,
        acc_unit="counts (0.061 mg per count)",
        time_column=0,
        time_to_s=1e-3,
        sample_column=None,
        rate_hz=None,
        gyro_columns=None,
        gyro_to_rads=1.0,
        poses=(
            Pose("x_up", "x", +1, 100, 1000),
            Pose("x_down", "x", -1, 2800, 3653),
        ),
        pose_source="by eye from a plot (README): the two long quiet stretches",
    ),
    # Axivity AX3 worn on the wrist, asleep: ~2 h at ~24.4 Hz, rows of the source cut out as
    # they are (gzip). Raw counts, 256 per g, always multiples of 4 (15.6 mg steps: the ±8 g
    # range). The z axis reads ~0.08 g low, so a pose's norm is 0.87-1.06 g: 15 % tolerance.
    "axivity-ax3-wrist-night.csv.gz": LogSpec(
        header_lines=1,
        acc_columns=(1, 2, 3),
        acc_names=("acc_x (counts)", "acc_y (counts)", "acc_z (counts)"),
        acc_in_g=1.0 / 256.0,
        acc_unit="counts (256 per g)",
        time_column=0,
        time_to_s=1.0,
        sample_column=None,
        rate_hz=None,
        gyro_columns=None,
        gyro_to_rads=1.0,
        poses=(
            Pose("p01", None, 0, 250, 3250),
            Pose("p02", None, 0, 7250, 10750),
            Pose("p03", None, 0, 17500, 25000),
            Pose("p04", None, 0, 26750, 47500),
            Pose("p05", None, 0, 52250, 70000),
            Pose("p06", None, 0, 70750, 83750),
            Pose("p07", None, 0, 89750, 104250),
            Pose("p08", None, 0, 105250, 120250),
            Pose("p09", None, 0, 120750, 125000),
            Pose("p10", None, 0, 141250, 146750),
            Pose("p11", None, 0, 148750, 153750),
            Pose("p12", None, 0, 169250, 175000),
        ),
        pose_source="by eye from a plot (README), each trimmed to its quiet 10 s windows",
        norm_tolerance=0.15,
    ),
    # imucal's example Ferraris session (MaD Lab Erlangen): held on each of six faces, then
    # turned 360° about x, y and z. Acceleration m/s², gyro deg/s (the values are whole steps
    # of 9.81/2048 m/s² and 2000/32768 deg/s); no time column: n_samples counts the samples,
    # 102.4 Hz as imucal's own example computes with this file (README). Uncalibrated: biases
    # of 0.4-0.6 m/s² put the pose norms 5.5 % below to 6.8 % above g, hence 8 %.
    "imucal-ferraris-session.csv.gz": LogSpec(
        header_lines=1,
        acc_columns=(4, 5, 6),
        acc_names=("acc_x", "acc_y", "acc_z"),
        acc_in_g=None,
        acc_unit="m/s^2",
        time_column=None,
        time_to_s=1.0,
        sample_column=0,
        rate_hz=102.4,
        gyro_columns=(1, 2, 3),
        gyro_to_rads=math.pi / 180.0,
        poses=(
            Pose("x_p", "x", +1, 540, 1271),
            Pose("x_a", "x", -1, 1620, 2361),
            Pose("y_p", "y", +1, 2814, 3298),
            Pose("y_a", "y", -1, 3740, 4152),
            Pose("z_p", "z", +1, 4522, 4975),
            Pose("z_a", "z", -1, 5376, 5983),
        ),
        pose_source=("the source's own annotation (imucal-ferraris-session-list.json, its "
                     "x_p … z_a; imucal slices data.iloc[start:end], so end is exclusive)"),
        norm_tolerance=0.08,
    ),
    # Samsung Galaxy S5 lying flat, screen up, for 4 h (scikit-diveMove's test data, AGPL):
    # 10 Hz, acceleration m/s², gyro rad/s ("output" channels), t = index / 10. One hold: the
    # whole excerpt. The phone's gyro biases (up to 0.035 rad/s) are far above the 0.02 rad/s
    # the tumble tests allow a hold, so it is not among their LOGS (tests/test_real_static.py).
    "galaxy-s5-static-4h.csv.gz": LogSpec(
        header_lines=1,
        acc_columns=(1, 2, 3),
        acc_names=("ax (m/s^2)", "ay (m/s^2)", "az (m/s^2)"),
        acc_in_g=None,
        acc_unit="m/s^2",
        time_column=0,
        time_to_s=1.0,
        sample_column=None,
        rate_hz=None,
        gyro_columns=(4, 5, 6),
        gyro_to_rads=1.0,
        poses=(Pose("z_up", "z", +1, 0, 144000),),
        pose_source="the whole excerpt: the phone lay still (its publisher's static test)",
    ),
}


def acc_to_ms2(spec: LogSpec, g_unit: float = G_UNIT) -> float:
    """m/s² per unit of the log's acceleration columns."""
    return 1.0 if spec.acc_in_g is None else spec.acc_in_g * g_unit


def times(spec: LogSpec, table: np.ndarray) -> np.ndarray:
    """Each row's time in s: the time column times ``time_to_s``, or, for a log with a sample
    counter instead (``time_column`` None), the counter divided by the stated ``rate_hz``."""
    if spec.time_column is not None:
        return table[:, spec.time_column] * spec.time_to_s
    if spec.sample_column is None or spec.rate_hz is None:
        raise ValueError("a LogSpec needs a time column or a sample counter with a rate")
    return table[:, spec.sample_column] / spec.rate_hz


def spec_for(path: str | Path) -> LogSpec:
    """The ``LogSpec`` of a log, looked up by its file name."""
    name = Path(path).name
    if name not in SPECS:
        raise KeyError(f"{name}: no reference spec; known logs: {', '.join(SPECS)}")
    return SPECS[name]


def read_rows(path: str | Path) -> tuple[list[list[str]], list[list[float]]]:
    """``(header_lines, rows)``: the header cells and every data row as floats (plain csv);
    a cell that is not a number becomes NaN."""
    spec = spec_for(path)
    with open_text(path) as f:
        lines = list(csv.reader(f))
    header, data = lines[: spec.header_lines], lines[spec.header_lines:]
    rows = [[_number(cell) for cell in line] for line in data if line]
    return header, rows


@functools.lru_cache(maxsize=8)
def _table(path: str, mtime_ns: int) -> np.ndarray:
    """The data rows as a read-only float array, read once per file version (the AX3 excerpt
    has 175000 rows; several tests ask for its poses)."""
    table = np.array(read_rows(path)[1], dtype=float)
    table.flags.writeable = False
    return table


def open_text(path: str | Path):
    """The log as text for ``csv`` (newline=""), decompressed if its name ends in ``.gz``."""
    if str(path).endswith(".gz"):
        return gzip.open(path, "rt", newline="")
    return open(path, newline="")


def _number(cell: str) -> float:
    try:
        return float(cell)
    except ValueError:
        return math.nan


def pose_means(path: str | Path, g_unit: float = G_UNIT) -> dict:
    """Per held pose: sample count, mean, std and norm of each axis (m/s²), gyro rms (rad/s).

    ``g_unit``: m/s² per g, converts logs in g or counts (module docstring).

    Returns ``{"file", "units", "acc_unit_in_file", "acc_to_ms2", "pose_source",
    "poses": {name: {"axis", "sign", "start", "stop", "n", "mean": {x, y, z},
    "std": {x, y, z}, "norm", "gyro_rms"}}}``;
    ``std`` is the sample standard deviation (n − 1), ``gyro_rms`` the rms over the pose of
    the gyro vector's magnitude (None when the log has no gyro); ``axis`` None (``sign`` 0)
    marks a tilted pose. ``norm_tolerance``: how far (relative) from g the log's pose norms are
    expected to stay, given its sensor's offsets (LogSpec).
    """
    spec = spec_for(path)
    table = _table(str(path), Path(path).stat().st_mtime_ns)
    acc = table[:, list(spec.acc_columns)] * acc_to_ms2(spec, g_unit)
    gyro = (table[:, list(spec.gyro_columns)] * spec.gyro_to_rads
            if spec.gyro_columns is not None else None)
    poses = {}
    for pose in spec.poses:
        rows_of = slice(pose.start, pose.stop)
        block = acc[rows_of]
        mean = block.mean(axis=0)
        std = block.std(axis=0, ddof=1)
        gyro_rms = (float(np.sqrt(np.mean(np.sum(gyro[rows_of] ** 2, axis=1))))
                    if gyro is not None else None)
        poses[pose.name] = {
            "axis": pose.axis, "sign": pose.sign, "start": pose.start, "stop": pose.stop,
            "n": int(block.shape[0]),
            "mean": dict(zip("xyz", map(float, mean), strict=True)),
            "std": dict(zip("xyz", map(float, std), strict=True)),
            "norm": float(np.linalg.norm(mean)),
            "gyro_rms": gyro_rms,
        }
    return {
        "file": Path(path).name,
        "units": {"mean": "m/s^2", "std": "m/s^2", "norm": "m/s^2", "gyro_rms": "rad/s",
                  "start": "data row (0-based, header excluded)", "stop": "data row, exclusive",
                  "n": "samples"},
        "acc_unit_in_file": spec.acc_unit,
        "acc_to_ms2": acc_to_ms2(spec, g_unit),
        "pose_source": spec.pose_source,
        "norm_tolerance": spec.norm_tolerance,
        "poses": poses,
    }


def six_position(path: str | Path, g: float, g_unit: float = G_UNIT) -> dict:
    """Bias and scale of every axis that has an up and a down pose (two-point tumble test).

    ``g`` is the local gravity in m/s²; ``g_unit`` converts logs in g or counts (as in
    ``pose_means``). For each axis the first pose listed with sign +1 and the first with sign
    −1 are used (a repeated pose, e.g. ``z_up_end``, is left out). Returns ``{"file", "g", "units",
    "axes": {axis: {"up", "down", "n_up", "n_down", "bias", "bias_std", "scale",
    "scale_std"}}}``; axes without both poses are absent. Equations: module docstring.
    """
    if not (math.isfinite(g) and g > 0):
        raise ValueError(f"g must be a positive number of m/s², got {g!r}")
    means = pose_means(path, g_unit)
    axes = {}
    for axis in "xyz":
        up = _first(means["poses"], axis, +1)
        down = _first(means["poses"], axis, -1)
        if up is None or down is None:
            continue
        pu, pd = means["poses"][up], means["poses"][down]
        m_up, m_down = pu["mean"][axis], pd["mean"][axis]
        bias_std = 0.5 * math.sqrt(pu["std"][axis] ** 2 / pu["n"] + pd["std"][axis] ** 2 / pd["n"])
        axes[axis] = {
            "up": up, "down": down, "n_up": pu["n"], "n_down": pd["n"],
            "bias": (m_up + m_down) / 2.0, "bias_std": bias_std,
            "scale": (m_up - m_down) / (2.0 * g) - 1.0, "scale_std": bias_std / g,
        }
    return {
        "file": means["file"], "g": g,
        "units": {"bias": "m/s^2", "bias_std": "m/s^2", "scale": "1", "scale_std": "1",
                  "g": "m/s^2", "n_up": "samples", "n_down": "samples"},
        "axes": axes,
    }


def _first(poses: dict, axis: str, sign: int) -> str | None:
    for name, pose in poses.items():
        if pose["axis"] == axis and pose["sign"] == sign:
            return name
    return None


def six_face(path: str | Path, g: float, g_unit: float = G_UNIT) -> dict:
    """Bias, scale and misalignment of the three axes from the log's face poses: per axis
    ordinary least squares on the pose means (module docstring, "Six-face least squares").

    ``g``: local gravity, m/s²; ``g_unit`` converts logs in g or counts (as in ``pose_means``).
    Every pose with an ``axis`` is used (tilted poses are not faces); at least five are needed
    (four parameters per axis and one dof for the scatter), on faces along all three axes.

    Returns ``{"file", "g", "units", "faces": [pose names], "dof": H − 4, "param_names",
    "params", "std", "std_within", "hold_sigma": {axis: σ̂_a}, "k_matrix", "residuals"}`` with
    ``param_names`` per axis a (order x, y, z): ``bias_a``, ``scale_a``, then
    ``misalignment_ab`` for the two other axes b in xyz order; ``residuals[h][a]`` m/s².
    """
    if not (math.isfinite(g) and g > 0):
        raise ValueError(f"g must be a positive number of m/s², got {g!r}")
    means = pose_means(path, g_unit)
    faces = [(name, pose) for name, pose in means["poses"].items() if pose["axis"] is not None]
    h = len(faces)
    u = np.zeros((h, 3))
    m = np.zeros((h, 3))
    var_w = np.zeros((h, 3))
    for i, (_, pose) in enumerate(faces):
        u[i, "xyz".index(pose["axis"])] = pose["sign"]
        m[i] = [pose["mean"][a] for a in "xyz"]
        var_w[i] = [pose["std"][a] ** 2 / pose["n"] for a in "xyz"]
    x = np.column_stack([np.ones(h), g * u])
    if h < 5 or np.linalg.matrix_rank(x) < 4:
        raise ValueError(f"{means['file']}: {h} face poses do not identify bias, scale and "
                         "misalignment of three axes (need faces along x, y and z, ≥ 5 poses)")
    xtx_inv = np.linalg.inv(x.T @ x)
    hat = xtx_inv @ x.T  # (4, H): p = hat @ m
    names, params, std, std_within, sigma, rows, resid = [], [], [], [], {}, [], []
    for k, axis in enumerate("xyz"):
        row = hat @ m[:, k]  # [b, K_x, K_y, K_z]
        r = m[:, k] - x @ row
        s2 = float(r @ r) / (h - 4)
        cov = s2 * xtx_inv
        cov_w = hat @ np.diag(var_w[:, k]) @ hat.T
        kaa = row[1 + k]
        others = [j for j in range(3) if j != k]
        jac = np.zeros((4, 4))  # d[b, K_aa − 1, K_ab/K_aa, K_ac/K_aa] / d[b, K_x, K_y, K_z]
        jac[0, 0] = 1.0
        jac[1, 1 + k] = 1.0
        for i, j in enumerate(others):
            jac[2 + i, 1 + j] = 1.0 / kaa
            jac[2 + i, 1 + k] = -row[1 + j] / kaa**2
        names += [f"bias_{axis}", f"scale_{axis}", *(f"misalignment_{axis}{'xyz'[j]}"
                                                       for j in others)]
        params += [float(row[0]), float(kaa - 1.0), *(float(row[1 + j] / kaa) for j in others)]
        std += np.sqrt(np.diag(jac @ cov @ jac.T)).tolist()
        std_within += np.sqrt(np.diag(jac @ cov_w @ jac.T)).tolist()
        sigma[axis] = math.sqrt(s2)
        rows.append(row[1:].tolist())
        resid.append(r)
    return {
        "file": means["file"], "g": g,
        "units": {"bias": "m/s^2", "scale": "1", "misalignment": "rad", "hold_sigma": "m/s^2",
                  "residuals": "m/s^2", "k_matrix": "1", "g": "m/s^2"},
        "faces": [name for name, _ in faces], "dof": h - 4,
        "param_names": names, "params": params, "std": std, "std_within": std_within,
        "hold_sigma": sigma, "k_matrix": rows,
        "residuals": np.column_stack(resid).tolist(),
    }
