"""A read log written back in the course format, with its provenance (``tiltbench import``).

Files written (MATLAB v5, one row per sample, the course names and shapes so that the course
scripts run unchanged):

==========================  =========================================================
the log has                 written
==========================  =========================================================
θ (a θ column, or pose      ``ensayo.mat``: ``tita`` N×1 rad, ``datos`` N×2 m/s², and
angles: held samples only)  ``t`` N×1 s and ``pose`` N×1 when the log has them
θ unknown, ≥ 2 held poses   ``ensayo.mat`` with ``datos``, ``t`` (if any) and ``pose``
                            (N×1, integer labels, -1 moving) and **no** ``tita``
no held poses or only one   ``acel.mat``: ``t`` M×1 s (uniform), ``Aerr`` M×2 m/s²,
                            ``gyro`` M×1 rad/s when the log has a gyro
==========================  =========================================================

plus ``provenance.json``: the reader's record (source name and sha256, format, column
mapping, units and conversion, axes, detected segments and thresholds, gaps) with the tool
version and :data:`calib.logs.reader.LOG_FORMAT_VERSION`. The set is written atomically: all files
or none, and as one set: with ``force`` over an earlier import, its course file of the other
kind is removed with it (never an old ``ensayo.mat`` beside a new ``acel.mat``).

``acel.mat`` must be uniformly sampled (``calib.files.course.read_acel``); a log whose steps jitter
(phones, USB loggers) is resampled by linear interpolation onto the grid ``t0 + k·dt``, ``dt``
the mean step (same sample count), and the provenance says so with the largest deviation
``max |t_k − (t0 + k·dt)|`` of the log's times from that grid. A log with gaps in time
(``--allow-gaps``) is refused for ``acel.mat``: filling a gap would write readings the log does
not have; a calibration set (``ensayo.mat``) keeps its held poses on both sides of a gap. A
``tita``-less ``ensayo.mat`` is read back by :func:`calib.logs.reader.read_log` (pose labels, θ
unknown); ``calibrate``/``gap`` need θ and say so.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from calib.files.atomic import atomic_dir
from calib.input_rules import DataError

MAT_HEADER_LEN = 116
FILES = ("ensayo.mat", "acel.mat", "provenance.json")
"""Names ``tiltbench import`` may write (the overwrite check covers all of them)."""


def write_mat(path: Path, variables: dict[str, np.ndarray], note: str = "") -> None:
    """Write MATLAB v5 ``path``: 1-D arrays as N×1 columns; ``pose`` stored as int32 labels, the
    rest float64; a fixed header so that the same data give the same bytes. Streamed to the
    file (scipy.io.savemat on the open file, then the header's text replaced): a long log is
    not held a second time as bytes."""
    import scipy.io

    clean = {}
    for k, v in variables.items():
        arr = np.asarray(v, dtype=np.int32 if k == "pose" else float)
        clean[k] = arr.reshape(-1, 1) if arr.ndim == 1 else arr
    text = f"MATLAB 5.0 MAT-file, written by tiltbench import {note}".strip()
    with open(path, "wb") as f:
        scipy.io.savemat(f, clean, format="5", oned_as="column")
        f.seek(0)  # savemat's header text carries the time of writing
        f.write(text.encode("ascii", "replace")[:MAT_HEADER_LEN].ljust(MAT_HEADER_LEN, b" "))


def uniform(t: np.ndarray, columns: list[np.ndarray]
            ) -> tuple[np.ndarray, list[np.ndarray], dict | None]:
    """``t`` and each array of ``columns`` (N or N×k) on a uniform grid: unchanged (the same
    arrays, no copy) when already uniform (the ``read_acel`` tolerance), else linearly
    interpolated onto ``t0 + k·dt``; the record of it (None when unchanged)."""
    d = np.diff(t)
    d -= d.mean()
    np.abs(d, out=d)
    if d.max() <= 1e-6 * max(float((t[-1] - t[0]) / (t.size - 1)), 1e-12) + 1e-9:
        return t, list(columns), None
    del d
    # the mean step over the log keeps the sample count and lets the grid not drift from the
    # log's clock (a median step would, by its bias times N)
    count = int(t.size)
    step = float((t[-1] - t[0]) / (count - 1))
    grid = t[0] + step * np.arange(count)
    out = [np.interp(grid, t, x) if x.ndim == 1 else
           np.column_stack([np.interp(grid, t, x[:, k]) for k in range(x.shape[1])])
           for x in columns]
    # each sample i goes to grid point i: its time moves by |t_i − grid_i| (not to the
    # nearest grid point, which would hide a drift of the log's clock)
    dev = float(np.max(np.abs(t - grid)))
    return grid, out, {
        "method": "linear interpolation onto a uniform grid", "step_s": step,
        "samples_in": int(t.size), "samples_out": int(count),
        "max_deviation_from_grid_s": dev}


def course_variables(log) -> tuple[str, dict[str, np.ndarray], dict | None]:
    """The file name, its variables and the resampling record (None) for an
    :class:`calib.logs.reader.ImuLog` (module docstring)."""
    poses = 0 if log.pose is None else int(np.max(log.pose)) + 1
    if log.theta is not None:
        e = log.to_ensayo()  # the checks every later command makes, before writing
        out = {"tita": e.tita, "datos": e.datos}
        if log.t is not None:
            out["t"] = log.t
        if log.pose is not None:
            out["pose"] = log.pose
        return "ensayo.mat", out, None
    if poses >= 2:
        out = {"datos": log.acc}
        if log.t is not None:
            out["t"] = log.t
        out["pose"] = log.pose
        return "ensayo.mat", out, None
    if log.t is None:
        raise DataError(f"{log.source}: no θ, fewer than two held poses and no sample times: "
                        "neither a calibration run nor a vehicle run; give --poses, a θ "
                        "column or --columns t=…")
    gaps = log.provenance.get("gaps") or []
    if gaps:  # acel.mat is one uniform grid: a gap would be filled with readings never made
        g0 = gaps[0]
        raise DataError(f"{log.source}: {len(gaps)} gap(s) in time (the first "
                        f"{g0['length_s']:.4g} s after {g0['after']}); a vehicle run "
                        "(acel.mat) is one uniformly sampled stretch and import never writes "
                        "readings the log does not have: cut the log at the gap and import "
                        "each stretch on its own")
    t, (aerr, *gyro), record = uniform(log.t, [log.acc, *([log.gyro] if log.gyro is not None
                                                          else [])])
    out = {"t": t, "Aerr": aerr}
    if gyro:
        out["gyro"] = gyro[0]
    return "acel.mat", out, record


def write_course_set(log, out: str | Path, force: bool = False, tool_version: str = "",
                     extra: dict | None = None) -> tuple[list[Path], dict]:
    """Write the course file and ``provenance.json`` into ``out`` as one set (module
    docstring); return the paths and the provenance written."""
    from calib.files.course import dumps

    name, variables, record = course_variables(log)
    prov = dict(log.provenance)
    prov["tool"] = {"name": "tiltbench import", "version": tool_version}
    prov["written"] = {name: {k: list(np.shape(v)) if np.ndim(v) > 1 else [len(v), 1]
                              for k, v in variables.items()}}
    if record is not None:
        prov["resampled"] = record
    if name == "ensayo.mat" and "tita" not in variables:
        prov["theta"] = "unknown: ensayo.mat holds datos, t and pose labels, no tita"
    prov.update(extra or {})
    if str(out).strip() == "":
        raise DataError("--out: an empty folder name; give the folder to write the set into")
    # the set's files are exclusive: an earlier import's ensayo.mat does not survive beside a
    # new acel.mat (nor the reverse), so the folder always holds one set and its provenance
    with atomic_dir(out, force=force, owned=FILES, exclusive=FILES) as tmp:
        write_mat(tmp / name, variables, prov["source"]["name"])
        (tmp / "provenance.json").write_text(dumps(prov), encoding="utf-8")
    return [Path(out) / name, Path(out) / "provenance.json"], prov


__all__ = ["FILES", "course_variables", "uniform", "write_course_set", "write_mat"]
