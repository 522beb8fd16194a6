"""The front door (issue 31): the log readers and every command that reads a log —
``calibrate``, ``noise``, ``import``, ``apply``, ``gap`` — and the sensor profile read by
``generate … --sensor`` and ``gap --sensor``, under bad input as a class, and a named valid
set that must still pass.

Kinds (each a list of :class:`~validation.fuzz.runner.Case`; written from
``docs/real-data.md``, ``docs/noise.md`` and ``tiltbench X --help``, not from the code):

================  ===========================================================================
``unit_mistake``  a still log (``noise``) and a held-pose log (``calibrate``, ``import``, and
                  ``apply`` / ``gap`` for the CSV ones) written in one unit and labelled or
                  stated as another: g as m/s², m/s² as g, mg, counts without or with a
                  wrong ``--sensitivity``, int16 counts through ``--map``, a gravity-removed
                  export (≈ 0 g), in CSV, phyphox zip, Sensor Logger, ROS 1/2 bags, ``.mat``;
                  a gyro in the wrong unit under ``--theta-source gyro``; a vehicle run in g
                  under m/s² headers through ``trajectory --acel`` and ``import``. Refused in
                  one line that names the likely unit (``says``)
``sensor_file``   ``sensor.json`` edited (N < 0, N = 1e6, rate 1e9 Hz, quantization 5 m/s²,
                  bias 1e6, a JSON list, one axis, a missing field, a bad checksum,
                  ``fit_ok`` false, …), with the checksum left stale or recomputed as a
                  forger would (docs/noise.md states the canonical form): refused by
                  ``generate calibration|static --sensor`` and ``gap --sensor`` in one line
                  naming the file and the field; the unedited profile, a forged in-range
                  edit and ``fit_ok`` false with ``--allow-failed-fit`` pass
``bad_bag``       ROS 1 / ROS 2 bags truncated, with bytes flipped (start, middle, end),
                  empty, a broken ``metadata.yaml``, a bag directory without its storage
                  file, two Imu topics and none chosen: one-line refusal naming the bag; bytes
                  flipped inside the messages (a bag has no checksum): refused, or the answer
                  right
``cell_count``    a row with one cell more or fewer (CSV, TSV, ``;``, gzip, phyphox zip,
                  Sensor Logger, a cut-off last line, a header with a name too many),
                  decimal commas in a comma-separated file: refused naming the line
``unit_suffix``   the family of unit suffixes of column names (``ax_m_s2``, ``ax_mps2``,
                  ``ax_g``, ``ax_mg``, ``ax_counts``, ``gx_deg_per_s``, ``gx_dps``,
                  ``gx_rad_s``, ``t_ms``, ``time_ns``, …) alone, with an agreeing option and
                  with a contradicting one: recognized or option-stated → read with the right
                  values (``noise --json`` means, gyro and rate; ``import`` → ``acel.mat``);
                  contradicting → what the docs say: ``--units`` / ``--time-unit`` refused,
                  ``--gyro-unit`` wins
``log_refusal``   the rest of docs/real-data.md's "What is refused" list: no header, unit not
                  stated, unknown unit text, a non-numeric / empty / NaN / Inf cell, time
                  not increasing, a gap, a saturated stretch, a damaged gzip, ``--poses``
                  whose count differs, θ in degrees without ``--angle-unit``, ``--rate`` on
                  a log with times, an empty ``--out``, a calibration in other units than
                  the log (``apply``); ``noise`` on several poses, a stuck axis, a carried
                  sensor, a gap (refused, or split at it and said so, with the log's answer)
``valid_log``     the named valid set (``expect="valid"``: a refusal is ``refused_valid``,
                  an answer off the truth ``silent_wrong``): the course files, a generated
                  vehicle run (imported, and through ``trajectory`` as CSV in m/s² and in g
                  against its truth), gains of ±5 %, counts with ``--sensitivity`` (CSV and
                  int16 ``.mat``), the real shipped logs (``data/real``) with the commands
                  their docs give, a phyphox zip, a Sensor Logger export under another
                  name, a nanosecond-stamped CSV with ``--time-unit ns``, ROS 1/2 bags, TSV,
                  ``;`` with decimal commas, gzip, ``--allow-gaps`` / ``--allow-saturation``
================  ===========================================================================

Inputs: :func:`build` writes them under ``base/front`` (signals from :mod:`.logfiles`,
seeded; a calibration, a sensor profile, an imported run and a generated course set made by
``tiltbench`` itself); the course files are read from ``../shared/course-data`` (copied only
into the case folders) and the real logs from ``data/real``.
"""

from __future__ import annotations

import copy
import hashlib
import json
import re
import shutil
from pathlib import Path

import numpy as np

from validation.fuzz import logfiles as lf
from validation.fuzz.runner import Case, Check, _json, end_check, mention_check, tiltbench

REPO = Path(__file__).resolve().parents[2]
COURSE_DATA = REPO.parent / "shared" / "course-data"
"""The course files (DESIGN.md: ``../shared/course-data``), read in place."""
REAL = REPO / "data" / "real"
"""The real shipped logs (``data/real/README.md``)."""

KIND_NAMES = ("unit_mistake", "sensor_file", "bad_bag", "cell_count", "unit_suffix",
              "log_refusal", "valid_log")

ANGLES = (0, 60, 120, 180, 240, 300)
POSES = ["--poses", ",".join(str(a) for a in ANGLES), "--angle-unit", "deg"]
SENS = 4096.0
"""Counts per g of the simulated raw logs (a 16-bit ±8 g part)."""
FACTOR = {"m/s2": 1.0, "g": 1.0 / lf.G_UNIT, "mg": 1000.0 / lf.G_UNIT,
          "counts": SENS / lf.G_UNIT}
"""m/s² → the file's numbers, per unit (g and mg with standard gravity, docs/real-data.md)."""
LABEL = {"m/s2": "m/s^2", "g": "g", "mg": "mg", "counts": "counts"}
ACC = ("ax", "ay", "az")
GYRO_RAD = ("gx (rad/s)", "gy (rad/s)", "gz (rad/s)")
GAINS = {"P95": (0.95, 0.95, 0.95), "P105": (1.05, 1.05, 1.05), "Pmix": (0.95, 1.05, 1.0)}
BIASES = {"P": (0.0, 0.0, 0.0), "P95": (0.0, 0.0, 0.0), "P105": (0.1, -0.05, 0.0),
          "Pmix": (-0.08, 0.06, 0.0)}


def _acc_head(unit: str | None) -> tuple[str, ...]:
    return tuple(f"{a} ({LABEL[unit]})" if unit else a for a in ACC)


def _sig(path: Path) -> lf.Signal:
    z = np.load(path)
    return lf.Signal(z["t"], z["acc"], z["gyro"], z["theta"], [])


# ================================================================ inputs
def build(base: Path, seed: int, env: dict, run=None) -> dict[str, Path]:
    """Write every input of the front-door kinds under ``base/front``; return
    ``{"fd.…": path}``. ``run(argv, cwd, env)`` runs a fixture-building ``tiltbench``
    command (default: a subprocess)."""
    run = run or tiltbench
    d = base / "front"
    d.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng([seed, 31])
    f: dict[str, Path] = {}
    sig = {"P": lf.poses(rng), "S": lf.still(rng)}
    for name, gain in GAINS.items():
        sig[name] = lf.poses(rng, gain=gain, bias=BIASES[name])
    sig["S105"] = lf.still(rng, gain=(1.05, 1.05, 1.05))
    sig["V"] = lf.vehicle(rng)
    sig["Pwide"] = lf.poses(rng, hold=200)  # for the gyro: θ from integration
    for name, s in sig.items():
        p = d / "signals" / f"{name}.npz"
        p.parent.mkdir(exist_ok=True)
        np.savez(p, t=s.t, acc=s.acc, gyro=s.gyro, theta=s.theta)
        f[f"fd.sig.{name}"] = p
    _unit_files(d / "units", sig, f)
    _cell_files(d / "cells", sig, f)
    _suffix_files(d / "suffix", sig, f)
    _refusal_files(d / "refuse", sig, f)
    _bag_files(d / "bags", sig, f)
    _valid_files(d / "valid", sig, f)
    _real_files(d / "real", f)
    _made_by_tiltbench(d / "made", f, seed, env, run)
    _profiles(d / "profiles", f)
    return f


def _csv(path: Path, s: lf.Signal, unit: str | None = "m/s2", numbers: str | None = None,
         gyro: bool = True, **kw) -> Path:
    """``s`` as a CSV: the numbers in ``numbers`` (default ``unit``), the header stating
    ``unit`` (None: no unit)."""
    numbers = numbers or unit or "m/s2"
    return lf.csv_log(path, s, acc_head=_acc_head(unit), gyro_head=GYRO_RAD if gyro else None,
                      acc_factor=FACTOR[numbers], counts=numbers == "counts", **kw)


def _removed(s: lf.Signal) -> lf.Signal:
    """``s`` with gravity removed (a "linear acceleration" export): ≈ 0 g at rest."""
    grav = np.c_[-lf.G_LOCAL * np.sin(s.theta), -lf.G_LOCAL * np.cos(s.theta),
                 np.zeros_like(s.t)]
    return lf.Signal(s.t, s.acc - grav, s.gyro, s.theta, s.holds)


UNIT_MISTAKES = [
    # name, the numbers' unit, the header's unit (None: none), options, what it must say
    ("g under (m/s^2)", "g", "m/s2", [], r"--units g\b"),
    ("m/s2 under (g)", "m/s2", "g", [], r"--units m/s2"),
    ("mg under (g)", "mg", "g", [], r"--units mg"),
    ("mg under (m/s^2)", "mg", "m/s2", [], r"--units mg"),
    ("g under (mg)", "g", "mg", [], r"--units g\b"),
    ("counts under (g)", "counts", "g", [], r"counts|--sensitivity"),
    ("counts under (m/s^2)", "counts", "m/s2", [], r"counts|--sensitivity"),
    ("counts without --sensitivity", "counts", "counts", [], r"--sensitivity"),
    ("counts with --sensitivity 1000 (4096 per g)", "counts", "counts",
     ["--sensitivity", "1000"], r"--sensitivity"),
    ("counts with --sensitivity 1 (4096 per g)", "counts", "counts", ["--sensitivity", "1"],
     r"--sensitivity"),
    ("m/s2 stated --units g", "m/s2", None, ["--units", "g"], r"--units m/s2"),
    ("g stated --units m/s2", "g", None, ["--units", "m/s2"], r"--units g\b"),
    ("mg stated --units g", "mg", None, ["--units", "g"], r"--units mg"),
    ("m/s2 stated --units mg", "m/s2", None, ["--units", "mg"], r"--units m/s2"),
    ("counts stated --units m/s2", "counts", None, ["--units", "m/s2"],
     r"counts|--sensitivity"),
    ("counts stated --units counts without --sensitivity", "counts", None,
     ["--units", "counts"], r"--sensitivity"),
    ("gravity removed under (m/s^2)", "removed", "m/s2", [], r"gravity|--units"),
]
"""The unit mistakes of a CSV log (the still log through ``noise``, the held-pose log through
``calibrate``, ``import``, ``apply``, ``gap``)."""


def _unit_files(d: Path, sig: dict, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    for k, (_, numbers, unit, _, _) in enumerate(UNIT_MISTAKES):
        for which in ("P", "S"):
            s = sig[which]
            if numbers == "removed":
                s, numbers_ = _removed(s), "m/s2"
            else:
                numbers_ = numbers
            f[f"fd.unit.{k}.{which}"] = _csv(d / f"m{k}_{which}.csv", s, unit, numbers_)
    for which in ("P", "S"):
        s = sig[which]
        f[f"fd.unit.phyphox_g.{which}"] = lf.phyphox_zip(
            d / f"phyphox_g_{which}.zip", lf.phyphox_text(s, acc_factor=FACTOR["g"]))
        f[f"fd.unit.phyphox_linear.{which}"] = lf.phyphox_zip(
            d / f"phyphox_linear_{which}.zip", lf.phyphox_text(_removed(s), linear=True))
        f[f"fd.unit.sl_g.{which}"] = lf.sensorlogger(d / f"sl_g_{which}.csv", s,
                                                     acc_factor=FACTOR["g"])
        f[f"fd.unit.sl_removed.{which}"] = lf.sensorlogger(d / f"sl_removed_{which}.csv",
                                                           _removed(s))
        f[f"fd.unit.ros1_g.{which}"] = lf.ros1_bag(d / f"ros1_g_{which}.bag", s,
                                                   acc_factor=FACTOR["g"])
        lf.ros2_bag(d / f"ros2_g_{which}", s, acc_factor=FACTOR["g"])
        f[f"fd.unit.ros2_g.{which}"] = d / f"ros2_g_{which}"
        f[f"fd.unit.mat_counts.{which}"] = lf.mat_log(d / f"counts_{which}.mat", s,
                                                      FACTOR["counts"], np.int16)
        f[f"fd.unit.mat_g.{which}"] = lf.mat_log(d / f"g_{which}.mat", s, FACTOR["g"])
    # a gyro in deg/s labelled rad/s (and the reverse) under --theta-source gyro
    s = sig["Pwide"]
    f["fd.unit.gyro_deg_as_rad"] = lf.csv_log(
        d / "gyro_deg_as_rad.csv", s, acc_head=_acc_head("m/s2"), gyro_head=GYRO_RAD,
        gyro_factor=180 / np.pi)
    f["fd.unit.gyro_ok"] = lf.csv_log(d / "gyro_ok.csv", s, acc_head=_acc_head("m/s2"),
                                      gyro_head=GYRO_RAD)
    f["fd.unit.gyro_rad_as_deg"] = lf.csv_log(
        d / "gyro_rad_as_deg.csv", s, acc_head=_acc_head("m/s2"),
        gyro_head=("gx (deg/s)", "gy (deg/s)", "gz (deg/s)"))


CELL_LINE = 100
"""The line (1-based, the header is line 1) that the cell-count edits break."""


def _cell_files(d: Path, sig: dict, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    for which in ("P", "S"):
        s = sig[which]
        head = ["t", *_acc_head("m/s2"), *GYRO_RAD]
        cols = [s.t, s.acc, s.gyro]
        text = lf.table_text(head, cols)
        last = len(text.splitlines())
        edits = {
            "more": (",", CELL_LINE, lambda ln: ln + ",1.5"),
            "fewer": (",", CELL_LINE, lambda ln: ln.rsplit(",", 1)[0]),
            "last_cut": (",", last, lambda ln: ",".join(ln.split(",")[:3])),
            "tsv_more": ("\t", CELL_LINE, lambda ln: ln + "\t1.5"),
            "semicolon_fewer": (";", CELL_LINE, lambda ln: ln.rsplit(";", 1)[0]),
        }
        for name, (sep, line, edit) in edits.items():
            t = lf.table_text(head, cols, sep=sep) if sep != "," else text
            ext = ".tsv" if sep == "\t" else ".csv"
            f[f"fd.cell.{name}.{which}"] = lf.write_text(d / f"{name}_{which}{ext}",
                                                         lf.edit_row(t, line, edit))
        f[f"fd.cell.gz_more.{which}"] = lf.write_text(
            d / f"gz_more_{which}.csv.gz", lf.edit_row(text, CELL_LINE, edits["more"][2]),
            gz=True)
        f[f"fd.cell.header_more.{which}"] = lf.write_text(
            d / f"header_more_{which}.csv", lf.edit_row(text, 1, lambda ln: ln + ",temp (C)"))
        f[f"fd.cell.decimal_comma.{which}"] = lf.write_text(
            d / f"decimal_comma_{which}.csv", lf.table_text(head, cols, decimal_comma=True))
        ph = lf.phyphox_text(s)
        f[f"fd.cell.phyphox_more.{which}"] = lf.phyphox_zip(
            d / f"phyphox_more_{which}.zip", lf.edit_row(ph, CELL_LINE, lambda ln: ln + ",0"))
        sl = lf.sensorlogger(d / f"tmp_{which}.csv", s)
        f[f"fd.cell.sl_fewer.{which}"] = lf.write_text(
            d / f"sl_fewer_{which}.csv",
            lf.edit_row(sl.read_text(), CELL_LINE, lambda ln: ln.rsplit(",", 1)[0]))
        sl.unlink()


SUFFIX_ACC = {"m_s2": "m/s2", "mps2": "m/s2", "m_per_s2": "m/s2", "ms2": "m/s2", "g": "g",
              "mg": "mg", "counts": "counts", "lsb": "counts"}
"""Acceleration unit suffixes of column names (docs/real-data.md, calib/logs/table.py's
table) and the unit each states."""
SUFFIX_GYRO = {"deg_per_s": "deg/s", "dps": "deg/s", "deg_s": "deg/s", "degps": "deg/s",
               "rad_per_s": "rad/s", "rad_s": "rad/s", "rads": "rad/s", "rps": "rad/s"}
SUFFIX_TIME = {"s": 1.0, "ms": 1e3, "us": 1e6, "ns": 1e9}
GYRO_FACTOR = {"rad/s": 1.0, "deg/s": 180.0 / np.pi}
NS_TOL = 1e-4
"""m/s²: how far ``import`` may move the readings of a log with nanosecond epoch stamps (read
as float64, their 10 ms steps jitter by ±128 ns and the log is resampled onto a uniform grid,
by linear interpolation: a few µm/s² here; far below any unit mistake)."""


def _suffix_files(d: Path, sig: dict, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    s = sig["S"]
    for suf, unit in SUFFIX_ACC.items():
        f[f"fd.suf.acc.{suf}"] = lf.csv_log(
            d / f"acc_{suf}.csv", s, acc_head=tuple(f"{a}_{suf}" for a in ACC),
            gyro_head=GYRO_RAD, acc_factor=FACTOR[unit], counts=unit == "counts")
    for suf, unit in SUFFIX_GYRO.items():
        f[f"fd.suf.gyro.{suf}"] = lf.csv_log(
            d / f"gyro_{suf}.csv", s, acc_head=_acc_head("m/s2"),
            gyro_head=tuple(f"{a}_{suf}" for a in ("gx", "gy", "gz")),
            gyro_factor=GYRO_FACTOR[unit])
    for suf, factor in SUFFIX_TIME.items():
        tv = s.t * factor if suf != "ns" else lf.ns_stamps(s.t)
        fmt = ".6f" if suf in ("s", "ms") else ".1f"
        f[f"fd.suf.time.{suf}"] = lf.csv_log(
            d / f"time_{suf}.csv", s, time_head=f"t_{suf}" if suf != "ns" else "time_ns",
            time_values=tv, acc_head=_acc_head("m/s2"), gyro_head=GYRO_RAD, time_fmt=fmt)
    # no unit anywhere (options state them), and unit texts not read by the readers
    f["fd.suf.bare"] = lf.csv_log(d / "bare.csv", s, acc_head=ACC,
                                  gyro_head=("gx", "gy", "gz"), time_head="time",
                                  time_values=s.t * 1e3, acc_factor=FACTOR["g"],
                                  gyro_factor=GYRO_FACTOR["deg/s"])
    f["fd.suf.furlongs"] = lf.csv_log(d / "furlongs.csv", s,
                                      acc_head=tuple(f"{a} (furlongs)" for a in ACC),
                                      gyro_head=tuple(f"{a} (furlongs)" for a in
                                                      ("gx", "gy", "gz")))
    f["fd.suf.brackets_g"] = lf.csv_log(d / "brackets_g.csv", s,
                                        acc_head=tuple(f"acc_{a} [g]" for a in "xyz"),
                                        gyro_head=tuple(f"gyro_{a} [deg/s]" for a in "xyz"),
                                        acc_factor=FACTOR["g"],
                                        gyro_factor=GYRO_FACTOR["deg/s"])


def _refusal_files(d: Path, sig: dict, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    for which in ("P", "S"):
        s = sig[which]
        head = ["t", *_acc_head("m/s2"), *GYRO_RAD]
        text = lf.table_text(head, [s.t, s.acc, s.gyro])
        lines = text.splitlines()

        def cell(line: int, col: int, value: str, lines=lines) -> str:
            out = list(lines)
            cells = out[line - 1].split(",")
            cells[col] = value
            out[line - 1] = ",".join(cells)
            return "\n".join(out) + "\n"

        L = CELL_LINE
        cases = {
            "no_header": "\n".join(lines[1:]) + "\n",
            "text_cell": cell(L, 2, "abc"),
            "empty_cell": cell(L, 2, ""),
            "nan_cell": cell(L, 1, "nan"),
            "inf_cell": cell(L, 3, "inf"),
            "time_back": cell(L, 0, "0.000000"),
            "time_repeat": cell(L, 0, lines[L - 2].split(",")[0]),
            "header_only": lines[0] + "\n",
            "empty": "",
        }
        for name, t in cases.items():
            f[f"fd.ref.{name}.{which}"] = lf.write_text(d / f"{name}_{which}.csv", t)
        # a gap of 2 s at line L (every later time shifted)
        tg = s.t.copy()
        tg[L - 2:] += 2.0
        f[f"fd.ref.gap.{which}"] = lf.csv_log(d / f"gap_{which}.csv", s, time_values=tg,
                                              acc_head=_acc_head("m/s2"), gyro_head=GYRO_RAD)
        # a saturated stretch: 30 samples of y in a hold at the column's extreme (≥ g/2 in
        # size), as a sensor clipping there reads (its readings shift by ~3 noise σ)
        acc = s.acc.copy()
        start = s.holds[3][0] + 100 if which == "P" else 500  # P: the 180° hold, y ≈ +g
        acc[start:start + 30, 1] = acc[:, 1].max() if which == "P" else acc[:, 1].min()
        f[f"fd.ref.saturated.{which}"] = lf.csv_log(
            d / f"saturated_{which}.csv", lf.Signal(s.t, acc, s.gyro, s.theta, s.holds),
            acc_head=_acc_head("m/s2"), gyro_head=GYRO_RAD)
        gz = lf.write_text(d / f"whole_{which}.csv.gz", text, gz=True)
        f[f"fd.ref.gz_truncated.{which}"] = lf.truncated(gz, d / f"gz_truncated_{which}.csv.gz")
        f[f"fd.ref.gz_flipped.{which}"] = lf.flipped(gz, d / f"gz_flipped_{which}.csv.gz",
                                                     count=16)
        gz.unlink()
    s = sig["S"]
    f["fd.ref.stuck"] = lf.csv_log(
        d / "stuck.csv", lf.Signal(s.t, np.c_[np.full(s.t.size, -2.0), s.acc[:, 1:]],
                                   s.gyro, s.theta, s.holds),
        acc_head=_acc_head("m/s2"), gyro_head=GYRO_RAD)
    carried = s.acc + np.c_[0.8 * np.sin(2 * np.pi * s.t / 7.0), 0.5 * np.cos(s.t), 0 * s.t]
    f["fd.ref.carried"] = lf.csv_log(d / "carried.csv",
                                     lf.Signal(s.t, carried, s.gyro, s.theta, s.holds),
                                     acc_head=_acc_head("m/s2"))
    # a θ column in degrees with no unit (and the held-pose readings that go with it)
    p = sig["P"]
    th = np.degrees(np.where(np.isnan(p.theta), 0.0, p.theta))
    f["fd.ref.theta_deg"] = lf.write_text(
        d / "theta_deg.csv",
        lf.table_text(["t", "theta", *_acc_head("m/s2")], [p.t, th, p.acc]))


def _bag_files(d: Path, sig: dict, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    for which in ("P", "S"):
        s = sig[which]
        bag = lf.ros1_bag(d / f"imu_{which}.bag", s)
        f[f"fd.bag.ros1.{which}"] = bag
        for name, where, fn in (("trunc50", 0.5, lf.truncated), ("trunc90", 0.9, lf.truncated),
                                ("trunc2", 0.02, lf.truncated), ("flip50", 0.5, lf.flipped),
                                ("flip25", 0.25, lf.flipped), ("flip95", 0.95, lf.flipped),
                                ("flip0", 0.0, lf.flipped)):
            f[f"fd.bag.ros1_{name}.{which}"] = fn(bag, d / f"{name}_{which}.bag", where)
        (d / f"empty_{which}.bag").write_bytes(b"")
        f[f"fd.bag.ros1_empty.{which}"] = d / f"empty_{which}.bag"
        files = lf.ros2_bag(d / f"imu2_{which}", s)
        db3 = next(p for n, p in files.items() if n.endswith(".db3"))
        meta = files["metadata.yaml"]
        f[f"fd.bag.ros2.{which}"] = db3.parent
        for name, fn, where in (("trunc50", lf.truncated, 0.5), ("flip50", lf.flipped, 0.5),
                                ("flip90", lf.flipped, 0.9), ("flip5", lf.flipped, 0.05)):
            out = d / f"ros2_{name}_{which}"
            out.mkdir(exist_ok=True)
            shutil.copy2(meta, out / "metadata.yaml")
            fn(db3, out / db3.name, where)
            f[f"fd.bag.ros2_{name}.{which}"] = out
        out = d / f"ros2_badmeta_{which}"
        out.mkdir(exist_ok=True)
        (out / "metadata.yaml").write_text(meta.read_text()[:200] + "\n: [unclosed\n")
        shutil.copy2(db3, out / db3.name)
        f[f"fd.bag.ros2_badmeta.{which}"] = out
        out = d / f"ros2_nodb_{which}"
        out.mkdir(exist_ok=True)
        shutil.copy2(meta, out / "metadata.yaml")
        f[f"fd.bag.ros2_nodb.{which}"] = out
    # two Imu topics, none chosen (refused, naming them); one chosen (valid)
    f["fd.bag.two_topics"] = _two_topic_bag(d / "two_topics.bag", sig["P"])


def _two_topic_bag(path: Path, s: lf.Signal) -> Path:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    if path.exists():
        path.unlink()
    with Writer(path) as w:
        conns = [w.add_connection(t, "sensor_msgs/msg/Imu", typestore=ts)
                 for t in ("/imu/left", "/imu/right")]
        for t, msg in lf._imu_messages(ts, s, 1.0):
            for c in conns:
                w.write(c, t, ts.serialize_ros1(msg, "sensor_msgs/msg/Imu"))
    return path


def _valid_files(d: Path, sig: dict, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    for name in GAINS:
        s = sig[name]
        f[f"fd.ok.{name}.ms2"] = _csv(d / f"{name}_ms2.csv", s)
        f[f"fd.ok.{name}.g"] = _csv(d / f"{name}_g.csv", s, "g")
        f[f"fd.ok.{name}.counts"] = _csv(d / f"{name}_counts.csv", s, "counts")
    s = sig["S105"]
    f["fd.ok.S105.ms2"] = _csv(d / "S105_ms2.csv", s)
    f["fd.ok.S105.g"] = _csv(d / "S105_g.csv", s, "g")
    for which in ("P", "S"):
        s = sig[which]
        f[f"fd.ok.{which}.ms2"] = _csv(d / f"{which}_ms2.csv", s)
        f[f"fd.ok.{which}.counts"] = _csv(d / f"{which}_counts.csv", s, "counts")
        f[f"fd.ok.{which}.bare_counts"] = _csv(d / f"{which}_bare_counts.csv", s, None,
                                               "counts")
        f[f"fd.ok.{which}.mat_counts"] = lf.mat_log(d / f"{which}_counts.mat", s,
                                                    FACTOR["counts"], np.int16)
        f[f"fd.ok.{which}.mat_ms2"] = lf.mat_log(d / f"{which}_ms2.mat", s)
        f[f"fd.ok.{which}.phyphox"] = lf.phyphox_zip(
            d / f"Acceleration with g 2026-01-01 {which}.zip", lf.phyphox_text(s))
        f[f"fd.ok.{which}.sensorlogger"] = lf.sensorlogger(d / f"my phone run {which}.csv", s)
        f[f"fd.ok.{which}.ns"] = lf.csv_log(
            d / f"{which}_ns.csv", s, time_head="time",
            time_values=lf.ns_stamps(s.t), acc_head=_acc_head("m/s2"),
            gyro_head=GYRO_RAD, time_fmt=".0f")
        f[f"fd.ok.{which}.tsv"] = _csv(d / f"{which}.tsv", s, sep="\t")
        f[f"fd.ok.{which}.semicolon_comma"] = _csv(d / f"{which}_semicolon.csv", s, sep=";",
                                                   decimal_comma=True)
        f[f"fd.ok.{which}.gz"] = _csv(d / f"{which}.csv.gz", s, gz=True)
    v = sig["V"]
    f["fd.ok.V.ms2"] = _csv(d / "vehicle_ms2.csv", v)
    f["fd.ok.V.g"] = _csv(d / "vehicle_g.csv", v, "g")


def _made_by_tiltbench(d: Path, f: dict, seed: int, env: dict, run) -> None:
    """A calibration (``calibrate --save``), a sensor profile (``noise --save`` with it),
    an imported run with times (for ``gap --sensor``), a calibration of the +5 % log, and a
    generated course set (a vehicle run with its truth)."""
    d.mkdir(parents=True, exist_ok=True)
    for name, src in (("P", f["fd.ok.P.ms2"]), ("P105", f["fd.ok.P105.ms2"])):
        shutil.copy2(src, d / f"{name}.csv")
        run(["calibrate", f"{name}.csv", "--save", f"cal_{name}.json", "--force"], d, env)
        f[f"fd.made.cal_{name}"] = d / f"cal_{name}.json"
    shutil.copy2(f["fd.ok.S.ms2"], d / "S.csv")
    run(["noise", "S.csv", "--calibration", "cal_P.json", "--save", "sensor.json", "--force"],
        d, env)
    f["fd.made.sensor"] = d / "sensor.json"
    run(["import", "P.csv", *POSES, "--out", "imp", "--force"], d, env)
    f["fd.made.imp_ensayo"] = d / "imp" / "ensayo.mat"
    course = d / "course"
    run(["generate", "course", "--seed", str(seed + 31), "--count", "2001", "--out",
         str(course), "--force"], d, env)
    for kind in ("ensayo", "acel", "puntos"):
        f[f"fd.made.course.{kind}"] = course / f"{kind}.mat"
    f["fd.made.course.datos"] = course / "datos.txt"
    f["fd.made.course.truth"] = course / "truth.json"
    import scipy.io

    a = scipy.io.loadmat(course / "acel.mat")
    t, acc = a["t"].ravel(), np.asarray(a["Aerr"], float)
    z = lf.G_LOCAL + np.random.default_rng([seed, 31, 1]).normal(0.0, 0.05, t.size)
    # the run as a CSV: x, y (and z, level: +g), numbers in one unit, the header in another
    for key, numbers, header, with_z in (("ms2", "m/s2", "m/s2", False),
                                         ("g", "g", "g", False),
                                         ("xyz_ms2", "m/s2", "m/s2", True),
                                         ("xyz_g", "g", "g", True),
                                         ("g_as_ms2", "g", "m/s2", False),
                                         ("xyz_g_as_ms2", "g", "m/s2", True)):
        names = ("ax", "ay", "az") if with_z else ("ax", "ay")
        cols = np.c_[acc, z] if with_z else acc
        text = lf.table_text(["t (s)", *(f"{c} ({LABEL[header]})" for c in names)],
                             [t, cols * FACTOR[numbers]], fmt=".9g")
        f[f"fd.made.course.acel_{key}"] = lf.write_text(d / f"course_acel_{key}.csv", text)


# ---------------------------------------------------------------- sensor profiles
def forge(doc: dict) -> dict:
    """``doc`` with its checksum recomputed as docs/noise.md states it: SHA-256 of the
    canonical JSON (keys sorted, no spaces, floats in their shortest round-trip form) of the
    fields ``checksum.covers`` lists — what a careful forger does after an edit."""
    covers = doc["checksum"]["covers"]
    part = {k: doc.get(k) for k in covers}
    text = json.dumps(part, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    doc["checksum"]["value"] = hashlib.sha256(text.encode("ascii")).hexdigest()
    return doc


def _set(path: str, value):
    """An edit setting the dotted ``path`` (list indices as numbers) to ``value``."""
    def edit(doc):
        keys = [int(k) if k.isdigit() else k for k in path.split(".")]
        obj = doc
        for k in keys[:-1]:
            obj = obj[k]
        obj[keys[-1]] = value
        return doc
    return edit


def _delete(path: str):
    def edit(doc):
        keys = path.split(".")
        obj = doc
        for k in keys[:-1]:
            obj = obj[k]
        del obj[keys[-1]]
        return doc
    return edit


def _negate_var(doc):
    doc["calibration"]["cov"][0][0] = -doc["calibration"]["cov"][0][0]
    return doc


def _scale_n(factor: float):
    def edit(doc):
        term = doc["axes"]["x"]["white_noise_density"]
        term["value"] *= factor
        return doc
    return edit


PROFILE_EDITS = [
    # name, edit, also forged (checksum recomputed), what the refusal must name
    ("N negative", _set("axes.x.white_noise_density.value", -0.002), True,
     r"white_noise_density"),
    ("N 1e6", _set("axes.x.white_noise_density.value", 1e6), True, r"white_noise_density"),
    ("N 1e6 with its interval", lambda d: _set("axes.x.white_noise_density.interval",
                                               [1e6, 1e6])(
        _set("axes.x.white_noise_density.value", 1e6)(d)), True, r"white_noise_density"),
    ("rate 1e9 Hz", _set("sample_rate", 1e9), True, r"sample_rate"),
    ("rate 0", _set("sample_rate", 0.0), True, r"sample_rate"),
    ("quantization 5 m/s2", _set("axes.x.quantization_step", 5.0), True,
     r"quantization_step"),
    ("gyro quantization 5 rad/s", _set("axes.gyro_z.quantization_step", 5.0), True,
     r"quantization_step"),
    ("calibration bias 1e6", _set("calibration.params.0", 1e6), True, r"calibration"),
    ("calibration gain 0", _set("calibration.params.1", -1.0), True, r"calibration|scale"),
    ("calibration negative variance", _negate_var, True, r"calibration|cov"),
    ("one axis", _delete("axes.y"), True, r"axes|\by\b"),
    ("missing fit", _delete("fit"), True, r"\bfit\b"),
    ("missing sample_rate", _delete("sample_rate"), True, r"sample_rate"),
    ("sample_rate as text", _set("sample_rate", "100"), True, r"sample_rate"),
    ("unknown field", _set("comment", "edited by hand"), True, r"comment"),
    ("term level differs", _set("axes.x.white_noise_density.level", 0.95), True, r"level"),
    ("fit_ok false", _set("axes.x.fit_ok", False), True, r"fit_ok|checksum"),
    ("format_version 1", _set("format_version", 1), True, r"format_version"),
    ("bad checksum", _set("checksum.value", "0" * 64), False, r"checksum"),
    ("in-range edit of N", _scale_n(1.001), False, r"checksum"),
]
"""Edits of ``sensor.json``: each with the checksum left stale, and (``True``) forged."""


def _profiles(d: Path, f: dict) -> None:
    d.mkdir(parents=True, exist_ok=True)
    good = json.loads(f["fd.made.sensor"].read_text())

    def save(name: str, obj) -> None:
        p = d / f"{name}.json"
        p.write_text(json.dumps(obj, indent=2) if not isinstance(obj, str) else obj)
        f[f"fd.prof.{name}"] = p

    for k, (_, edit, forged, _) in enumerate(PROFILE_EDITS):
        save(f"e{k}", edit(copy.deepcopy(good)))
        if forged:
            save(f"e{k}_forged", forge(edit(copy.deepcopy(good))))
    text = f["fd.made.sensor"].read_text()
    save("list", [good])
    save("truncated", text[: len(text) // 3])
    save("empty", "")
    n = good["axes"]["x"]["white_noise_density"]["value"]
    save("nan", text.replace(repr(n), "NaN", 1))
    save("forged_in_range", forge(_scale_n(1.001)(copy.deepcopy(good))))
    save("forged_fit_failed", forge(_set("axes.x.fit_ok", False)(copy.deepcopy(good))))


# ================================================================ truth checks
def calibration_check(truth: dict[str, float], floor=(0.01, 0.002), sigmas=6.0) -> Check:
    """``calibrate --json``: every parameter of ``truth`` (``bias_x``, ``scale_x``, …) within
    ``sigmas``·std + ``floor`` (bias m/s², scale) of its true value."""
    def check(code, out, err, root) -> str | None:
        est = calibration_params(_json(out))
        if est is None:
            return "no calibration parameters in the JSON answer"
        for name, true in truth.items():
            if name not in est:
                return f"no {name} in the answer"
            value, std = est[name]
            tol = sigmas * (std if np.isfinite(std) else 0.0) + floor[name.startswith("scale")]
            if not (np.isfinite(value) and abs(value - true) <= tol):
                return f"{name} = {value:.5g}, the truth {true:.5g} (tolerance {tol:.3g})"
        return None

    return check


def calibration_params(obj: dict | None) -> dict[str, tuple[float, float]] | None:
    """{name: (value, std)} of a ``calibrate --json`` answer: ``fit.param_names`` (θ unknown,
    six-face), or ``axes.<a>.bias|scale`` (θ known)."""
    if not obj:
        return None
    fit = obj.get("fit")
    if isinstance(fit, dict) and "param_names" in fit:
        std = fit.get("std") or [np.nan] * len(fit["params"])
        return {n: (float(v), float(s)) for n, v, s in
                zip(fit["param_names"], fit["params"], std, strict=False)}
    axes = obj.get("axes")
    if isinstance(axes, dict):
        out = {}
        for a, block in axes.items():
            if isinstance(block, dict) and "bias" in block:
                out[f"bias_{a}"] = (float(block["bias"]), float(block.get("bias_std", np.nan)))
                out[f"scale_{a}"] = (float(block["scale"]),
                                     float(block.get("scale_std", np.nan)))
        return out or None
    return None


def truth_params(gain, bias) -> dict[str, float]:
    return {"bias_x": bias[0], "scale_x": gain[0] - 1, "bias_y": bias[1],
            "scale_y": gain[1] - 1}


def noise_check(sig_path: Path, gyro_factor: float | None = 1.0,
                rate: float = lf.RATE, white: float | None = 0.02 / np.sqrt(lf.RATE)
                ) -> Check:
    """``noise --json``: the x, y means (m/s²) those of the logged signal (its gain
    included), the gyro z mean (rad/s) × ``gyro_factor`` (the factor an option that wins
    applies; None: not checked), the sample rate, and x's white-noise density ``white``
    ((m/s²)/√Hz, within 15 %; None: not checked)."""
    s = _sig(sig_path)
    mx, my = float(np.mean(s.acc[:, 0])), float(np.mean(s.acc[:, 1]))
    mg = float(np.mean(s.gyro[:, 2]))

    def check(code, out, err, root) -> str | None:
        obj = _json(out)
        try:
            axes = obj["axes"]
            got = {"x": axes["x"]["mean"], "y": axes["y"]["mean"], "rate": obj["sample_rate"]}
            if gyro_factor is not None:
                got["gyro_z"] = axes["gyro_z"]["mean"]
            n = axes["x"]["terms"]["white_noise_density"]["value"]
        except (KeyError, TypeError) as exc:
            return f"answer unreadable: {exc!r}"
        want = {"x": mx, "y": my, "rate": rate}
        if gyro_factor is not None:
            want["gyro_z"] = mg * gyro_factor
        for k, w in want.items():
            tol = 0.01 if k in ("x", "y") else 0.01 * abs(w)
            if not abs(float(got[k]) - w) <= tol:
                return f"{k} mean {float(got[k]):.6g}, the log's {w:.6g}"
        if white is not None and not (n is not None and abs(n / white - 1) < 0.15):
            return f"white noise density {n}, the log's {white:.3g} (m/s²)/√Hz"
        return None

    return check


def acel_check(sig_path: Path, tol: float, gyro_factor: float | None = 1.0,
               dt: float = 1.0 / lf.RATE, axes=(0, 1)) -> Check:
    """``import`` of a log without held poses → ``imp/acel.mat``: ``Aerr`` the log's
    ``axes`` in m/s² sample for sample (within ``tol``), ``gyro`` its z rate in rad/s ×
    ``gyro_factor`` (None: not checked), ``t`` stepping by ``dt``."""
    s = _sig(sig_path)

    def check(code, out, err, root) -> str | None:
        import scipy.io

        p = root / "imp" / "acel.mat"
        if not p.exists():
            return "no imp/acel.mat written"
        m = scipy.io.loadmat(p)
        a = np.asarray(m.get("Aerr"), float)
        want = s.acc[:, list(axes)]
        if a.shape != want.shape:
            return f"Aerr {a.shape}, the log {want.shape}"
        err_ = float(np.max(np.abs(a - want)))
        if not err_ <= tol:
            return f"Aerr off the log by up to {err_:.3g} m/s² (tolerance {tol:.2g})"
        if gyro_factor is not None:
            g = np.asarray(m.get("gyro"), float).ravel() if "gyro" in m else None
            if g is None or g.size != s.t.size:
                return "no gyro in acel.mat"
            ge = float(np.max(np.abs(g - s.gyro[:, 2] * gyro_factor)))
            if not ge <= 1e-4 * max(1.0, gyro_factor):
                return f"gyro off the log by up to {ge:.3g} rad/s"
        step = float(np.median(np.diff(np.asarray(m["t"], float).ravel())))
        if not abs(step / dt - 1) < 1e-6:
            return f"t steps by {step:.6g} s, the log by {dt:.6g} s"
        return None

    return check


def ensayo_check(gain, bias, theta_known: bool = True, noise: float = 0.02) -> Check:
    """``import`` of a held-pose log → ``imp/ensayo.mat``: with θ the readings fit
    ``gain·(−g sin θ, −g cos θ) + bias`` to within the noise; without θ each pose's mean is
    the true pose's, in the order of :data:`ANGLES`."""
    def check(code, out, err, root) -> str | None:
        import scipy.io

        p = root / "imp" / "ensayo.mat"
        if not p.exists():
            return "no imp/ensayo.mat written"
        m = scipy.io.loadmat(p)
        datos = np.asarray(m["datos"], float)
        if theta_known:
            th = np.asarray(m["tita"], float).ravel()
            model = np.c_[-lf.G_LOCAL * np.sin(th), -lf.G_LOCAL * np.cos(th)]
            r = datos - (model * np.asarray(gain[:2]) + np.asarray(bias[:2]))
            rms = float(np.sqrt(np.mean(r**2)))
            return None if rms < 3 * noise else f"datos off the model by {rms:.3g} m/s² rms"
        pose = np.asarray(m["pose"]).ravel()
        labels = [k for k in dict.fromkeys(pose.tolist()) if k >= 0]
        if len(labels) != len(ANGLES):
            return f"{len(labels)} poses, the log has {len(ANGLES)}"
        for k, lab in enumerate(labels):
            th = np.radians(ANGLES[k])
            want = np.array([-lf.G_LOCAL * np.sin(th), -lf.G_LOCAL * np.cos(th)])
            want = want * np.asarray(gain[:2]) + np.asarray(bias[:2])
            got = datos[pose == lab].mean(axis=0)
            if np.max(np.abs(got - want)) > 0.05:
                return f"pose {k} reads {got.round(3)}, held at {want.round(3)}"
        return None

    return check


def json_check(pred, what: str) -> Check:
    """Exit 0 with a JSON answer for which ``pred(obj)`` holds (``what`` names it)."""
    def check(code, out, err, root) -> str | None:
        obj = _json(out)
        try:
            ok = obj is not None and bool(pred(obj))
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            return f"answer unreadable ({what}): {exc!r}"
        return None if ok else f"answer not {what}"

    return check


def files_check(*names: str) -> Check:
    def check(code, out, err, root) -> str | None:
        missing = [n for n in names if not (root / n).exists()]
        return f"not written: {', '.join(missing)}" if missing else None

    return check


def both(*checks: Check) -> Check:
    """The first reason any of ``checks`` gives, or None."""
    def check(code, out, err, root) -> str | None:
        return next((why for c in checks if (why := c(code, out, err, root))), None)

    return check


# ================================================================ cases
def _bag_files_of(f: dict, key: str, name: str) -> dict[str, Path]:
    """The files of a bag fixture ``f[key]`` in a case folder as ``name`` (a ROS 2 bag is a
    directory: its files under ``name/``)."""
    src = f[key]
    if src.is_dir():
        return {f"{name}/{p.name}": p for p in sorted(src.iterdir())}
    return {name: src}


def unit_mistakes(f: dict) -> list[Case]:
    """Every unit mistake on every reader and log command (module docstring)."""
    cases: list[Case] = []
    cal = {"cal.json": f["fd.made.cal_P"]}

    def three(label: str, p_files: dict, s_files: dict, log: str, still: str, opts: list,
              says: str, extra: bool = False) -> None:
        cases.append(Case("unit_mistake", f"noise: {label}",
                          ["noise", still, *opts, "--json"], s_files, expect="refuse", says=says))
        cases.append(Case("unit_mistake", f"calibrate: {label}",
                          ["calibrate", log, *opts, "--json"], p_files,
                          expect="refuse", says=says))
        cases.append(Case("unit_mistake", f"import: {label}",
                          ["import", log, *opts, "--out", "imp", "--json"], p_files,
                          expect="refuse", says=says))
        if extra:
            cases.append(Case("unit_mistake", f"apply: {label}",
                              ["apply", log, "--calibration", "cal.json", *opts, "--out",
                               "corrected.csv"], {**p_files, **cal}, expect="refuse", says=says))
            cases.append(Case("unit_mistake", f"gap: {label}",
                              ["gap", log, *POSES, *opts, "--json"], p_files,
                              expect="refuse", says=says))

    for k, (label, _, _, opts, says) in enumerate(UNIT_MISTAKES):
        three(f"CSV {label}", {"log.csv": f[f"fd.unit.{k}.P"]},
              {"still.csv": f[f"fd.unit.{k}.S"]}, "log.csv", "still.csv", opts, says,
              extra=k in (0, 1, 2, 7, 16))
    g = r"--units g\b"
    gone = r"gravity (was )?removed"
    three("phyphox zip in g", {"run.zip": f["fd.unit.phyphox_g.P"]},
          {"still.zip": f["fd.unit.phyphox_g.S"]}, "run.zip", "still.zip", [], g)
    three("phyphox zip Linear Acceleration", {"run.zip": f["fd.unit.phyphox_linear.P"]},
          {"still.zip": f["fd.unit.phyphox_linear.S"]}, "run.zip", "still.zip", [], gone)
    three("Sensor Logger in g (renamed)", {"phone.csv": f["fd.unit.sl_g.P"]},
          {"still.csv": f["fd.unit.sl_g.S"]}, "phone.csv", "still.csv", [], g)
    three("Sensor Logger gravity removed (renamed)", {"phone.csv": f["fd.unit.sl_removed.P"]},
          {"still.csv": f["fd.unit.sl_removed.S"]}, "phone.csv", "still.csv", [], gone)
    three("ROS 1 bag in g", {"imu.bag": f["fd.unit.ros1_g.P"]},
          {"still.bag": f["fd.unit.ros1_g.S"]}, "imu.bag", "still.bag", [], r"\bg\b")
    three("ROS 2 bag in g", _bag_files_of(f, "fd.unit.ros2_g.P", "bag"),
          _bag_files_of(f, "fd.unit.ros2_g.S", "bag"), "bag", "bag", [], r"\bg\b")
    mp = ["--map", "datos=acc,t=time"]
    three(".mat int16 counts through --map", {"log.mat": f["fd.unit.mat_counts.P"]},
          {"still.mat": f["fd.unit.mat_counts.S"]}, "log.mat", "still.mat", mp,
          r"counts|--sensitivity")
    three(".mat int16 counts --units counts without --sensitivity",
          {"log.mat": f["fd.unit.mat_counts.P"]}, {"still.mat": f["fd.unit.mat_counts.S"]},
          "log.mat", "still.mat", [*mp, "--units", "counts"], r"--sensitivity")
    three(".mat int16 counts --sensitivity 1000 (4096 per g)",
          {"log.mat": f["fd.unit.mat_counts.P"]}, {"still.mat": f["fd.unit.mat_counts.S"]},
          "log.mat", "still.mat", [*mp, "--units", "counts", "--sensitivity", "1000"],
          r"--sensitivity")
    three(".mat in g through --map", {"log.mat": f["fd.unit.mat_g.P"]},
          {"still.mat": f["fd.unit.mat_g.S"]}, "log.mat", "still.mat", mp, g)
    # a vehicle run in g under (m/s^2) headers: with z (level, +g) the 1 g check sees it
    course = {"ensayo.mat": f["fd.made.course.ensayo"], "puntos.mat": f["fd.made.course.puntos"],
              "datos.txt": f["fd.made.course.datos"]}
    traj = ["trajectory", "--ensayo", "ensayo.mat", "--acel", "acel.csv", "--puntos",
            "puntos.mat", "--datos", "datos.txt", "--json"]
    xyz = {"acel.csv": f["fd.made.course.acel_xyz_g_as_ms2"]}
    cases.append(Case("unit_mistake", "trajectory: vehicle run (x, y, z) in g under (m/s^2)",
                      traj, {**course, **xyz}, expect="refuse", says=g))
    cases.append(Case("unit_mistake", "import: vehicle run (x, y, z) in g under (m/s^2)",
                      ["import", "acel.csv", "--out", "imp", "--json"], xyz, expect="refuse",
                      says=g))
    # x, y alone: nothing in the run can tell g from m/s² (the issue exempts vehicle runs
    # from the 1 g check; docs/real-data.md says so): run, its answer not graded
    cases.append(Case("unit_mistake", "trajectory: vehicle run (x, y) in g under (m/s^2), "
                      "cannot be told", traj,
                      {**course, "acel.csv": f["fd.made.course.acel_g_as_ms2"]},
                      expect="any"))
    # the gyro in the wrong unit: θ from the gyro cannot close between the holds
    gyro = ["--theta-source", "gyro", *POSES]
    for name, key, opts in (("gyro in deg/s under (rad/s)", "fd.unit.gyro_deg_as_rad", []),
                            ("gyro in rad/s under (deg/s)", "fd.unit.gyro_rad_as_deg", []),
                            ("gyro in rad/s under (rad/s) stated --gyro-unit deg/s (wins)",
                             "fd.unit.gyro_ok", ["--gyro-unit", "deg/s"])):
        files = {"log.csv": f[key]}
        for cmd in ("calibrate", "import"):
            out = ["--out", "imp"] if cmd == "import" else []
            cases.append(Case("unit_mistake", f"{cmd}: {name}, θ from the gyro",
                              [cmd, "log.csv", *gyro, *opts, *out, "--json"], files,
                              expect="refuse", says=r"--gyro-unit"))
    return cases


def sensor_files(f: dict) -> list[Case]:
    """Edited ``sensor.json`` through ``generate calibration|static --sensor`` and
    ``gap --sensor`` (module docstring)."""
    gen_cal = ["generate", "calibration", "--sensor", "sensor.json", "--positions", "4",
               "--per-position", "100", "--seed", "1", "--out", "twin", "--json"]
    gen_static = ["generate", "static", "--sensor", "sensor.json", "--duration", "10",
                  "--seed", "1", "--out", "twin", "--json"]
    gap = ["gap", "ensayo.mat", "--sensor", "sensor.json", "--json"]
    commands = {"generate calibration": gen_cal, "generate static": gen_static, "gap": gap}
    ens = {"ensayo.mat": f["fd.made.imp_ensayo"]}
    cases: list[Case] = []

    def each(label: str, prof: Path, expect: str, says: str | None, extra=(),
             check: Check | None = None, which=tuple(commands)) -> None:
        for cmd in which:
            argv = commands[cmd]
            files = {"sensor.json": prof, **(ens if cmd == "gap" else {})}
            cases.append(Case("sensor_file", f"{cmd} --sensor: {label}", [*argv, *extra],
                              files, expect=expect, check=check,
                              says=None if says is None else rf"sensor\.json.*({says})"))

    for k, (label, _, forged, says) in enumerate(PROFILE_EDITS):
        each(f"{label} (checksum stale)", f[f"fd.prof.e{k}"], "refuse", says)
        if forged:  # the checksum holds: the field itself must be named
            each(f"{label} (checksum forged)", f[f"fd.prof.e{k}_forged"], "refuse",
                 says.replace("|checksum", ""))
    for name, label in (("list", "a JSON list"), ("truncated", "truncated"),
                        ("empty", "an empty file"), ("nan", "NaN for N")):
        each(label, f[f"fd.prof.{name}"], "refuse", r".")
    ok = json_check(lambda o: "files" in o or "verdict" in o, "a run or a verdict")
    each("as written (control)", f["fd.made.sensor"], "valid", None, check=ok)
    each("in-range edit, checksum forged (cannot be told)", f["fd.prof.forged_in_range"],
         "valid", None, check=ok)
    each("fit_ok false, forged, with --allow-failed-fit", f["fd.prof.forged_fit_failed"],
         "valid", None, extra=["--allow-failed-fit"], check=ok)
    return cases


def bad_bags(f: dict) -> list[Case]:
    """Damaged ROS bags through ``calibrate``, ``import`` and ``noise``."""
    cases: list[Case] = []
    tp = truth_params((1, 1, 1), (0, 0, 0))
    names = {"ros1_trunc50": "truncated at 50 %", "ros1_trunc90": "truncated at 90 %",
             "ros1_trunc2": "truncated at 2 %", "ros1_flip50": "64 bytes flipped at 50 %",
             "ros1_flip25": "64 bytes flipped at 25 %",
             "ros1_flip95": "64 bytes flipped at 95 %",
             "ros1_flip0": "its first 64 bytes flipped", "ros1_empty": "empty",
             "ros2_trunc50": "storage truncated at 50 %",
             "ros2_flip50": "storage with 64 bytes flipped at 50 %",
             "ros2_flip90": "storage with 64 bytes flipped at 90 %",
             "ros2_flip5": "storage with 64 bytes flipped at 5 %",
             "ros2_badmeta": "metadata.yaml broken", "ros2_nodb": "no storage file"}
    for key, label in names.items():
        ros = "ROS 1" if key.startswith("ros1") else "ROS 2"
        name = "imu.bag" if ros == "ROS 1" else "bag"
        pf = _bag_files_of(f, f"fd.bag.{key}.P", name)
        sf = _bag_files_of(f, f"fd.bag.{key}.S", name)
        if "flip" in key and key != "ros1_flip0":
            # bytes flipped inside the messages: a bag has no checksum, so a flipped float
            # can read as another number (rosbags decodes it): refused, or the answer right
            kw = [{"expect": "any", "check": calibration_check(tp)},
                  {"expect": "any", "check": ensayo_check((1, 1, 1), (0, 0, 0), False)},
                  {"expect": "any", "check": noise_check(f["fd.sig.S"])}]
        else:  # not readable as a bag: refused as such, naming the file
            says = re.escape(name) + r".*(ROS bag|log format)"
            kw = [{"expect": "refuse", "says": says}] * 3
        cases.append(Case("bad_bag", f"calibrate: {ros} bag {label}",
                          ["calibrate", name, "--json"], pf, **kw[0]))
        cases.append(Case("bad_bag", f"import: {ros} bag {label}",
                          ["import", name, "--out", "imp", "--json"], pf, **kw[1]))
        cases.append(Case("bad_bag", f"noise: {ros} still bag {label}",
                          ["noise", name, "--json"], sf, **kw[2]))
    cases.append(Case("bad_bag", "calibrate: two Imu topics, none chosen",
                      ["calibrate", "imu.bag", "--json"], {"imu.bag": f["fd.bag.two_topics"]},
                      expect="refuse", says=r"/imu/left.*/imu/right.*--columns topic"))
    return cases


def cell_counts(f: dict) -> list[Case]:
    """Rows with a cell more or fewer, decimal commas in a comma-separated file: refused,
    naming the line."""
    cases: list[Case] = []
    n_lines = {w: sum(1 for _ in f[f"fd.cell.last_cut.{w}"].open()) for w in ("P", "S")}
    table = [("more", "one cell more on line 100", "log.csv", CELL_LINE),
             ("fewer", "one cell fewer on line 100", "log.csv", CELL_LINE),
             ("last_cut", "the last line cut off", "log.csv", None),
             ("tsv_more", "TSV, one cell more on line 100", "log.tsv", CELL_LINE),
             ("semicolon_fewer", "';', one cell fewer on line 100", "log.csv", CELL_LINE),
             ("gz_more", "gzip, one cell more on line 100", "log.csv.gz", CELL_LINE),
             ("header_more", "a header with one name more", "log.csv", 2),
             ("decimal_comma", "decimal commas, comma-separated", "log.csv", 2),
             ("phyphox_more", "phyphox zip, one cell more on line 100", "run.zip", CELL_LINE),
             ("sl_fewer", "Sensor Logger, one cell fewer on line 100", "phone.csv",
              CELL_LINE)]
    for key, label, name, line in table:
        for cmd, which in (("calibrate", "P"), ("import", "P"), ("noise", "S")):
            ln = line if line is not None else n_lines[which]
            out = ["--out", "imp"] if cmd == "import" else []
            says = rf"line {ln}\b"
            if key == "phyphox_more":
                says = rf"Accelerometer\.csv.*line {ln}\b"
            cases.append(Case("cell_count", f"{cmd}: {label}", [cmd, name, *out, "--json"],
                              {name: f[f"fd.cell.{key}.{which}"]}, expect="refuse",
                              says=says))
    for key in ("more", "fewer"):  # the other commands that read a log
        log = {"log.csv": f[f"fd.cell.{key}.P"]}
        label = dict((k, lab) for k, lab, _, _ in table)[key]
        cases.append(Case("cell_count", f"apply: {label}",
                          ["apply", "log.csv", "--calibration", "cal.json", "--out",
                           "corrected.csv"], {**log, "cal.json": f["fd.made.cal_P"]},
                          expect="refuse", says=rf"line {CELL_LINE}\b"))
        cases.append(Case("cell_count", f"gap: {label}", ["gap", "log.csv", *POSES, "--json"],
                          log, expect="refuse", says=rf"line {CELL_LINE}\b"))
    return cases


def unit_suffixes(f: dict) -> list[Case]:
    """The family of unit suffixes, alone, with an agreeing option and a contradicting one
    (module docstring). Values checked through ``noise --json`` and ``import``."""
    cases: list[Case] = []
    sig = f["fd.sig.S"]

    def noise_case(label, file, opts, expect, check=None, says=None):
        cases.append(Case("unit_suffix", f"noise: {label}", ["noise", "log.csv", *opts,
                                                               "--json"],
                          {"log.csv": file}, expect=expect, check=check, says=says))

    def import_case(label, file, opts, check):
        cases.append(Case("unit_suffix", f"import: {label}",
                          ["import", "log.csv", *opts, "--out", "imp", "--json"],
                          {"log.csv": file}, expect="valid", check=check))

    other = {"m/s2": "g", "g": "m/s2", "mg": "g", "counts": "m/s2"}
    for suf, unit in SUFFIX_ACC.items():
        file = f[f"fd.suf.acc.{suf}"]
        sens = ["--sensitivity", str(SENS)] if unit == "counts" else []
        tol = 0.6 / FACTOR["counts"] if unit == "counts" else 2e-6 / FACTOR[unit] + 1e-6
        noise_case(f"ax_{suf}", file, sens, "valid", noise_check(sig))
        noise_case(f"ax_{suf} --units {unit}", file, ["--units", unit, *sens], "valid",
                   noise_check(sig))
        noise_case(f"ax_{suf} --units {other[unit]} (contradicts)", file,
                   ["--units", other[unit], *sens], "refuse",
                   says=rf"{re.escape(unit)}.*--units|--units.*{re.escape(unit)}")
        import_case(f"ax_{suf}", file, sens, acel_check(sig, tol))
    for suf, unit in SUFFIX_GYRO.items():
        file = f[f"fd.suf.gyro.{suf}"]
        wrong = "rad/s" if unit == "deg/s" else "deg/s"
        noise_case(f"gx_{suf}", file, [], "valid", noise_check(sig))
        noise_case(f"gx_{suf} --gyro-unit {unit}", file, ["--gyro-unit", unit], "valid",
                   noise_check(sig))
        # docs/real-data.md: --gyro-unit "(given, it wins)": the numbers are read in its unit
        # (deg/s numbers read as rad/s: 1.15 rad/s, no longer still: refused by noise)
        factor = GYRO_FACTOR[unit] / GYRO_FACTOR[wrong]
        noise_case(f"gx_{suf} --gyro-unit {wrong} (contradicts: the option wins)", file,
                   ["--gyro-unit", wrong], "any" if unit == "deg/s" else "valid",
                   noise_check(sig, gyro_factor=factor), says=r"gyro")
        import_case(f"gx_{suf}", file, [], acel_check(sig, 2e-6))
    time_unit = {"s": "s", "ms": "ms", "us": "us", "ns": "ns"}
    for suf, unit in time_unit.items():
        file = f[f"fd.suf.time.{suf}"]
        head = "time_ns" if suf == "ns" else f"t_{suf}"
        wrong = "s" if unit != "s" else "ms"
        noise_case(head, file, [], "valid", noise_check(sig))
        noise_case(f"{head} --time-unit {unit}", file, ["--time-unit", unit], "valid",
                   noise_check(sig))
        noise_case(f"{head} --time-unit {wrong} (contradicts)", file, ["--time-unit", wrong],
                   "refuse", says=r"--time-unit")
        # ns stamps since the epoch: the reader resamples them (float64 steps jitter by
        # ±128 ns), moving the readings by a few µm/s²: allowed, reported
        import_case(head, file, [], acel_check(sig, NS_TOL if suf == "ns" else 2e-6))
    bare = f["fd.suf.bare"]
    stated = ["--units", "g", "--gyro-unit", "deg/s", "--time-unit", "ms"]
    noise_case("no unit in the header, all stated by options", bare, stated, "valid",
               noise_check(sig))
    import_case("no unit in the header, all stated by options", bare, stated,
                acel_check(sig, 2e-6 / FACTOR["g"] + 1e-6, gyro_factor=1.0))
    noise_case("no unit in the header, none stated", bare, [], "refuse", says=r"--units")
    fur = f["fd.suf.furlongs"]
    noise_case("a unit text not read (furlongs)", fur, [], "refuse", says=r"--units")
    noise_case("a unit text not read (furlongs), stated by options", fur,
               ["--units", "m/s2", "--gyro-unit", "rad/s"], "valid", noise_check(sig))
    br = f["fd.suf.brackets_g"]
    noise_case("acc_x [g], gyro_x [deg/s]", br, [], "valid", noise_check(sig))
    import_case("acc_x [g], gyro_x [deg/s]", br, [],
                acel_check(sig, 2e-6 / FACTOR["g"] + 1e-6))
    return cases


def log_refusals(f: dict) -> list[Case]:
    """docs/real-data.md's "What is refused", item by item, through ``calibrate``,
    ``import`` and ``noise``."""
    cases: list[Case] = []
    L = CELL_LINE
    rows = [("no_header", "no header", r"header"),
            ("text_cell", "a text cell on line 100", rf"line {L}\b"),
            ("empty_cell", "an empty cell on line 100", rf"line {L}\b"),
            ("nan_cell", "NaN on line 100", rf"line {L}\b"),
            ("inf_cell", "Inf on line 100", rf"line {L}\b"),
            ("time_back", "time going back on line 100", rf"line {L}\b"),
            ("time_repeat", "time repeated on line 100", rf"line {L}\b"),
            ("gap", "a 2 s gap before line 100", rf"line {L - 1}\b.*--allow-gaps"),
            ("saturated", "30 samples at the extreme of y", r"--allow-saturation"),
            ("gz_truncated", "a truncated gzip file", r"gzip|damaged|compressed|truncated"),
            ("gz_flipped", "a damaged gzip file", r"gzip|damaged|compressed|CRC"),
            ("header_only", "a header and no rows", r"log\.csv"),
            ("empty", "an empty file", r"log\.csv")]
    for key, label, says in rows:
        for cmd, which in (("calibrate", "P"), ("import", "P"), ("noise", "S")):
            name = "log.csv.gz" if key.startswith("gz_") else "log.csv"
            out = ["--out", "imp"] if cmd == "import" else []
            kw = {"expect": "refuse"}
            if key == "gap" and cmd == "noise":
                # noise may split a log at its gaps (pooling the Allan variance over the
                # segments) instead of refusing it: then it says so and the answer is the log's
                kw = {"expect": "any", "check": both(noise_check(f["fd.sig.S"]),
                                                     mention_check(r"gap", "the gap"))}
            cases.append(Case("log_refusal", f"{cmd}: {label}", [cmd, name, *out, "--json"],
                              {name: f[f"fd.ref.{key}.{which}"]}, says=says, **kw))
    plog = {"log.csv": f["fd.ok.P.ms2"]}
    slog = {"log.csv": f["fd.ok.S.ms2"]}
    more = [
        ("calibrate: --poses with 5 angles for 6 poses",
         ["calibrate", "log.csv", "--poses", "0,60,120,180,240", "--angle-unit", "deg"],
         plog, r"--poses|poses"),
        ("import: --poses with 7 angles for 6 poses",
         ["import", "log.csv", "--poses", "0,60,120,180,240,300,30", "--angle-unit", "deg",
          "--out", "imp"], plog, r"--poses|poses"),
        ("import: --rate on a log with times", ["import", "log.csv", "--rate", "100",
                                                "--out", "imp"], plog, r"--rate"),
        ("import: an empty --out", ["import", "log.csv", "--out", ""], plog, r"--out"),
        ("calibrate: a θ column in degrees without --angle-unit",
         ["calibrate", "log.csv", "--json"], {"log.csv": f["fd.ref.theta_deg"]},
         r"--angle-unit deg"),
        ("import: a θ column in degrees without --angle-unit",
         ["import", "log.csv", "--out", "imp", "--json"], {"log.csv": f["fd.ref.theta_deg"]},
         r"--angle-unit deg"),
        ("noise: a log of six poses", ["noise", "log.csv", "--json"], plog,
         r"pose|still|held"),
        ("noise: a stuck axis x", ["noise", "log.csv", "--json"],
         {"log.csv": f["fd.ref.stuck"]}, r"\bx\b"),
        ("noise: a carried sensor (not still)", ["noise", "log.csv", "--json"],
         {"log.csv": f["fd.ref.carried"]}, r"\bx\b|\by\b"),
        ("import: a still log with a gap, --allow-gaps (acel.mat never filled)",
         ["import", "log.csv", "--allow-gaps", "--out", "imp", "--json"],
         {"log.csv": f["fd.ref.gap.S"]}, r"gap"),
        ("apply: a cal.json fitted in m/s² to the log in g (DESIGN: units must match)",
         ["apply", "log.csv", "--calibration", "cal.json", "--out", "corrected.csv"],
         {"log.csv": f["fd.ok.P105.g"], "cal.json": f["fd.made.cal_P105"]},
         r"cal\.json.*\bg\b"),
    ]
    for label, argv, files, says in more:
        cases.append(Case("log_refusal", label, argv, files, expect="refuse", says=says))
    cases.append(Case("log_refusal", "noise: a gap, with --allow-gaps",
                      ["noise", "log.csv", "--allow-gaps", "--json"],
                      {"log.csv": f["fd.ref.gap.S"]}, expect="any", says=r"gap",
                      check=both(noise_check(f["fd.sig.S"]), mention_check(r"gap", "the gap"))))
    # an option that does not apply is not a refusal; the answer must stay right
    cases.append(Case("log_refusal", "noise: --sensitivity on a log in m/s² (unused)",
                      ["noise", "log.csv", "--sensitivity", "4096", "--json"], slog,
                      expect="any", check=noise_check(f["fd.sig.S"])))
    return cases


def valid_logs(f: dict) -> list[Case]:
    """The named valid set: each must run (exit 0) and give the answer its truth says."""
    cases: list[Case] = []

    def ok(name, argv, files, check=None):
        cases.append(Case("valid_log", name, argv, files, expect="valid", check=check))

    # the course files, read in place (copied into the case folder only)
    if COURSE_DATA.is_dir():
        c = {n: COURSE_DATA / n for n in ("ensayo.mat", "acel.mat", "puntos.mat", "datos.txt")}
        answer = {"scale_x": -0.0301, "bias_x": 0.0767, "scale_y": 0.0100, "bias_y": -0.0175}
        ok("course: calibrate ensayo.mat --datos (the course answer)",
           ["calibrate", "ensayo.mat", "--datos", "datos.txt", "--json"], c,
           calibration_check(answer, floor=(5e-4, 1e-4), sigmas=0.0))
        ok("course: gap ensayo.mat --datos", ["gap", "ensayo.mat", "--datos", "datos.txt",
                                              "--json"], c,
           json_check(lambda o: o["verdict"] in ("nothing_detected", "explained",
                                                 "unexplained"), "a verdict"))
        ok("course: import ensayo.mat", ["import", "ensayo.mat", "--out", "imp", "--json"], c,
           files_check("imp/ensayo.mat", "imp/provenance.json"))
        ok("course: import acel.mat", ["import", "acel.mat", "--out", "imp", "--json"], c,
           files_check("imp/acel.mat", "imp/provenance.json"))
        ok("course: trajectory", ["trajectory", "--ensayo", "ensayo.mat", "--acel", "acel.mat",
                                  "--puntos", "puntos.mat", "--datos", "datos.txt",
                                  "--json"], c,
           json_check(lambda o: np.all(np.isfinite(o["final_corrected"])), "a finite end"))
    # a generated vehicle run: imported, and through trajectory as a CSV against its truth
    course = {"ensayo.mat": f["fd.made.course.ensayo"], "puntos.mat": f["fd.made.course.puntos"],
              "datos.txt": f["fd.made.course.datos"]}
    truth = f["fd.made.course.truth"]
    for key, label in (("acel_ms2", "m/s²"), ("acel_g", "g"), ("acel_xyz_ms2", "m/s², 3 axes"),
                       ("acel_xyz_g", "g, 3 axes")):
        ok(f"vehicle run: trajectory --acel a CSV in {label} (its truth)",
           ["trajectory", "--ensayo", "ensayo.mat", "--acel", "acel.csv", "--puntos",
            "puntos.mat", "--datos", "datos.txt", "--json"],
           {**course, "acel.csv": f[f"fd.made.course.{key}"]}, end_check(truth, "trajectory"))
    ok("vehicle run: trajectory --acel acel.mat (its truth)",
       ["trajectory", "--ensayo", "ensayo.mat", "--acel", "acel.mat", "--puntos", "puntos.mat",
        "--datos", "datos.txt", "--json"], {**course, "acel.mat": f["fd.made.course.acel"]},
       end_check(truth, "trajectory"))
    ok("vehicle run: import acel.mat", ["import", "acel.mat", "--out", "imp", "--json"],
       {"acel.mat": f["fd.made.course.acel"]}, files_check("imp/acel.mat"))
    v = f["fd.sig.V"]
    ok("vehicle run: import a 3-axis CSV in m/s²", ["import", "log.csv", "--out", "imp",
                                                    "--json"],
       {"log.csv": f["fd.ok.V.ms2"]}, acel_check(v, 2e-6))
    ok("vehicle run: import a 3-axis CSV in g", ["import", "log.csv", "--out", "imp",
                                                 "--json"],
       {"log.csv": f["fd.ok.V.g"]}, acel_check(v, 2e-6 / FACTOR["g"] + 1e-6))
    # gains of ±5 %, in m/s², g and counts with --sensitivity
    sens = ["--sensitivity", str(SENS)]
    for name, gain in GAINS.items():
        truth_p = truth_params(gain, BIASES[name])
        floor = (0.01, 0.002)
        for unit, opts in (("ms2", []), ("g", []), ("counts", sens)):
            ok(f"gain {gain[:2]}: calibrate a CSV in {unit}",
               ["calibrate", "log.csv", *opts, "--json"], {"log.csv": f[f"fd.ok.{name}.{unit}"]},
               calibration_check(truth_p, floor))
        ok(f"gain {gain[:2]}: calibrate --poses (θ known)",
           ["calibrate", "log.csv", *POSES, "--json"], {"log.csv": f[f"fd.ok.{name}.g"]},
           calibration_check(truth_p, floor))
        ok(f"gain {gain[:2]}: import --poses", ["import", "log.csv", *POSES, "--out", "imp",
                                                 "--json"],
           {"log.csv": f[f"fd.ok.{name}.g"]}, ensayo_check(gain, BIASES[name]))
        ok(f"gain {gain[:2]}: import (θ unknown)", ["import", "log.csv", *sens, "--out",
                                                     "imp", "--json"],
           {"log.csv": f[f"fd.ok.{name}.counts"]},
           ensayo_check(gain, BIASES[name], theta_known=False))
    s105 = f["fd.sig.S105"]
    ok("gain 1.05: noise on a still log in m/s²", ["noise", "log.csv", "--json"],
       {"log.csv": f["fd.ok.S105.ms2"]}, noise_check(s105))
    ok("gain 1.05: noise on a still log in g", ["noise", "log.csv", "--json"],
       {"log.csv": f["fd.ok.S105.g"]}, noise_check(s105))
    ok("gain 1.05: apply its calibration to the log",
       ["apply", "log.csv", "--calibration", "cal.json", "--out", "corrected.csv"],
       {"log.csv": f["fd.ok.P105.ms2"], "cal.json": f["fd.made.cal_P105"]},
       corrected_check(f["fd.sig.P105"], GAINS["P105"], BIASES["P105"]))
    ok("gap on a held-pose log (θ from --poses)", ["gap", "log.csv", *POSES, "--json"],
       {"log.csv": f["fd.ok.P.ms2"]}, json_check(lambda o: "verdict" in o, "a verdict"))
    # counts with --sensitivity: CSV stated, CSV by option, int16 .mat by --map
    tp = truth_params((1, 1, 1), (0, 0, 0))
    s = f["fd.sig.S"]
    mp = ["--map", "datos=acc,t=time"]
    for label, key, opts in (("a CSV '(counts)' --sensitivity", "counts", sens),
                             ("a bare CSV --units counts --sensitivity", "bare_counts",
                              ["--units", "counts", *sens]),
                             ("an int16 .mat --map --units counts --sensitivity", "mat_counts",
                              [*mp, "--units", "counts", *sens])):
        name = "log.mat" if key.startswith("mat") else "log.csv"
        ok(f"counts: calibrate {label}", ["calibrate", name, *opts, "--json"],
           {name: f[f"fd.ok.P.{key}"]}, calibration_check(tp))
        ok(f"counts: noise {label}", ["noise", name, *opts, "--json"],
           {name: f[f"fd.ok.S.{key}"]}, noise_check(s, gyro_factor=None if key.startswith(
               "mat") else 1.0))
        ok(f"counts: import {label}", ["import", name, *opts, "--out", "imp", "--json"],
           {name: f[f"fd.ok.S.{key}"]},
           acel_check(s, 0.6 / FACTOR["counts"], gyro_factor=None if key.startswith("mat")
                      else 1.0))
    ok("a .mat in m/s² through --map: calibrate", ["calibrate", "log.mat", *mp, "--json"],
       {"log.mat": f["fd.ok.P.mat_ms2"]}, calibration_check(tp))
    # formats: phyphox zip, Sensor Logger renamed, ns stamps, bags, TSV, ';' decimal comma, gz
    fmts = [("phyphox zip", "phyphox", "run.zip", [], False),
            ("Sensor Logger export renamed", "sensorlogger", "my phone run.csv", [], False),
            ("nanosecond stamps --time-unit ns", "ns", "log.csv", ["--time-unit", "ns"], True),
            ("TSV", "tsv", "log.tsv", [], True),
            ("';' with decimal commas", "semicolon_comma", "log.csv", [], True),
            ("gzip CSV", "gz", "log.csv.gz", [], True)]
    for label, key, name, opts, gyro in fmts:
        ok(f"{label}: calibrate", ["calibrate", name, *opts, "--json"],
           {name: f[f"fd.ok.P.{key}"]}, calibration_check(tp))
        ok(f"{label}: noise", ["noise", name, *opts, "--json"], {name: f[f"fd.ok.S.{key}"]},
           noise_check(s, gyro_factor=1.0 if gyro else None))
        ok(f"{label}: import", ["import", name, *opts, "--out", "imp", "--json"],
           {name: f[f"fd.ok.S.{key}"]},
           acel_check(s, {"phyphox": 2e-5, "ns": NS_TOL}.get(key, 2e-6),
                      gyro_factor=1.0 if gyro else None))
    for ros, key, name in (("ROS 1 bag", "ros1", "imu.bag"), ("ROS 2 bag", "ros2", "bag")):
        pf = _bag_files_of(f, f"fd.bag.{key}.P", name)
        sf = _bag_files_of(f, f"fd.bag.{key}.S", name)
        ok(f"{ros}: calibrate", ["calibrate", name, "--json"], pf, calibration_check(tp))
        ok(f"{ros}: noise", ["noise", name, "--json"], sf, noise_check(s))
        ok(f"{ros}: import", ["import", name, "--out", "imp", "--json"], sf,
           acel_check(s, 1e-9))
    db3 = next(n for n in _bag_files_of(f, "fd.bag.ros2.P", "bag") if n.endswith(".db3"))
    ok("ROS 2 bag: calibrate its .db3 file", ["calibrate", db3, "--json"],
       _bag_files_of(f, "fd.bag.ros2.P", "bag"), calibration_check(tp))
    ok("ROS 1 bag with two Imu topics: calibrate --columns topic=/imu/right",
       ["calibrate", "imu.bag", "--columns", "topic=/imu/right", "--json"],
       {"imu.bag": f["fd.bag.two_topics"]}, calibration_check(tp))
    ok("--allow-gaps: calibrate held poses across a gap",
       ["calibrate", "log.csv", "--allow-gaps", "--json"], {"log.csv": f["fd.ref.gap.P"]},
       calibration_check(tp))
    ok("--allow-saturation: calibrate", ["calibrate", "log.csv", "--allow-saturation",
                                         "--json"],
       {"log.csv": f["fd.ref.saturated.P"]}, calibration_check(tp))
    ok("--allow-saturation: noise", ["noise", "log.csv", "--allow-saturation", "--json"],
       {"log.csv": f["fd.ref.saturated.S"]}, noise_check(s, white=None))
    ok("θ from the gyro: calibrate --theta-source gyro",
       ["calibrate", "log.csv", "--theta-source", "gyro", *POSES, "--json"],
       {"log.csv": f["fd.unit.gyro_ok"]}, calibration_check(tp))
    cases += real_logs(f)
    return cases


def corrected_check(sig_path: Path, gain, bias) -> Check:
    """``apply --out corrected.csv``: the corrected x, y readings are the true ones,
    ``(A_m − bias)/(1 + scale)`` with the log's gain and bias undone (within 0.05 m/s² rms:
    the noise and the calibration's error)."""
    s = _sig(sig_path)

    def check(code, out, err, root) -> str | None:
        p = root / "corrected.csv"
        if not p.exists():
            return "corrected.csv not written"
        rows = [ln for ln in p.read_text().splitlines() if ln and not ln.startswith("#")]
        data = np.array([[float(c) for c in r.split(",")] for r in rows[1:]])
        want = (s.acc[:, :2] - np.asarray(bias[:2])) / np.asarray(gain[:2])
        if data.shape[0] != want.shape[0] or data.shape[1] < 3:
            return f"corrected.csv holds {data.shape}, the log {want.shape}"
        rms = float(np.sqrt(np.mean((data[:, 1:3] - want) ** 2)))
        return None if rms < 0.05 else f"corrected readings off by {rms:.3g} m/s² rms"

    return check


def real_logs(f: dict) -> list[Case]:
    """The real shipped logs (``data/real``) with the commands their docs give, checked
    against the numbers the docs state."""
    cases: list[Case] = []
    if not REAL.is_dir():
        return cases

    def ok(name, argv, files, check=None):
        cases.append(Case("valid_log", f"real: {name}", argv, files, expect="valid",
                          check=check))

    yei = {"yei.csv": REAL / "yei-3space-z-flip.csv"}
    r = ["--units", "g", "--gyro-unit", "rad/s", "--axes", "x,-z"]
    held = ["--min-hold", "0.5", "--poses", "0,0,180,0,0", "--angle-unit", "deg"]
    ok("YEI import (docs/real-data.md)", ["import", "yei.csv", *r, *held, "--out", "imp",
                                          "--json"], yei,
       files_check("imp/ensayo.mat", "imp/provenance.json"))
    # docs/real-data.md: x bias −0.4132 m/s², scale −0.1716; y bias 0.0733, scale 0.0013
    ok("YEI calibrate, θ from the gyro (the docs' estimates)",
       ["calibrate", "yei.csv", *r, *held, "--theta-source", "gyro", "--json"], yei,
       calibration_check({"bias_x": -0.4132, "scale_x": -0.1716, "bias_y": 0.0733,
                          "scale_y": 0.0013}, floor=(0.002, 0.002), sigmas=0.0))
    ok("YEI noise on the turned-over hold (the docs' N)",
       ["noise", "still.csv", *r, "--json"], {"still.csv": f["fd.real.yei_still"]},
       json_check(lambda o: all(abs(o["axes"][a]["terms"]["white_noise_density"]["value"]
                                    / n - 1) < 0.15
                                for a, n in (("x", 0.00194), ("y", 0.00282))),
                  "N ≈ 0.00194, 0.00282 (m/s²)/√Hz"))
    ax3 = {"ax3.csv.gz": REAL / "axivity-ax3-wrist-night.csv.gz"}
    ok("Axivity AX3 calibrate (docs/real-data.md)",
       ["calibrate", "ax3.csv.gz", "--units", "counts", "--sensitivity", "256", "--min-hold",
        "100", "--json"], ax3,
       json_check(lambda o: all(abs(v) < (2.0 if n.startswith("bias") else 0.15)
                                for n, v in zip(o["fit"]["param_names"], o["fit"]["params"],
                                                strict=True)),
                  "a bias below 2 m/s² and a scale below 15 %"))
    imucal = {"ferraris.csv.gz": REAL / "imucal-ferraris-session.csv.gz"}
    # data/real/README.md: x biased by about +0.54 m/s², y −0.62, z +0.39
    ok("imucal six-face calibrate (README's biases)",
       ["calibrate", "ferraris.csv.gz", "--units", "m/s2", "--gyro-unit", "deg/s", "--json"],
       imucal, calibration_check({"bias_x": 0.54, "bias_y": -0.62, "bias_z": 0.39},
                                 floor=(0.05, 0.0), sigmas=0.0))
    pol = {"pololu.csv": REAL / "pololu-minimu9-x-flip.csv"}
    ok("Pololu import, counts --sensitivity 16393.4 (x up, x down)",
       ["import", "pololu.csv", "--units", "counts", "--sensitivity", "16393.4", "--out",
        "imp", "--json"], pol, _pololu_check())
    ng = {"ngimu.csv": REAL / "ngimu-sensors.csv"}
    ok("NGIMU import (moved, then z up: no tilt on x, y)",
       ["import", "ngimu.csv", "--out", "imp", "--json"], ng, _ngimu_check())
    return cases


def _real_files(d: Path, f: dict) -> None:
    """The YEI log's turned-over hold, cut as docs/real-data.md does it:
    ``(head -1 L; sed -n '1092,1251p' L) > still.csv``."""
    d.mkdir(parents=True, exist_ok=True)
    src = REAL / "yei-3space-z-flip.csv"
    if src.exists():
        lines = src.read_bytes().splitlines(keepends=True)
        (d / "yei_still.csv").write_bytes(b"".join([lines[0], *lines[1091:1251]]))
        f["fd.real.yei_still"] = d / "yei_still.csv"


def _pololu_check() -> Check:
    def check(code, out, err, root) -> str | None:
        import scipy.io

        p = root / "imp" / "ensayo.mat"
        if not p.exists():
            return "no imp/ensayo.mat"
        m = scipy.io.loadmat(p)
        pose, datos = np.asarray(m["pose"]).ravel(), np.asarray(m["datos"], float)
        labels = [k for k in dict.fromkeys(pose.tolist()) if k >= 0]
        means = [datos[pose == k, 0].mean() for k in labels]
        if len(means) < 2 or not (means[0] > 8.5 and min(means) < -8.5):
            return f"x reads {np.round(means, 2)} m/s² in its holds, not +g then −g"
        return None

    return check


def _ngimu_check() -> Check:
    def check(code, out, err, root) -> str | None:
        import scipy.io

        p = root / "imp" / "acel.mat"
        if not p.exists():
            return "no imp/acel.mat"
        a = np.asarray(scipy.io.loadmat(p)["Aerr"], float)
        tail = np.abs(a[-200:].mean(axis=0))
        return None if np.all(tail < 1.0) else f"lying flat, x, y read {tail.round(3)} m/s²"

    return check


KINDS = {"unit_mistake": unit_mistakes, "sensor_file": sensor_files, "bad_bag": bad_bags,
         "cell_count": cell_counts, "unit_suffix": unit_suffixes,
         "log_refusal": log_refusals, "valid_log": valid_logs}
"""The front-door kinds (registered in :data:`validation.fuzz.cases.KINDS`)."""
