"""The inputs of the fuzz cases: generated sets (through the command line) and edited copies.

Everything is written under ``base/``; the cases copy what they use into their own folder.
Edits follow the formats of DESIGN.md / docs: ``ensayo.mat`` {tita, datos}, ``acel.mat``
{t, Aerr[, gyro]}, ``gps.mat`` {t_gps, pos}, ``cal.json`` (``calibrate --save``).
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import scipy.io

from validation.fuzz import front_door
from validation.fuzz.runner import tiltbench


def _mat(path: Path, **arrays) -> Path:
    scipy.io.savemat(path, {k: np.asarray(v) for k, v in arrays.items()})
    return path


def _ensayo(path: Path, n: int, rng: np.random.Generator, noise: bool = True) -> Path:
    tita = np.linspace(0.0, 2 * np.pi, n, endpoint=n > 4)
    ref = np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)])
    datos = 1.01 * ref + np.array([0.08, -0.02])
    if noise:
        datos = datos + rng.normal(0.0, [0.5, 0.8], ref.shape)
    return _mat(path, tita=tita[:, None], datos=datos)


def build(base: Path, seed: int, env: dict,
          run: Callable[[list[str], Path, dict], None] = tiltbench) -> dict[str, Path]:
    """Write every input; return {name: path}. ``run(argv, cwd, env)`` runs a fixture-building
    command (default :func:`tiltbench`, a subprocess; a test may run them in its process)."""
    base.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    f: dict[str, Path] = {}
    gen = [
        ("c1", ["generate", "course", "--seed", str(seed + 1), "--gps", "--count", "2001"]),
        ("c3", ["generate", "course", "--seed", str(seed + 3), "--gps", "--count", "2001"]),
        ("t1", ["generate", "course", "--seed", str(seed + 2), "--gps", "--turning",
                "--count", "2001"]),
        ("sw", ["generate", "calibration", "--mode", "sweep", "--seed", str(seed + 4)]),
        ("q1", ["generate", "calibration", "--seed", str(seed + 5), "--count", "2001",
                "--effect", "quantization:x:lsb=0.01", "--effect", "quantization:y:lsb=0.01"]),
        ("q2", ["generate", "calibration", "--seed", str(seed + 6), "--count", "5001",
                "--effect", "quantization:x:lsb=0.002",
                "--effect", "quantization:y:lsb=0.002"]),
    ]
    for name, argv in gen:
        out = base / name
        if not (out / "truth.json").exists():
            run([*argv, "--out", str(out), "--force"], base, env)
    for name in ("c1", "c3", "t1"):
        d = base / name
        for kind in ("ensayo", "acel", "puntos", "gps"):
            f[f"{name}.{kind}"] = d / f"{kind}.mat"
        f[f"{name}.datos"] = d / "datos.txt"
        f[f"{name}.truth"] = d / "truth.json"
        for cal in ("cal.json", "cal.mat"):  # (kept between runs, as the sets are)
            if not (d / cal).exists():
                run(["calibrate", "ensayo.mat", "--datos", "datos.txt", "--save", cal], d, env)
        f[f"{name}.cal"] = d / "cal.json"
        f[f"{name}.calmat"] = d / "cal.mat"
    for name in ("sw", "q1", "q2"):
        f[f"{name}.ensayo"] = base / name / "ensayo.mat"
        f[f"{name}.truth"] = base / name / "truth.json"
    _edited_calibrations(base, f)
    _faulty_gps(base, f)
    _turning_gyro(base, f)
    _small_and_empty(base, f, rng)
    _truth_files(base, f)
    _logs(base, f, rng)
    f.update(front_door.build(base, seed, env, run))  # issue 31's front-door kinds
    return f


# ---------------------------------------------------------------- calibration files
def _edited_calibrations(base: Path, f: dict[str, Path]) -> None:
    """cal.json edits: the readable block set to another seed's truth, parameters edited,
    |ρ| > 1, n = 0 / 10¹², negative or NaN σ², a non-symmetric covariance."""
    d = base / "cal"
    d.mkdir(exist_ok=True)
    cal = json.loads(f["c3.cal"].read_text())
    truth1 = json.loads(f["c1.truth"].read_text())["sensor"]

    def save(name: str, obj: dict) -> None:
        p = d / f"{name}.json"
        p.write_text(json.dumps(obj, indent=2))
        f[f"cal.{name}"] = p

    # the readable block graded by validate, set to seed 1's truth (the issue's case)
    c = copy.deepcopy(cal)
    axes = c.get("calibration", {}).get("axes", {})
    for ax in ("x", "y"):
        if ax in axes:
            axes[ax]["bias"] = truth1[ax]["bias"]
            axes[ax]["scale"] = truth1[ax]["scale"]
    save("axes_edited", c)
    # the parameters themselves set to seed 1's truth (no checksum updated)
    c = copy.deepcopy(cal)
    c["params"] = [truth1["x"]["bias"], truth1["x"]["scale"], truth1["y"]["bias"],
                   truth1["y"]["scale"]]
    save("params_edited", c)
    c = copy.deepcopy(cal)  # both, as a careful forger would
    c["params"] = [truth1["x"]["bias"], truth1["x"]["scale"], truth1["y"]["bias"],
                   truth1["y"]["scale"]]
    for ax in ("x", "y"):
        if ax in axes:
            c["calibration"]["axes"][ax]["bias"] = truth1[ax]["bias"]
            c["calibration"]["axes"][ax]["scale"] = truth1[ax]["scale"]
    save("both_edited", c)
    c = copy.deepcopy(cal)  # |ρ| = 3 between bias_x and scale_x: a negative variance ahead
    cov = np.asarray(c["cov"], float)
    cov[0, 1] = cov[1, 0] = 3.0 * np.sqrt(cov[0, 0] * cov[1, 1])
    c["cov"] = cov.tolist()
    save("rho_gt_1", c)
    c = copy.deepcopy(cal)
    cov = np.asarray(c["cov"], float)
    cov[0, 1] = 0.5 * np.sqrt(cov[0, 0] * cov[1, 1])  # not symmetric
    c["cov"] = cov.tolist()
    save("cov_asymmetric", c)
    c = copy.deepcopy(cal)
    cov = np.asarray(c["cov"], float)
    cov[2, 2] = -cov[2, 2]
    c["cov"] = cov.tolist()
    save("cov_negative_var", c)
    for n in (0, 1, 10**12):
        c = copy.deepcopy(cal)
        c["n"] = n
        save(f"n_{n}", c)
    c = copy.deepcopy(cal)
    c["sigma2"] = [-0.25, 0.64]
    save("sigma2_negative", c)
    c = copy.deepcopy(cal)
    c["sigma2"] = [1e300, 1e300]
    save("sigma2_huge", c)
    c = copy.deepcopy(cal)
    c["params"][0] = 1e300
    save("bias_huge", c)
    c = copy.deepcopy(cal)
    c["params"][1] = -1.0  # gain 1 + scale = 0: no reading
    save("scale_minus_one", c)
    c = copy.deepcopy(cal)
    c["cov"] = (np.asarray(c["cov"], float) * 1e300).tolist()
    save("cov_huge", c)
    c = copy.deepcopy(cal)
    c["format_version"] = 99
    save("future_version", c)
    (d / "truncated.json").write_text(f["c3.cal"].read_text()[:200])
    f["cal.truncated"] = d / "truncated.json"
    (d / "nan.json").write_text(f["c3.cal"].read_text().replace(
        str(cal["params"][0]), "NaN", 1))
    f["cal.nan"] = d / "nan.json"
    f["cal.empty_mat"] = _mat(d / "empty.mat")
    f["cal.wrong_mat"] = _mat(d / "wrong.mat", params=np.array([[1.0, 2.0]]))


# ---------------------------------------------------------------- position fixes
def _faulty_gps(base: Path, f: dict[str, Path]) -> None:
    """gps.mat of c1 in km, columns swapped, +50 m offset, times +30 s, one 200 m outlier,
    NaN, times out of order, one fix."""
    d = base / "gps"
    d.mkdir(exist_ok=True)
    g = scipy.io.loadmat(f["c1.gps"])
    t, pos = g["t_gps"].astype(float), g["pos"].astype(float)
    edits = {
        "km": (t, pos / 1000.0),
        "swapped": (t, pos[:, ::-1]),
        "offset50": (t, pos + 50.0),
        "shift30": (t + 30.0, pos),
        "shift_minus5": (t - 5.0, pos),
        "outlier200": (t, np.where(np.arange(len(t))[:, None] == len(t) // 2,
                                   pos + [200.0, 0.0], pos)),
        "nan": (t, np.where(np.arange(len(t))[:, None] == 3, np.nan, pos)),
        "unsorted": (t[::-1], pos[::-1]),
        "one_fix": (t[:1], pos[:1]),
        "huge": (t, pos * 1e300),
    }
    for name, (tt, pp) in edits.items():
        f[f"gps.{name}"] = _mat(d / f"{name}.mat", t_gps=tt, pos=pp)
    f["gps.empty"] = _mat(d / "empty.mat")


# ---------------------------------------------------------------- turning runs
def _turning_gyro(base: Path, f: dict[str, Path]) -> None:
    """acel.mat of the turning run t1 with the gyro missing, all zeros, in deg/s, ×1e6,
    constant, NaN."""
    d = base / "gyro"
    d.mkdir(exist_ok=True)
    a = scipy.io.loadmat(f["t1.acel"])
    t, acc, gyro = a["t"], a["Aerr"], a["gyro"].astype(float)
    edits = {
        "missing": None,
        "zeros": np.zeros_like(gyro),
        "degps": np.degrees(gyro),
        "absurd": gyro * 1e6,
        "constant": np.full_like(gyro, float(np.mean(gyro))),
        "nan": np.where(np.arange(len(gyro))[:, None] == 10, np.nan, gyro),
    }
    for name, gy in edits.items():
        arrays = {"t": t, "Aerr": acc} if gy is None else {"t": t, "Aerr": acc, "gyro": gy}
        f[f"gyro.{name}"] = _mat(d / f"{name}.mat", **arrays)


# ---------------------------------------------------------------- small, empty, odd
def _small_and_empty(base: Path, f: dict[str, Path], rng: np.random.Generator) -> None:
    d = base / "small"
    d.mkdir(exist_ok=True)
    for n in (3, 4, 5):
        f[f"ens.n{n}"] = _ensayo(d / f"ens_n{n}.mat", n, rng)
        f[f"ens.n{n}_exact"] = _ensayo(d / f"ens_n{n}_exact.mat", n, rng, noise=False)
    f["ens.n2"] = _ensayo(d / "ens_n2.mat", 2, rng)
    f["ens.empty"] = _mat(d / "ens_empty.mat")
    f["ens.zero_rows"] = _mat(d / "ens_zero_rows.mat", tita=np.zeros((0, 1)),
                              datos=np.zeros((0, 2)))
    f["ens.same_theta"] = _mat(d / "ens_same_theta.mat", tita=np.full((50, 1), 0.3),
                               datos=rng.normal(0, 1, (50, 2)))
    f["ens.huge"] = _mat(d / "ens_huge.mat", tita=np.linspace(0, 6, 50)[:, None],
                         datos=rng.normal(0, 1, (50, 2)) * 1e300)
    f["ens.constant"] = _mat(d / "ens_constant.mat", tita=np.linspace(0, 6, 50)[:, None],
                             datos=np.ones((50, 2)))
    t = np.arange(3) * 0.01
    f["acel.n3"] = _mat(d / "acel_n3.mat", t=t[:, None], Aerr=rng.normal(0, 0.5, (3, 2)))
    f["acel.n1"] = _mat(d / "acel_n1.mat", t=np.zeros((1, 1)), Aerr=np.zeros((1, 2)))
    f["acel.empty"] = _mat(d / "acel_empty.mat")
    f["acel.zero_dt"] = _mat(d / "acel_zero_dt.mat", t=np.zeros((50, 1)),
                             Aerr=np.zeros((50, 2)))
    f["puntos.empty"] = _mat(d / "puntos_empty.mat")
    f["puntos.one"] = _mat(d / "puntos_one.mat", A=np.array([[1.0, 2.0]]))
    f["gps.n3_run"] = _mat(d / "gps_n3.mat", t_gps=np.array([[0.0], [0.01]]),
                           pos=np.zeros((2, 2)))
    (d / "datos_empty.txt").write_text("")
    f["datos.empty"] = d / "datos_empty.txt"
    (d / "datos_garbage.txt").write_text("P0 = nan nan\nV0 = 1 2\nvar = -1 0\n")
    f["datos.garbage"] = d / "datos_garbage.txt"


def _truth_files(base: Path, f: dict[str, Path]) -> None:
    d = base / "truth"
    d.mkdir(exist_ok=True)
    good = json.loads(f["t1.truth"].read_text())
    bad = {
        "empty": "",
        "not_json": "this is not json {",
        "list": "[1, 2, 3]",
        "empty_object": "{}",
        "end_text": json.dumps({**good, "true_final_position": "far away"}),
        "end_nan": json.dumps({**good, "true_final_position": [float("nan"), 0.0]}),
        "no_trajectory": json.dumps({k: v for k, v in good.items()
                                     if k not in ("trajectory", "vehicle")}),
        "truncated": f["t1.truth"].read_text()[: len(f["t1.truth"].read_text()) // 2],
    }
    for name, text in bad.items():
        (d / f"{name}.json").write_text(text)
        f[f"truth.{name}"] = d / f"{name}.json"


CSV_HEADER = "t,ax (m/s^2),ay (m/s^2),az (m/s^2)\n"
"""A log header whose units are stated (docs/real-data.md: units are never guessed)."""


def _csv_rows(t: np.ndarray, acc: np.ndarray) -> str:
    return "\n".join(",".join(f"{v:.6f}" for v in row) for row in np.column_stack([t, acc]))


def _logs(base: Path, f: dict[str, Path], rng: np.random.Generator) -> None:
    """A static CSV log (noise) and a held-pose CSV log (import), plus tiny ones."""
    d = base / "logs"
    d.mkdir(exist_ok=True)
    n = 6000
    t = np.arange(n) / 100.0
    acc = np.array([0.05, -0.02, 9.8]) + rng.normal(0, 0.02, (n, 3))
    rows = _csv_rows(t, acc)
    (d / "still.csv").write_text(CSV_HEADER + rows + "\n")
    f["log.still"] = d / "still.csv"
    (d / "still3.csv").write_text(CSV_HEADER
                                  + "\n".join(rows.splitlines()[:3]) + "\n")
    f["log.still3"] = d / "still3.csv"
    poses = np.radians([0.0, 90.0, 180.0, 270.0])
    parts = []
    for th in poses:
        m = 300
        parts.append(np.column_stack([np.full(m, -9.8 * np.sin(th)), np.full(m, 0.0),
                                      np.full(m, -9.8 * np.cos(th))])
                     + rng.normal(0, 0.02, (m, 3)))
    acc = np.vstack(parts)
    t = np.arange(len(acc)) / 100.0
    rows = _csv_rows(t, acc)
    (d / "poses.csv").write_text(CSV_HEADER + rows + "\n")
    f["log.poses"] = d / "poses.csv"
    (d / "header_only.csv").write_text(CSV_HEADER)
    f["log.header_only"] = d / "header_only.csv"
