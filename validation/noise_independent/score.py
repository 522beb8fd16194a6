"""Coverage and twin closure on filtered static logs, at a run count the test suite cannot
afford (``tests/test_shaping.py`` runs R = 40).

    python -m validation.noise_independent.score [--calls 100] [--seed S] [--jobs 2]

Each call draws two axis-logs of 16 384 readings at 10 Hz from the independent generator
(:mod:`validation.noise_independent.generator`: white noise N = 2e-3 (m/s²)/√Hz and a flicker
bank B = 2e-4 m/s², not the bench's processes), passes them through a 4-pole Butterworth
low-pass at 0.3 Hz (scipy.signal: the export), and runs what ``tiltbench noise --twin`` runs:
:func:`calib.noise.allan.characterize_noise` (the filter read from the log,
:mod:`calib.noise.shaping`), the profile, its twin drawn by the bench
(:func:`bench.sensor_twin.simulate_axis`) and the closure test, and the same twin 1.5×
noisier. Reported, with binomial bands ``p ± 4·√(p(1−p)/R)``:

* how often the filter is read (it should be every time);
* coverage of N and B at the tool's level 0.683 (B: "not resolved, < upper" covers when the
  truth is below the upper bound);
* the closure's rejection of the true twin (α = 0.05) and of the 1.5× noisier one.

It asserts nothing (exit 0); docs/noise.md quotes its output.
"""

from __future__ import annotations

import argparse
import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy import signal

RATE = 10.0
N_SAMPLES = 2 ** 14
LEVEL = 0.683
CUT_HZ = 0.3


def one_call(seed: int) -> list[dict]:
    """Two axis-logs of one call (seeded): what the tool reported on each."""
    from bench.sensor_twin import simulate_axis, twin_axis
    from bench.sensors import AxisErrors
    from calib.noise.allan import characterize_noise
    from calib.noise.closure import closure_test, twin_adev
    from validation.noise_independent.generator import NoiseSpec, static_log

    spec = NoiseSpec(rate=RATE, white=2e-3, flicker=2e-4)
    rng = np.random.default_rng(seed)
    b, a = signal.butter(4, CUT_HZ, fs=RATE)
    cols = [signal.lfilter(b, a, static_log(spec, N_SAMPLES + 2000, rng)[0])[2000:]
            for _ in range(2)]
    res = characterize_noise(np.column_stack(cols), RATE, level=LEVEL, axes=("x", "y"))
    profile = res.to_profile()
    out = []
    for fit in res.axes:
        errors = twin_axis(profile, fit.axis, RATE)
        same = closure_test(fit, twin_adev(fit, simulate_axis(errors, N_SAMPLES, RATE, rng),
                                           RATE))
        louder_errors = AxisErrors(noise_var=errors.noise_var * 2.25,
                                   terms=tuple(_louder(t) for t in errors.terms))
        louder = closure_test(fit, twin_adev(fit, simulate_axis(louder_errors, N_SAMPLES,
                                                                RATE, rng), RATE))
        n_lo, n_hi = fit.term("white_noise_density").interval
        b_term = fit.term("bias_instability")
        b_lo, b_hi = b_term.interval
        out.append({"shaped": fit.export_filter is not None,
                    "n_cover": bool(n_lo <= spec.white_eff <= n_hi),
                    "b_cover": bool((b_lo if b_term.resolved else 0.0) <= spec.flicker
                                    <= b_hi),
                    "same": bool(same.reject), "louder": bool(louder.reject),
                    "full_range": bool(fit.octaves[0] == 0)})
    return out


def _louder(term):
    """A twin term 1.5× larger in Allan deviation (the export filter unchanged)."""
    from bench.terms import BiasInstability, BiasRandomWalk

    if isinstance(term, BiasInstability):
        return BiasInstability(b=term.b * 1.5)
    if isinstance(term, BiasRandomWalk):
        return BiasRandomWalk(q_per_sample=term.q_per_sample * 1.5)
    return term


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    p.add_argument("--calls", type=int, default=100, help="calls (two axis-logs each)")
    p.add_argument("--seed", type=int, default=20261129)
    p.add_argument("--jobs", type=int, default=2, help="worker processes")
    args = p.parse_args(argv)
    seeds = np.random.SeedSequence(args.seed).generate_state(args.calls).tolist()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = [r for call in pool.map(one_call, seeds) for r in call]
    r = len(rows)

    def rate(key: str) -> float:
        return sum(row[key] for row in rows) / r

    def band(p0: float) -> float:
        return 4.0 * math.sqrt(p0 * (1.0 - p0) / r)

    print(f"filtered static logs (4-pole Butterworth at {CUT_HZ} Hz, {N_SAMPLES} readings at "
          f"{RATE:g} Hz, N 2e-3, B 2e-4), R = {r} axis-logs, seed {args.seed}")
    print(f"  filter read: {rate('shaped'):.3f}; whole octave grid described: "
          f"{rate('full_range'):.3f}")
    print(f"  coverage at {LEVEL}: N {rate('n_cover'):.3f}, B {rate('b_cover'):.3f} "
          f"(band {LEVEL} ± {band(LEVEL):.3f})")
    print(f"  twin closure: true twin rejected {rate('same'):.3f} (α 0.05 ± "
          f"{band(0.05):.3f}), 1.5× noisier twin rejected {rate('louder'):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
