"""Benchmarks, reported as ratios against a baseline measured in the same run.

    python benchmarks/run.py            # or: make bench

1. Static calibration run (course design, N = 20001 distinct θ): one batched
   ``mujoco.rollout`` over the distinct poses (bench.tilt.static_readings) against the
   baseline of a Python loop calling ``mj_forward`` once per sample.
2. Held positions (100 positions × 200 samples): one physics evaluation per distinct pose
   against one per sample (the same loop baseline).
3. Calibration fit (N = 20001): ``calib.calibration.ls.fit_axis`` (centred design, one Householder
QR of
   the augmented design for solution, rank and covariance, plus the condition number) against
   the MATLAB-style normal equations ``inv(HᵀH)Hᵀy`` — the price of the safe numerics.

``make bench`` also runs ``benchmarks/mc_speed.py``: the batched Monte Carlo and a single
``calibrate()`` against the cost of drawing their random numbers (targets printed with
PASS/FAIL); and ``benchmarks/csv_reader.py``: the CSV reader on 1- and 10-hour 100 Hz logs,
its peak memory against the numeric array it returns (≤ 2×) and its time against a plain
``pandas.read_csv`` of the same file (≤ 1.5×), with the 24-hour log's peak projected
(PASS/FAIL, exit code 1 on FAIL).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as the CLI does (bench/cli/__init__.py)


import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from timing import best_of  # noqa: E402  (benchmarks/timing.py, beside this script)

from bench.model import ACC_SENSORS, tilt_table  # noqa: E402
from bench.tilt import ThetaDesign, static_readings  # noqa: E402
from calib.calibration.ls import fit_axis  # noqa: E402
from calib.conventions import reference_accel  # noqa: E402


def loop_forward(theta: np.ndarray) -> np.ndarray:
    model, _ = tilt_table()
    data = mujoco.MjData(model)
    out = np.empty((theta.size, 2))
    ax, ay = (model.sensor(ACC_SENSORS[a]).adr[0] for a in "xy")
    for i, th in enumerate(theta):
        data.qpos[0] = th
        data.ctrl[0] = th
        data.qvel[0] = 0.0
        mujoco.mj_forward(model, data)
        out[i] = data.sensordata[ax], data.sensordata[ay]
    return out


def main() -> None:
    rows = []
    course = ThetaDesign().angles()
    held = ThetaDesign(kind="positions", positions=100, per_position=200).angles()
    for label, theta in (("static course design (20001 poses)", course),
                         ("held positions (100 × 200)", held)):
        base = best_of(lambda th=theta: loop_forward(th), 3)
        ours = best_of(lambda th=theta: static_readings(th), 3)
        rows.append((label, "mj_forward loop per sample", base, ours))
    tita = course
    a_m = reference_accel(tita)[:, 1] + np.random.default_rng(0).standard_normal(tita.size)

    def naive():
        a_r = reference_accel(tita)[:, 1]
        H = np.column_stack([np.ones_like(a_r), a_r])
        return np.linalg.inv(H.T @ H) @ H.T @ (a_m - a_r)

    rows.append(("fit_axis N = 20001", "inv(HᵀH)Hᵀy", best_of(naive, 20),
                 best_of(lambda: fit_axis(tita, a_m, "y", 0.64), 20)))
    print(f"{'benchmark':<38}{'baseline':<28}{'base ms':>10}{'ours ms':>10}{'speed-up':>10}")
    for label, bl, b, o in rows:
        print(f"{label:<38}{bl:<28}{1e3 * b:>10.2f}{1e3 * o:>10.2f}{b / o:>9.2f}×")


if __name__ == "__main__":
    main()
