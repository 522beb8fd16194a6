"""Course-compatible files (MATLAB v5 .mat, datos.txt) and the truth manifest.

Same seed and parameters give the same bytes: the .mat header, which scipy stamps with the
current time, is replaced by a fixed text, and JSON is written with sorted keys.
Every file is written atomically (temporary file + rename) and never replaces an existing
file unless ``force``.
"""

from __future__ import annotations

import io
import platform
from pathlib import Path

import numpy as np
import scipy.io

from calib.files.course import atomic_write_bytes, atomic_write_text, dumps

MAT_HEADER_LEN = 116  # MATLAB v5: 116 bytes of descriptive text, space padded


def versions() -> dict[str, str]:
    """Versions of everything that shapes a dataset (recorded in every manifest)."""
    import matplotlib
    import mujoco
    import scipy

    from bench.version import __version__

    out = {
        "tiltbench": __version__,
        "mujoco": mujoco.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
        "python": platform.python_version(),
    }
    try:
        import rerun

        out["rerun-sdk"] = rerun.__version__
    except Exception:  # rerun is optional for reading datasets
        pass
    return out


def without_versions(tree):
    """A JSON tree with every ``versions`` block (:func:`versions`, at any depth) left out:
    what must stay the same when another patch release of a package is installed."""
    if isinstance(tree, dict):
        return {k: without_versions(v) for k, v in tree.items() if k != "versions"}
    if isinstance(tree, list):
        return [without_versions(v) for v in tree]
    return tree


def mat_bytes(variables: dict[str, np.ndarray], note: str = "") -> bytes:
    """MATLAB v5 bytes of ``variables`` with a fixed, reproducible header.

    Arrays are stored as float64 (as FreeMat/MATLAB write them); 1-D arrays become N×1
    columns (the course layout), so MATLAB code written for the course files works as is.
    """
    buf = io.BytesIO()
    clean = {}
    for k, v in variables.items():
        arr = np.asarray(v, dtype=float)
        clean[k] = arr.reshape(-1, 1) if arr.ndim == 1 else arr
    scipy.io.savemat(buf, clean, format="5", oned_as="column")
    data = bytearray(buf.getvalue())
    text = f"MATLAB 5.0 MAT-file, written by tiltbench {note}".strip()
    header = text.encode("ascii", errors="replace")[:MAT_HEADER_LEN].ljust(MAT_HEADER_LEN, b" ")
    data[:MAT_HEADER_LEN] = header
    return bytes(data)


def save_mat(path: str | Path, variables: dict[str, np.ndarray], force: bool = False) -> Path:
    """Write a course-compatible .mat file atomically (see :func:`mat_bytes`)."""
    return atomic_write_bytes(path, mat_bytes(variables), force=force)


def write_gps(path: str | Path, fixes, force: bool = False) -> Path:
    """Write ``gps.mat`` (course style, :func:`save_mat`) of :class:`bench.gnss.GnssFixes`:
    ``t_gps`` M×1 s, ``pos`` M×2 m, and ``vel`` M×2 m/s when the receiver gives velocity."""
    return save_mat(path, fixes.mat_variables(), force=force)


def write_json(path: str | Path, obj: dict, force: bool = False) -> Path:
    """Write JSON with sorted keys (stable bytes) atomically."""
    return atomic_write_text(path, dumps(obj), force=force)


MODEL_UNITS: dict[str, str] = {
    "sensor.*.bias": "m/s²", "sensor.*.scale": "1", "sensor.*.noise_var": "(m/s²)²",
    "table.g": "m/s²", "table.misalignment": "rad", "table.tilt_offset": "rad",
    "table.lever_arm": "m", "table.cutoff": "m/s²",
}
"""Units of a bench model (sensor bias/scale/noise and the MjSpec table edits): a run's truth
and the gap report's ``model_after`` share them."""


def _run_units() -> dict[str, str]:
    """Units of one run's truth object (calibration or vehicle: the keys they have)."""
    from calib.units import effect_units

    out = {f"sensor.*.terms.{k}": u for k, u in effect_units().items()}
    out.update({
        "g": "m/s²", "n": "count", "n_samples": "count", "seed": "—",
        **MODEL_UNITS,
        "theta_design.start": "rad", "theta_design.stop": "rad",
        "theta_design.count": "count", "theta_design.per_position": "count",
        "theta_design.positions": "count",
        "theta_summary.min": "rad", "theta_summary.max": "rad",
        "theta_summary.distinct": "count",
        "sweep.start": "rad", "sweep.stop": "rad", "sweep.duration": "s", "sweep.rate": "Hz",
        "sweep.cycles": "1",
        "duration": "s", "rate": "Hz", "p0": "m", "v0": "m/s",
        "raw_final_position": "m", "profile.accel": "m/s²", "profile.duration": "s",
        "trajectory.final_position": "m", "trajectory.final_velocity": "m/s",
        "trajectory.mass": "kg", "trajectory.t_final": "s", "trajectory.samples.t": "s",
        "trajectory.samples.pos": "m", "trajectory.samples.vel": "m/s",
    })
    return out


TURN_UNITS = {
    "turning": "—", "yaw_profile.alpha": "rad/s²", "yaw_profile.duration": "s",
    "gyro_sigma": "rad/s", "gyro_seed_spawn_key": "—", "trajectory.final_heading": "rad",
    "trajectory.samples.heading": "rad", "trajectory.samples.yaw_rate": "rad/s",
}
"""Units of the turning vehicle's extra keys in ``truth.json`` (:mod:`bench.vehicle`), added
only for a turning run so that other sets keep their bytes."""

TWIN_UNITS: dict[str, str] = {
    "sensor.*.terms.b": "m/s²", "theta": "rad",
    "sensor_profile.sample_rate": "Hz", "sensor_profile.run_rate": "Hz",
    "sensor_profile.white_noise_density": "(m/s²)/√Hz",
    "sensor_profile.bias_instability": "m/s²",
    "sensor_profile.rate_random_walk": "m/s²/√s",
    "sensor_profile.quantization_step": "m/s²",
    "sensor_profile.calibration.bias": "m/s²", "sensor_profile.calibration.scale": "1",
}
"""Units of the twin's and the static log's keys in ``truth.json`` (:mod:`bench.sensor_twin`;
added only for a ``--sensor`` or a ``generate static`` run, so other sets keep their bytes)."""


def truth_units(gps: bool = False, turning: bool = False) -> dict[str, str]:
    """The ``units`` of every ``truth.json`` (calibration, vehicle and course sets; a course
    set nests a calibration and a vehicle truth under ``calibration`` / ``vehicle``), the one
    home of truth units (docs/units.md). ``gps``: the set has a receiver (a ``gps`` object,
    :data:`bench.gnss.GPS_UNITS`); its units are added only then, so a set without fixes keeps
    its bytes."""
    from calib.units import nest

    run = _run_units()
    out = dict(run)
    out.update(nest("calibration", run))
    out.update(nest("vehicle", run))
    out.update({
        "candidates.*": "m", "true_final_position": "m",
        "course.g": "m/s²", "course.accel_limits": "m/s²", "course.bias_limit": "m/s²",
        "course.scale_limit": "1", "course.noise_var": "(m/s²)²", "course.min_separation": "m",
        "course.raw_jitter": "m", "course.n_segments": "count",
    })
    if gps:
        from bench.gnss import GPS_UNITS

        out.update(GPS_UNITS)
    if turning:  # the turning vehicle's keys, only then
        out.update(TURN_UNITS)
        out.update(nest("vehicle", TURN_UNITS))
    return out


def truth_manifest(truth: dict, seed: int) -> dict:
    """The ``truth.json`` object: the given parameters plus the seed, the package versions and
    the units of its numbers (:func:`truth_units`); recordings log the same object."""
    from calib.units import with_units

    manifest = dict(truth)
    manifest["seed"] = int(seed)
    manifest["versions"] = versions()
    turning = bool(truth.get("turning") or (isinstance(truth.get("vehicle"), dict)
                                            and truth["vehicle"].get("turning")))
    units = truth_units(gps="gps" in truth, turning=turning)
    if "sensor_profile" in truth or truth.get("kind") == "static":  # only then: bytes kept
        units.update(TWIN_UNITS)
    return with_units(manifest, units)


def write_truth(path: str | Path, truth: dict, seed: int, force: bool = False) -> Path:
    """Write ``truth.json`` (:func:`truth_manifest`)."""
    return write_json(path, truth_manifest(truth, seed), force=force)


def datos_text(p0, v0, noise_var) -> str:
    """``datos.txt`` in the course's wording (Spanish, bracketed pairs, UTF-8)."""

    def pair(v):
        return "[" + " ".join(f"{float(x):g}" for x in v) + "]"

    return (f"Posición inicial = {pair(p0)}\n"
            f"Velocidad inicial = {pair(v0)}\n"
            f"varianza del ruido de los acelerómetros = {pair(noise_var)}")


def write_datos(path: str | Path, p0, v0, noise_var, force: bool = False) -> Path:
    return atomic_write_text(path, datos_text(p0, v0, noise_var), force=force)


def prepare_out_dir(out: str | Path, names: list[str], force: bool = False) -> Path:
    """Create ``out``; refuse (before writing anything) if any of ``names`` exists there."""
    out = Path(out)
    if not force:
        clash = [n for n in names if (out / n).exists()]
        if clash:
            raise FileExistsError(f"{out}: {', '.join(clash)} already exist(s)")
    out.mkdir(parents=True, exist_ok=True)
    return out
