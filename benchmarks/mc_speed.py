"""Speed of the batched Monte Carlo (calib.calibration.montecarlo) as ratios against the RNG bound,
all measured in the same run.

    python benchmarks/mc_speed.py            # or: make bench
    python benchmarks/mc_speed.py --quick    # fewer runs and repeats (≈ 10 s)

At N = 20001 (the course design, θ a full turn; course σ² = 0.25, 0.64 (m/s²)²):

(a) bound: runs/s of drawing the 2N normals of each run alone, with the engine's stream setup
    (``Generator(PCG64(SeedSequence(seed, spawn_key=(k,))))``, ``standard_normal`` into one
    reused (2, N) buffer — faster than a fresh array per run, so the stricter bound);
(b) the engine, generate + calibrate, in this process (``--workers 1``): target ≥ 0.85 (a);
(c) the engine on a local pool of two processes (``bench.sweep.process_map(2)``, pool
    start-up included): target ≥ 1.6 (a);
(d) one ``calibrate()`` (per-axis OLS, σ² given, design cached from an earlier fit of the
    same θ) against generating its data (the reference ``A_r`` and the 2N normals):
    target ≤ 0.1; the first fit of a new design (cold cache) is shown beside it.

For context (c) is followed by the normals-only draws on the same two-process pool: what two
processes get on this machine at the time (≈ 2× when two cores are free, less when the
machine is shared), which bounds (c).

Each figure is the best of ``--repeat`` timings (``time.perf_counter``), BLAS at one thread.
The machine may be shared: absolute numbers move with the load, the ratios less so.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as the CLI does (bench/cli/__init__.py)

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from timing import best_of  # noqa: E402  (benchmarks/timing.py, beside this script)

from bench.sweep import process_map  # noqa: E402
from calib import Ensayo, calibrate  # noqa: E402
from calib.calibration.correct import apply_errors  # noqa: E402
from calib.calibration.montecarlo import simulate_calibrations  # noqa: E402
from calib.conventions import reference_accel  # noqa: E402
from calib.stats.runs import chunk_ranges, serial_map  # noqa: E402

N = 20001
BIAS, SCALE, NV = (0.0767, -0.0175), (-0.0301, 0.0100), (0.25, 0.64)
TARGETS = {"engine_1": 0.85, "engine_2": 1.6, "fit": 0.1}


def normals_only(runs: int, seed: int = 1) -> None:
    """The bound: each run's stream and its 2N normals, drawn into one reused buffer (the
    fastest way to draw them: a fresh (2, N) array per run costs page faults on top)."""
    buf = np.empty((2, N))
    for k in range(runs):
        ss = np.random.SeedSequence(seed, spawn_key=(k,))
        np.random.Generator(np.random.PCG64(ss)).standard_normal(out=buf)


def _normals_chunk(runs: range) -> int:
    buf = np.empty((2, N))
    for k in runs:
        ss = np.random.SeedSequence(1, spawn_key=(k,))
        np.random.Generator(np.random.PCG64(ss)).standard_normal(out=buf)
    return len(runs)


def normals_two_processes(runs: int) -> None:
    process_map(2)(_normals_chunk, chunk_ranges(runs, 256))


def measure(runs: int, repeat: int) -> dict[str, float]:
    theta = np.linspace(0.0, 2 * np.pi, N)

    def engine(mapper, r):
        return lambda: simulate_calibrations(theta, BIAS, SCALE, NV, r, 1, mapper=mapper)

    # interleaved (bound, engine, pool, bound, …) so a change of load hits all alike
    best = {"bound": np.inf, "engine_1": np.inf, "engine_2": np.inf, "bound_2": np.inf}
    for _ in range(repeat):
        best["bound"] = min(best["bound"], best_of(lambda: normals_only(runs), 1))
        best["bound_2"] = min(best["bound_2"], best_of(lambda: normals_two_processes(2 * runs), 1))
        best["engine_1"] = min(best["engine_1"], best_of(engine(serial_map, runs), 1))
        best["engine_2"] = min(best["engine_2"], best_of(engine(process_map(2), 2 * runs), 1))
    out = {"bound": runs / best["bound"], "engine_1": runs / best["engine_1"],
           "engine_2": 2 * runs / best["engine_2"], "bound_2": 2 * runs / best["bound_2"]}

    def generate():
        rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(1, spawn_key=(0,))))
        return apply_errors(reference_accel(theta), BIAS, SCALE) + np.sqrt(NV) * \
            rng.standard_normal((N, 2))

    ens = Ensayo(theta, generate())
    reps = 20 * repeat
    out["gen_ms"] = 1e3 * best_of(generate, reps)
    cold = []
    for i in range(repeat):  # a new design each time: θ shifted by a different tiny amount
        e2 = Ensayo(theta + 1e-9 * (i + 1), ens.datos)
        t0 = time.perf_counter()
        calibrate(e2, NV)
        cold.append(time.perf_counter() - t0)
    out["fit_cold_ms"] = 1e3 * min(cold)
    calibrate(ens, NV)  # warm the design cache
    out["fit_ms"] = 1e3 * best_of(lambda: calibrate(ens, NV), reps)
    return out


def report(m: dict[str, float]) -> list[str]:
    r1, r2 = m["engine_1"] / m["bound"], m["engine_2"] / m["bound"]
    rf, rc = m["fit_ms"] / m["gen_ms"], m["fit_cold_ms"] / m["gen_ms"]

    def verdict(ok: bool) -> str:
        return "PASS" if ok else "FAIL"

    return [
        f"N = {N}; runs/s best of repeats, BLAS 1 thread",
        f"(a) normals-only bound, 1 core        {m['bound']:9.0f} runs/s",
        f"(b) engine, 1 process                 {m['engine_1']:9.0f} runs/s   "
        f"{r1:5.2f}× bound  (target ≥ {TARGETS['engine_1']})  {verdict(r1 >= 0.85)}",
        f"(c) engine, 2 processes               {m['engine_2']:9.0f} runs/s   "
        f"{r2:5.2f}× bound  (target ≥ {TARGETS['engine_2']})  {verdict(r2 >= 1.6)}",
        f"    context: normals only, 2 processes {m['bound_2']:8.0f} runs/s   "
        f"{m['bound_2'] / m['bound']:5.2f}× bound  (what two processes get on this machine "
        "now; ≈ 2 when two cores are free)",
        f"(d) calibrate() fit (design cached)   {m['fit_ms']:9.3f} ms      "
        f"{rf:5.2f}× generating its data ({m['gen_ms']:.3f} ms)  (target ≤ "
        f"{TARGETS['fit']})  {verdict(rf <= 0.1)}",
        f"    calibrate() fit, new design       {m['fit_cold_ms']:9.3f} ms      {rc:5.2f}×",
    ]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer runs and repeats")
    ap.add_argument("--runs", type=int, default=None,
                    help="runs per timing (default 5000; twice that for two processes)")
    ap.add_argument("--repeat", type=int, default=None, help="timings per figure (3)")
    a = ap.parse_args(argv)
    runs = a.runs or (400 if a.quick else 5000)
    repeat = a.repeat or (2 if a.quick else 3)
    print("\n".join(report(measure(runs, repeat))))


if __name__ == "__main__":
    main()
