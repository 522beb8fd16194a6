"""The thesis comparison done properly (issue 13, part 5): dead reckoning, fixes alone, Kalman
filter and RTS smoother on the course geometry, over a Monte Carlo of R runs per scenario.

Setup (one truth per IMU rate, noise redrawn per run)
-----------------------------------------------------
* **Truth**: the course run (:class:`bench.vehicle.VehicleConfig` defaults: 60 s, the three
  20 s segments of ``COURSE_PROFILE``, P0 = (0, 0) m, V0 = (1, 3) m/s) simulated once by
  MuJoCo per IMU rate (100 Hz, 50 Hz): ``t``, ``pos``, ``vel``, true specific force ``acc``.
* **Calibration**: one course calibration run (20001 angles, ``COURSE_SENSOR``) fitted once
  (:func:`calib.calibration.tilt_plane.calibrate`, σ² known): estimate ``(b̂, ŝ)`` with covariance
  ``C_cal``. Each run draws the sensor's **true** bias and scale around the estimate,
  ``(b, s) ~ N((b̂, ŝ), C_cal)``: the calibration error of a random student, with the
  distribution the filter and the dead-reckoning region assume.
* **Per run** (its own stream ``SeedSequence(seed, spawn_key=(STUDY_STREAM,)).spawn(R)[k]``,
  :func:`calib.stats.runs.run_seeds`; the same R streams in every scenario — common random numbers,
  so scenario differences are paired): the sensor's true (b, s) (4 normals), the initial-state
  error ``(p̂0 − p0, v̂0 − v0) ~ N(0, diag(σ_p0², σ_p0², σ_v0², σ_v0²))`` (4 normals), the
  readings ``A_m = (1 + s)·acc + b + v``, ``v ~ N(0, σ_a²)`` (:func:`bench.vehicle.
  apply_sensor_errors`), the fixes (:func:`bench.gnss.simulate_fixes`, σ = 3 m per axis).

Methods (all four see the same run)
-----------------------------------
* ``dead_reckoning``: :func:`calib.vehicle.trajectory.correct_and_integrate` from ``(p̂0, v̂0)``;
  covariance of the end point from :func:`calib.vehicle.region.arrival_region` (noise + calibration)
  plus the initial-state terms ``P_p0 + T² P_v0`` (T the run's duration).
* ``fixes``: the fixes themselves as a position estimate (error at the fix epochs; std σ per
  axis; the region of the **last** fix — in the outage scenario that fix is 21 s old).
* ``filter``, ``smoother``: :func:`calib.fusion.linear.fuse` (Q from σ_a² and C_cal, R = σ² I,
  P0 from σ_p0, σ_v0 and C_cal), filtered and RTS-smoothed.

Scenarios (:data:`SCENARIOS`): IMU 100 / 50 Hz × fixes 1 / 10 Hz; no fix in the last 20 s;
and the filter's P0, Q or R mis-set by ×10 and ÷10 (the *variances* handed to the filter;
the data stay the same). Dead reckoning uses the same mis-set σ_a² (Q) and P0 as the filter.
"P0" is the initial position and velocity block, ``diag(σ_p0², σ_p0², σ_v0², σ_v0²)`` with
σ_p0 = 1 m, σ_v0 = 0.1 m/s, the σ the true initial error is drawn with (it is not zero, so
×10 and ÷10 change what the filter believes); the calibration block of P0 (``C_cal``'s
biases) is not scaled.

Numbers per method and scenario (:class:`StudyRow`)
---------------------------------------------------
* ``rms_m``: ``sqrt(mean |p̂ − p|²)`` over every node of the path (IMU samples; fix epochs
  for ``fixes``) and every run, m (2-D error).
* ``final_std_m``: stated per-axis std of the final position, ``sqrt(tr P/2)``, m (mean over
  runs); ``area_m2``: the stated level-L ellipse's area ``π χ²₂(L) sqrt(det P)``
  (:meth:`calib.vehicle.region.Ellipse.area`), m².
* ``nees``: mean over runs of the final-position NEES ``eᵀ P⁻¹ e`` (2 dof); if the stated P is
  right, R·NEES ~ χ²(2R), and the band is its two-sided quantiles at α = 6.3e-5 (≈ ±4σ,
  docs/conventions.md); ``nees_ok``: inside. ``coverage``: share of runs whose true end point
  is inside the level-L ellipse, with the exact Binomial(R, L) band at the same α. The
  smoother's last node is the filter's (no later data), so its NEES and coverage repeat the
  filter's; it differs along the path (RMS).

* NEES **along the path** (filter, smoother, fixes; not computed for dead reckoning, whose
  stated covariance comes at the end point only): at every fix epoch t_j (j = 1..M; the
  filter after the update, the smoother's stored covariance at that node), the mean over the
  R runs of the position NEES (2 dof) and, for the filter and smoother, of the
  position+velocity NEES (4 dof). If the stated covariance is right, ``R·mean ~ χ²(dof·R)``
  at each epoch. Each epoch is judged against the two-sided quantiles at ``NEES_ALPHA/T``,
  T = 2M tests (M epochs × the two NEES; T = M for fixes): by the union bound (Bonferroni)
  a consistent filter has every test inside with probability ≥ 1 − NEES_ALPHA. The epochs
  are strongly correlated in time (the same run's errors), which the union bound does not
  need: it stays valid, and conservative, under any dependence. Per row:
  ``path_out_frac`` (share of the M epochs whose position NEES is out), ``path_out_ranges`` /
  ``path_where`` (where, e.g. "t ≤ 10 s"), ``path4_out_frac`` / ``path4_where`` (the same for
  4 dof), and ``path_ok`` ("consistent along the path": no test out, either NEES). The
  curves are in :attr:`StudyResult.paths` (:class:`PathNees`). This sees what the final
  NEES cannot: a mis-set P0 is out early and forgotten after the first fixes; Q×10 is
  mostly inside in position but out in velocity.

A Monte Carlo of R runs supports only claims at the resolution of those bands: with R = 200 a
NEES of 2.3 is not distinguishable from 2, and coverage 0.99 not from 0.997.

Units SI: s, m, m/s, m/s², Hz; areas m².
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, replace

import numpy as np

from bench.fusion_study_result import (
    METHODS,
    PathNees,
    StudyResult,
    StudyRow,
    describe_ranges,
)
from calib.stats.consistency import (
    NEES_ALPHA,
    coverage_band,
    mean_nees_band,
    nees,
    out_ranges,
    path_band,
)
from calib.stats.runs import Mapper, chunk_ranges, run_seeds, serial_map
from calib.vehicle.region import Ellipse

STUDY_STREAM = 15
"""Spawn key of the study's per-run streams under the user's seed."""



@dataclass(frozen=True)
class Scenario:
    """One column of the comparison.

    imu_hz : IMU (and physics) rate, Hz.  fix_hz : fix rate, Hz.
    outage_s : no fix in the last ``outage_s`` s of the run (0: none).
    p0_factor, q_factor, r_factor : multiply the variances the filter is told (P0 of the
        position and velocity, σ_a², σ²) — 1 is the truth.
    """

    name: str
    imu_hz: float = 100.0
    fix_hz: float = 1.0
    outage_s: float = 0.0
    p0_factor: float = 1.0
    q_factor: float = 1.0
    r_factor: float = 1.0

    def to_dict(self) -> dict:
        return asdict(self)


SCENARIOS: tuple[Scenario, ...] = (
    Scenario("IMU 100 Hz, fixes 1 Hz"),
    Scenario("IMU 50 Hz, fixes 1 Hz", imu_hz=50.0),
    Scenario("IMU 100 Hz, fixes 10 Hz", fix_hz=10.0),
    Scenario("IMU 50 Hz, fixes 10 Hz", imu_hz=50.0, fix_hz=10.0),
    Scenario("20 s outage at the end", outage_s=20.0),
    Scenario("P0 x10", p0_factor=10.0),
    Scenario("P0 /10", p0_factor=0.1),
    Scenario("Q x10", q_factor=10.0),
    Scenario("Q /10", q_factor=0.1),
    Scenario("R x10", r_factor=10.0),
    Scenario("R /10", r_factor=0.1),
)
"""The scenarios of the comparison (issue 13, part 5); the first is the reference."""


@dataclass(frozen=True)
class StudyConfig:
    """runs R per scenario, seed, runs per task (memory: a task of 25 runs of 6000 steps holds
    ≈ 200 MB of covariances), region level L, the true initial-state σ (m, m/s) and fix σ (m).
    """

    # fields alike Scenario's in shape only: the study's size and truth, not a filter's settings
    runs: int = 200
    seed: int = 0
    chunk: int = 25
    level: float = 0.997
    p0_std: float = 1.0
    v0_std: float = 0.1
    gps_sigma: float = 3.0
    scenarios: tuple[Scenario, ...] = SCENARIOS

    def __post_init__(self) -> None:
        if int(self.runs) < 2:
            raise ValueError(f"runs must be >= 2, got {self.runs}")
        if int(self.chunk) < 1:
            raise ValueError(f"chunk must be >= 1, got {self.chunk}")

    def to_dict(self) -> dict:
        return {"runs": int(self.runs), "seed": int(self.seed), "chunk": int(self.chunk),
                "level": self.level, "p0_std": self.p0_std, "v0_std": self.v0_std,
                "gps_sigma": self.gps_sigma,
                "scenarios": [s.to_dict() for s in self.scenarios]}


# ------------------------------------------------------------------ the runs
def _receiver(scn: Scenario, t_end: float, sigma: float):
    from bench.gnss import Receiver

    outages = ((t_end - scn.outage_s, t_end),) if scn.outage_s > 0 else ()
    return Receiver(rate_hz=scn.fix_hz, pos_sigma_m=sigma, outages=outages)


def _run_chunk(task: dict) -> dict:
    """Runs ``task['seeds']`` of one scenario: sums and per-run final errors of every method.

    Module-level and picklable (mapper contract, :mod:`calib.stats.runs`)."""
    from bench.gnss import simulate_fixes
    from bench.sensors import SensorErrorModel
    from bench.vehicle import apply_sensor_errors
    from calib.fusion.linear import fuse
    from calib.vehicle.region import arrival_region
    from calib.vehicle.trajectory import correct_and_integrate

    scn: Scenario = task["scenario"]
    t, pos, vel, acc = (task[k] for k in ("t", "pos", "vel", "acc"))
    bias, scale, cal_cov, nv = (task[k] for k in ("bias", "scale", "cal_cov", "noise_var"))
    cal = task["calibration"]
    p0_true, v0_true = pos[0], vel[0]
    receiver = _receiver(scn, float(t[-1]), task["gps_sigma"])
    L = np.linalg.cholesky(cal_cov)  # order [bias_x, scale_x, bias_y, scale_y]
    s0 = np.array([task["p0_std"], task["p0_std"], task["v0_std"], task["v0_std"]])
    p0_var = task["p0_std"] ** 2 * scn.p0_factor
    v0_var = task["v0_std"] ** 2 * scn.p0_factor
    nv_f = np.asarray(nv) * scn.q_factor
    sig_f = task["gps_sigma"] * np.sqrt(scn.r_factor)
    T = float(t[-1] - t[0])

    accs, zs, p0s, v0s, dr = [], [], [], [], {"sq": 0.0, "e": [], "P": []}
    fx = {"sq": 0.0, "n": 0, "e": [], "P": []}
    t_gps = None
    for ss in task["seeds"]:
        rng = np.random.default_rng(ss)
        d = L @ rng.standard_normal(4)
        sensor = SensorErrorModel.from_pairs(
            (bias[0] + d[0], bias[1] + d[2]), (scale[0] + d[1], scale[1] + d[3]), tuple(nv))
        e0 = s0 * rng.standard_normal(4)
        p0, v0 = p0_true + e0[:2], v0_true + e0[2:]
        a_m = apply_sensor_errors(acc, sensor, rng, t)
        fixes = simulate_fixes(receiver, t, pos, vel, rng)
        t_gps = fixes.t_gps
        accs.append(a_m), zs.append(fixes.pos), p0s.append(p0), v0s.append(v0)
        # dead reckoning
        traj = correct_and_integrate(t, a_m, bias, scale, p0, v0)
        reg = arrival_region(traj, cal, {"end": pos[-1]}, nv_f, task["level"])
        P = reg.cov + np.eye(2) * (p0_var + T * T * v0_var)
        e = traj.pos_corrected - pos
        dr["sq"] += float(np.sum(e * e))
        dr["e"].append(e[-1])
        dr["P"].append(P)
        # fixes alone
        k = np.searchsorted(t, t_gps - receiver.latency_s - 1e-9 * max(1.0, T))
        ef = fixes.pos - pos[k]
        fx["sq"] += float(np.sum(ef * ef))
        fx["n"] += ef.shape[0]
        fx["e"].append(ef[-1])
        fx["P"].append(np.eye(2) * task["gps_sigma"] ** 2)
        fx["path2"] = fx.get("path2", 0.0) + np.sum(ef * ef, axis=-1) / task["gps_sigma"] ** 2
    A = np.stack(accs)
    Z = np.stack(zs)
    P0s, V0s = np.stack(p0s), np.stack(v0s)
    # fuse takes one initial estimate for all runs: move each run into the frame where its
    # estimated start is the common one, positions shifted by f(t) = Δp + Δv·(t − t0). Exact:
    # f follows the model's free motion (p⁺ = p + v h, v⁺ = v), the readings are unchanged
    # and the covariances do not depend on the positions, so the estimates shift by f.
    dp = P0s - P0s[0]
    dv = V0s - V0s[0]
    Zs = Z - dp[:, None, :] - dv[:, None, :] * (t_gps - t[0])[None, :, None]
    out = fuse(t, A, t_gps, Zs, bias=bias, scale=scale, cal_cov=cal_cov, noise_var=nv_f,
               sigma_pos=sig_f, p0=P0s[0], v0=V0s[0], p0_cov=p0_var, v0_cov=v0_var,
               smoother=True)
    shift = dp[:, None, :] + dv[:, None, :] * (out.times - t[0])[None, :, None]
    node_k = np.searchsorted(t, out.times - 1e-9 * max(1.0, T))
    truth_p = pos[node_k]
    result = {"dead_reckoning": _final(dr, truth_len=t.shape[0], runs=len(task["seeds"])),
              "fixes": {**_final(fx, n=fx["n"]), "path": {"t": t_gps, "sum2": fx["path2"]}}}
    fix_nodes = np.flatnonzero(out.is_fix)
    truth_v = vel[node_k[fix_nodes]]
    for name, x, P in (("filter", out.estimates, out.covariances),
                       ("smoother", out.smoothed, out.smoothed_covariances)):
        p_est = x[..., :2] + shift
        e = p_est - truth_p[None]
        # along the path: position (2 dof) and position+velocity (4 dof) at the fix epochs
        # (the estimates shift by f(t) = Δp + Δv (t − t0), the velocities by Δv)
        e4 = np.concatenate([e[:, fix_nodes], x[:, fix_nodes, 2:4] + dv[:, None, :]
                             - truth_v[None]], axis=-1)
        P4 = P[:, fix_nodes, :4, :4]
        result[name] = {"sq": float(np.sum(e * e)), "n": int(e.shape[0] * e.shape[1]),
                        "e": e[:, -1], "P": P[:, -1, :2, :2],
                        "path": {"t": out.times[fix_nodes],
                                 "sum2": np.sum(nees(e4[..., :2], P4[..., :2, :2]), axis=0),
                                 "sum4": np.sum(nees(e4, P4), axis=0)}}
        if name == "filter" and scn.outage_s > 0:
            result["curve"] = {"t": out.times, "sq_axis": np.sum(e * e, axis=(0, 2)) / 2.0,
                               "var": np.mean(np.trace(P[..., :2, :2], axis1=-2,
                                                       axis2=-1), axis=0) / 2.0}
    return result


def _final(acc: dict, truth_len: int | None = None, runs: int = 0, n: int | None = None
           ) -> dict:
    count = n if n is not None else truth_len * runs
    return {"sq": acc["sq"], "n": int(count), "e": np.stack(acc["e"]), "P": np.stack(acc["P"])}


def _path(scenario: str, method: str, parts: list[dict], runs: int) -> PathNees | None:
    if "path" not in parts[0]:
        return None
    t = np.asarray(parts[0]["path"]["t"], float)
    m2 = sum(p["path"]["sum2"] for p in parts) / runs
    has4 = "sum4" in parts[0]["path"]
    m4 = sum(p["path"]["sum4"] for p in parts) / runs if has4 else np.zeros(0)
    tests = t.shape[0] * (2 if has4 else 1)  # Bonferroni over every epoch and both NEES
    band4 = path_band(4, runs, tests) if has4 else None
    return PathNees(scenario, method, tuple(t.tolist()), tuple(np.asarray(m2).tolist()),
                    path_band(2, runs, tests), tuple(np.asarray(m4).tolist()), band4)


def _row(scenario: str, method: str, parts: list[dict], level: float,
         path: PathNees | None = None) -> StudyRow:
    sq = sum(p["sq"] for p in parts)
    n = sum(p["n"] for p in parts)
    e = np.concatenate([p["e"] for p in parts])
    P = np.concatenate([p["P"] for p in parts])
    runs = e.shape[0]
    nees = np.einsum("ri,ri->r", e, np.linalg.solve(P, e[..., None])[..., 0])
    std = float(np.mean(np.sqrt(np.trace(P, axis1=-2, axis2=-1) / 2.0)))
    area = float(np.mean([Ellipse.from_cov(np.zeros(2), c, level).area for c in P]))
    lo, hi = mean_nees_band(2, runs)
    from calib.vehicle.region import chi2_2dof

    cov = float(np.mean(nees <= chi2_2dof(level)))
    cband = coverage_band(level, runs)
    m = float(np.mean(nees))
    extra = {}
    if path is not None:
        t = np.asarray(path.t)
        out2 = path.out(2)
        extra = {"path_band": path.band, "path_out_frac": float(np.mean(out2)),
                 "path_out_ranges": tuple(out_ranges(t, out2)),
                 "path_ok": bool(not out2.any()
                                 and (path.band4 is None or not path.out(4).any())),
                 "path_where": describe_ranges(out_ranges(t, out2), t[0], t[-1])}
        if path.band4 is not None:
            extra["path4_band"] = path.band4
            extra["path4_out_frac"] = float(np.mean(path.out(4)))
            extra["path4_where"] = describe_ranges(out_ranges(t, path.out(4)), t[0], t[-1])
    return StudyRow(scenario, method, float(np.sqrt(sq / n)), std, area, m, (lo, hi),
                    bool(lo <= m <= hi), cov, cband, bool(cband[0] <= cov <= cband[1]),
                    **extra)


def study_inputs(config: StudyConfig) -> dict:
    """Truth per IMU rate (MuJoCo, once) and the calibration (fitted once)."""
    from bench.tilt import CalibrationConfig, generate_calibration
    from bench.vehicle import COURSE_SENSOR, VehicleConfig, simulate_vehicle
    from calib.calibration.tilt_plane import calibrate
    from calib.files.course import Ensayo

    nv = np.array([COURSE_SENSOR.x.noise_var, COURSE_SENSOR.y.noise_var])
    run = generate_calibration(CalibrationConfig(sensor=COURSE_SENSOR), int(config.seed))
    cal = calibrate(Ensayo(run.tita, run.datos), nv)
    truths = {}
    for rate in sorted({s.imu_hz for s in config.scenarios}, reverse=True):
        tr = simulate_vehicle(replace(VehicleConfig(), rate=rate))
        truths[rate] = {"t": tr.t, "pos": tr.pos, "vel": tr.vel, "acc": tr.acc}
    return {"calibration": cal, "noise_var": nv, "truths": truths}


def run_study(config: StudyConfig | None = None, mapper: Mapper = serial_map,
              progress: Callable[[str], None] | None = None,
              count: Callable[[int, int], None] | None = None) -> StudyResult:
    """Run the comparison (module docstring). ``mapper`` runs the tasks (one per scenario and
    chunk of runs; :mod:`calib.stats.runs`); ``progress`` gets lines, ``count(done, total)`` task
    counts. Same ``(seed, runs)`` → same numbers, whatever the mapper or chunk size."""
    config = config or StudyConfig()
    if progress:
        progress("simulating the course run per IMU rate and fitting the calibration")
    inp = study_inputs(config)
    cal = inp["calibration"]
    seeds = run_seeds(config.seed, config.runs, (STUDY_STREAM,))
    tasks, owner = [], []
    for i, scn in enumerate(config.scenarios):
        for rng_ in chunk_ranges(config.runs, config.chunk):
            tasks.append({"scenario": scn, **inp["truths"][scn.imu_hz],
                          "bias": cal.bias, "scale": cal.scale, "cal_cov": cal.cov,
                          "calibration": cal, "noise_var": inp["noise_var"],
                          "seeds": [seeds[k] for k in rng_], "level": config.level,
                          "p0_std": config.p0_std, "v0_std": config.v0_std,
                          "gps_sigma": config.gps_sigma})
            owner.append(i)
    if progress:
        progress(f"{len(config.scenarios)} scenarios × {config.runs} runs in {len(tasks)} tasks")
    outs = mapper(_run_chunk, tasks, count)
    rows, curve, paths = [], None, []
    for i, scn in enumerate(config.scenarios):
        parts = [o for o, j in zip(outs, owner, strict=True) if j == i]
        for m in METHODS:
            path = _path(scn.name, m, [p[m] for p in parts], config.runs)
            if path is not None and m != "fixes":
                paths.append(path)
            rows.append(_row(scn.name, m, [p[m] for p in parts], config.level, path))
        if curve is None and "curve" in parts[0]:
            t = parts[0]["curve"]["t"]
            sq = sum(p["curve"]["sq_axis"] for p in parts) / config.runs
            var = sum(p["curve"]["var"] * len(tasks_seeds) for p, tasks_seeds in zip(
                parts, chunk_ranges(config.runs, config.chunk), strict=True)) / config.runs
            curve = (t, np.sqrt(var), np.sqrt(sq), float(t[-1]) - scn.outage_s)
    if curve is None:
        return StudyResult(config.to_dict(), tuple(rows), paths=tuple(paths))
    step = max(1, curve[0].shape[0] // 600)
    return StudyResult(config.to_dict(), tuple(rows), curve[0][::step], curve[1][::step],
                       curve[2][::step], curve[3], tuple(paths))


__all__ = ["METHODS", "NEES_ALPHA", "SCENARIOS", "STUDY_STREAM", "PathNees", "Scenario",
           "StudyConfig", "StudyResult", "StudyRow", "describe_ranges", "out_ranges",
           "path_band", "run_study", "study_inputs"]
