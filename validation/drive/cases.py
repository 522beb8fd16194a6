"""The fixed case list of the drive part, its split, and how one case is built from a seed.

A case is (category, what, axis, design, timing, sampling, rate, N, stated noise, size, file
format, how the noise is stated). The list does not depend on the seed; the seed draws the
nominal bias and scale, the design's random choices, the noise, the switching times and the
paths. Categories and the answer expected of ``tiltbench gap``:

* ``drive_state`` — a disturbance present only while the table moves (:data:`DRIVE_KINDS`):
  verdict ``unexplained``, its words saying it happens while moving;
* ``step_like`` — random telegraph noise (a bias switching between two levels), a single bias
  step, a staircase: verdict ``unexplained``, described as switching / steps, not as 1/f;
* ``nil`` — practically nil: raw integer counts whose step is 0.001–0.05 σ, or a catalog
  effect at 0.3 σ of its signature: verdict ``nothing_detected`` (the step may be reported,
  not named);
* ``clean`` — no effect (course ``.mat``, CSV in m/s², CSV in raw counts with
  ``--sensitivity``): ``nothing_detected``;
* ``catalog`` — one effect of docs/effects.md at 6–12 σ of its signature: ``explained`` with
  exactly the true names.

Sizes ("σ of the signature", all recorded in the truth): a change of the mean is
``‖P⊥Δ‖/σ`` (:func:`.sensor.z_mean`, bias and scale refitted; for drive-state and step-like
mechanisms with every parametric catalog signature projected out as well, so a miss is a
structure no catalog effect takes); a change of the noise variance is its χ² excess in σ,
``(σ²_extra/σ²)·√(N_m/2)`` over the N_m samples it touches (``noise_level``: all N; noise while
moving: the moving samples); quantization is the χ² excess of its rounding variance,
``(lsb²/12)/σ²·√(N/2)``. An effect on both axes has √Σ z_a² = z (each axis z/√2).

The split: ``heldout`` when ``int(sha256(SPLIT_SALT + ":" + case_id).hexdigest()[:8], 16) /
2**32 < HELDOUT_FRACTION``, else ``tune`` — by the case id only, the same for every seed.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from . import files
from . import motion as mdesign
from .sensor import (
    AXES,
    DRIVE_KINDS,
    G_UNIT,
    Draws,
    G,
    axis,
    mean_output,
    readings,
    z_mean,
)

SPLIT_SALT = "tiltbench-drive-2026"
HELDOUT_FRACTION = 0.4
FORMAT = "tiltbench-drive-truth/1"

NOISE_SETS = ((0.25, 0.64), (0.04, 0.09), (0.01, 0.0225), (0.0025, 0.0049))
"""Stated noise variances (x, y), (m/s²)²; the course's first."""

CATEGORIES = ("drive_state", "step_like", "nil", "clean", "catalog")
EXPECTED = {"drive_state": "unexplained", "step_like": "unexplained",
            "nil": "nothing_detected", "clean": "nothing_detected", "catalog": "explained"}

MOVING_WORDS = (r"(?i)\b(while|when|whenever|only (when|while)) ((the table|it) (is )?)?"
                r"mov(ing|es)\b|during (the )?(moves|motion|movement|moving)|in motion")
WORDS = {
    "drive_state": {"any": [MOVING_WORDS], "none": []},
    "telegraph": {"any": [r"(?i)two[- ]level|telegraph|switch(es|ing)? between|bistable"],
                  "none": [r"(?i)1/f"]},
    "bias_step": {"any": [r"(?i)\bstep\b|\bjump\b"], "none": [r"(?i)1/f"]},
    "staircase": {"any": [r"(?i)\bsteps\b|staircase|\bjumps\b"], "none": [r"(?i)1/f"]},
}
"""What the unexplained descriptions should say (regular expressions, Python ``re``): at least
one description matches one of ``any`` and none matches ``none``."""


@dataclass(frozen=True)
class CaseDef:
    category: str
    what: str                      # mechanism kind, catalog effect, "fine_counts", "clean"
    axis: str                      # x | y | both | -
    design: str
    timing: str = "t"              # t | rate | none
    sampling: str = "uniform"      # uniform | jitter
    rate: float = 100.0
    n: int = 4001
    noise: int = 0                 # index into NOISE_SETS
    z: float = 0.0                 # size in σ (fine_counts: the step in σ)
    fmt: str = "mat"               # mat | csv_ms2 | csv_counts
    stated_by: str = "noise_var"   # noise_var | datos
    count: int = 0                 # telegraph: switches; staircase: steps
    tag: str = ""

    @property
    def case_id(self) -> str:
        pre = {"drive_state": "drv", "step_like": "stp", "nil": "nil", "clean": "cln",
               "catalog": "cat"}[self.category]
        samp = "j" if self.sampling == "jitter" else ""
        z = f"-z{self.z:g}" if self.category != "clean" else ""
        k = f"-k{self.count}" if self.count else ""
        tag = f"-{self.tag}" if self.tag else ""
        fmt = {"mat": "mat", "csv_ms2": "csvms2", "csv_counts": "csvcnt"}[self.fmt]
        dat = "-datos" if self.stated_by == "datos" else ""
        return (f"{pre}-{self.what}-{self.axis}-{self.design}-{self.timing}{samp}-r{self.rate:g}"
                f"-{fmt}-n{self.n}-s{self.noise}{z}{k}{dat}{tag}").replace("_", "")


def split_of(case_id: str) -> str:
    """``tune`` or ``heldout`` (module docstring)."""
    h = hashlib.sha256(f"{SPLIT_SALT}:{case_id}".encode()).hexdigest()
    return "heldout" if int(h[:8], 16) / 2**32 < HELDOUT_FRACTION else "tune"


MOV = mdesign.MOVING_DESIGNS


def _drive_cases() -> list[CaseDef]:
    out = []
    for k, kind in enumerate(DRIVE_KINDS):
        for j, z in enumerate((5.0, 8.0, 12.0, 20.0)):
            fmt = "csv_ms2" if j == 2 else ("csv_counts" if (j == 3 and k % 2) else "mat")
            out.append(CaseDef("drive_state", kind, ("x", "y", "both", "y")[(k + j) % 4],
                               MOV[(k + j) % 4], ("t", "rate")[(k + j) % 2],
                               "jitter" if (k + j) % 5 == 0 and (k + j) % 2 == 0 else "uniform",
                               (100.0, 200.0)[k % 2], (4001, 6001)[j % 2], (k + 2 * j) % 4,
                               z, fmt))
    return out


def _step_cases() -> list[CaseDef]:
    S = "step_like"
    return [
        CaseDef(S, "telegraph", "x", "stopgo_dwell", "t", n=4001, noise=0, z=6.0, count=4),
        CaseDef(S, "telegraph", "y", "pose_tour", "rate", rate=200, n=6001, noise=1, z=8.0,
                count=8),
        CaseDef(S, "telegraph", "x", "pose_holds", "none", n=4001, noise=2, z=10.0, count=12),
        CaseDef(S, "telegraph", "y", "sweep_pause", "t", "jitter", n=6001, noise=3, z=12.0,
                count=20, fmt="csv_ms2"),
        CaseDef(S, "telegraph", "both", "shuttle", "rate", n=4001, noise=0, z=16.0, count=6),
        CaseDef(S, "telegraph", "x", "pose_tour", "t", n=6001, noise=1, z=20.0, count=30,
                fmt="csv_counts"),
        CaseDef(S, "bias_step", "y", "stopgo_dwell", "rate", n=4001, noise=1, z=6.0),
        CaseDef(S, "bias_step", "x", "pose_holds", "t", n=6001, noise=0, z=10.0),
        CaseDef(S, "bias_step", "y", "shuttle", "t", n=4001, noise=2, z=16.0, fmt="csv_counts"),
        CaseDef(S, "staircase", "x", "sweep_pause", "rate", rate=200, n=6001, noise=3, z=8.0,
                count=3),
        CaseDef(S, "staircase", "y", "pose_holds", "none", n=4001, noise=1, z=10.0, count=4),
        CaseDef(S, "staircase", "both", "pose_tour", "t", n=6001, noise=0, z=14.0, count=5),
    ]


def _nil_cases() -> list[CaseDef]:
    N = "nil"
    fine = [CaseDef(N, "fine_counts", "both", MOV[i % 4], ("t", "rate")[i % 2],
                    rate=(100.0, 200.0, 50.0)[i % 3], n=(3001, 4001, 6001)[i % 3],
                    noise=i % 4, z=r, fmt="csv_counts",
                    stated_by="datos" if i == 3 else "noise_var")
            for i, r in enumerate((0.001, 0.002, 0.005, 0.01, 0.02, 0.03, 0.05, 0.05))]
    fine.append(CaseDef(N, "fine_counts", "both", "pose_holds", "none", n=4001, noise=0,
                        z=0.02, fmt="mat"))
    tiny = [CaseDef(N, w, ax, d, tm, n=4001, noise=s, z=0.3)
            for w, ax, d, tm, s in (
                ("misalignment", "x", "pose_tour", "t", 0),
                ("tilt_offset", "both", "stopgo_dwell", "none", 1),
                ("nonlinearity_k2", "y", "pose_holds", "none", 2),
                ("cross_axis", "x", "shuttle", "rate", 3),
                ("bias_drift", "y", "sweep_pause", "t", 0),
                ("lowpass_lag", "x", "shuttle", "t", 1),
                ("noise_level", "y", "pose_tour", "rate", 2),
                ("saturation", "x", "pose_holds", "t", 0))]
    return fine + tiny


def _catalog_cases() -> list[CaseDef]:
    C = "catalog"
    rows = (
        ("noise_level", "x", "stopgo_dwell", "t", "uniform", "mat", 8),
        ("noise_level", "y", "pose_tour", "rate", "uniform", "csv_ms2", 10),
        ("noise_level", "both", "pose_holds", "none", "holds", "mat", 7),
        ("misalignment", "x", "sweep_pause", "t", "uniform", "mat", 8),
        ("misalignment", "y", "pose_holds", "none", "holds", "mat", 10),
        ("misalignment", "x", "shuttle", "rate", "uniform", "csv_counts", 6),
        ("tilt_offset", "both", "pose_tour", "t", "jitter", "mat", 9),
        ("tilt_offset", "both", "stopgo_dwell", "none", "uniform", "mat", 7),
        ("tilt_offset", "both", "shuttle", "t", "uniform", "csv_ms2", 11),
        ("nonlinearity_k2", "x", "pose_tour", "rate", "uniform", "mat", 8),
        ("nonlinearity_k2", "y", "sweep_pause", "t", "uniform", "csv_counts", 10),
        ("nonlinearity_k2", "x", "pose_holds", "none", "holds", "mat", 12),
        ("cross_axis", "y", "stopgo_dwell", "t", "uniform", "mat", 8),
        ("cross_axis", "x", "pose_holds", "t", "holds", "mat", 10),
        ("cross_axis", "y", "shuttle", "rate", "uniform", "mat", 6),
        ("bias_drift", "x", "shuttle", "t", "uniform", "mat", 8),
        ("bias_drift", "y", "pose_tour", "none", "uniform", "mat", 10),
        ("bias_drift", "x", "sweep_pause", "rate", "uniform", "csv_ms2", 7),
        ("bias_random_walk", "y", "sweep_pause", "t", "uniform", "mat", 10),
        ("bias_random_walk", "x", "pose_holds", "none", "holds", "mat", 12),
        ("bias_random_walk", "y", "stopgo_dwell", "rate", "uniform", "mat", 10),
        ("quantization", "x", "pose_tour", "t", "uniform", "mat", 8),
        ("quantization", "both", "stopgo_dwell", "rate", "uniform", "mat", 10),
        ("quantization", "y", "pose_holds", "none", "holds", "mat", 7),
        ("saturation", "x", "pose_tour", "t", "uniform", "mat", 8),
        ("saturation", "y", "shuttle", "rate", "uniform", "mat", 10),
        ("saturation", "x", "pose_holds", "none", "holds", "mat", 12),
        ("lowpass_lag", "x", "shuttle", "t", "uniform", "mat", 8),
        ("lowpass_lag", "y", "pose_tour", "rate", "uniform", "mat", 10),
        ("lowpass_lag", "x", "stopgo_dwell", "t", "jitter", "csv_ms2", 9),
        # added after the first tune scoring, which had no quantization case (the three
        # above are all held out); the first two added fell in the held-out part too
        ("quantization", "y", "sweep_pause", "t", "uniform", "mat", 9),
        ("quantization", "x", "shuttle", "rate", "uniform", "mat", 11),
        ("quantization", "both", "pose_tour", "rate", "uniform", "mat", 8),
        ("quantization", "x", "sweep_pause", "none", "uniform", "mat", 12),
    )
    return [CaseDef(C, w, ax, d, tm, "uniform" if s == "holds" else s,
                    rate=(100.0, 200.0)[i % 2], n=(4001, 6001)[i % 2], noise=i % 4, z=float(z),
                    fmt=f, stated_by="datos" if i % 7 == 3 else "noise_var")
            for i, (w, ax, d, tm, s, f, z) in enumerate(rows)]


CLEAN_COUNTS = {"csv_counts": 110, "csv_ms2": 60, "mat": 150}
"""Clean runs per file format (320 in all)."""


def _clean_cases() -> list[CaseDef]:
    """320 clean runs over every design, timing, rate and noise level, N 2001–6001. The list
    is drawn once from a fixed generator (not the set's seed), so the ids never change."""
    rng = np.random.default_rng(20261129)
    out = []
    i = 0
    for fmt, count in CLEAN_COUNTS.items():
        for _ in range(count):
            design = str(rng.choice(mdesign.DESIGNS if fmt == "mat" else MOV))
            if design == "pose_holds":
                timing = str(rng.choice(["none", "t"]))
            else:
                timing = str(rng.choice(["t", "rate", "none"], p=[0.45, 0.4, 0.15]))
            sampling = "jitter" if timing == "t" and design != "pose_holds" \
                and rng.uniform() < 0.3 else "uniform"
            out.append(CaseDef("clean", "clean", "-", design, timing, sampling,
                               rate=float(rng.choice([50.0, 100.0, 200.0])),
                               n=int(rng.integers(2001, 6002)), noise=int(rng.integers(0, 4)),
                               fmt=fmt, stated_by="datos" if rng.uniform() < 0.2 else "noise_var",
                               tag=f"c{i:03d}"))
            i += 1
    return out


CASES: tuple[CaseDef, ...] = tuple(_drive_cases() + _step_cases() + _nil_cases()
                                   + _catalog_cases() + _clean_cases())


def case_by_id() -> dict[str, CaseDef]:
    out = {c.case_id: c for c in CASES}
    if len(out) != len(CASES):
        raise RuntimeError("two cases share an id")
    return out


def case_rng(seed: int, case_id: str) -> np.random.Generator:
    """One stream per (seed, case id): a case's arrays do not depend on what else is built."""
    key = int(hashlib.sha256(case_id.encode()).hexdigest()[:16], 16)
    return np.random.default_rng(np.random.SeedSequence([seed, key]))


# --- building one case ----------------------------------------------------------------------

def _solve(zf, lo: float, hi: float, target: float) -> float:
    """s in [lo, hi] with zf(s) = target (zf increasing there)."""
    if zf(hi) < target:
        raise ValueError(f"size {target} σ not reached at {hi:g}")
    return float(brentq(lambda s: zf(s) - target, lo, hi, xtol=1e-14, rtol=1e-11))


def _axes(ax: str) -> tuple[str, ...]:
    return AXES if ax in ("both", "-") else (ax,)


def _with(base: dict, axes, **kv) -> dict:
    spec = {**base, "axes": {a: dict(p) for a, p in base["axes"].items()}}
    for a in axes:
        spec["axes"][a].update(kv)
    return spec


def _catalog(c: CaseDef, mo, base: dict, sign: float):
    """(spec, params per axis in docs/effects.md keys, size note) of a catalog effect."""
    axes = _axes(c.axis)
    w, z = c.what, c.z
    n = mo.n
    timed = mo.timing != "none"
    sig2 = {a: base["axes"][a]["sigma2"] for a in AXES}
    per = z / np.sqrt(len(axes))            # each axis' share of a pooled size

    def mean_size(key, hi, lo=0.0):
        return sign * _solve(lambda s: z_mean(mo, base, _with(base, axes, **{key: sign * s})),
                             lo, hi, z)

    if w == "noise_level":
        spec, params = _with(base, ()), {}
        for a in axes:
            spec["axes"][a]["sigma2"] = sig2[a] * (1.0 + per * np.sqrt(2.0 / n))
            params[a] = {"sigma2": spec["axes"][a]["sigma2"]}
        return spec, params, f"χ² excess {z:g} σ (σ²_true/σ² − 1 = {per * np.sqrt(2 / n):.4f})"
    if w == "quantization":
        spec, params = _with(base, ()), {}
        for a in axes:
            lsb = float(np.sqrt(12.0 * sig2[a] * per * np.sqrt(2.0 / n)))
            spec["axes"][a]["lsb"] = lsb
            params[a] = {"lsb": lsb}
        ratio = ", ".join(f"{a}: lsb = {params[a]['lsb'] / np.sqrt(sig2[a]):.2f} σ" for a in axes)
        return spec, params, f"rounding-variance χ² excess {z:g} σ ({ratio})"
    if w == "tilt_offset":
        d = sign * _solve(lambda s: z_mean(mo, base, {**base, "tilt_offset": sign * s}),
                          0.0, 0.5, z)
        return {**base, "tilt_offset": d}, {"both": {"delta": d}}, f"z = {z:g}"
    if w == "saturation":
        a = axes[0]

        def zl(lim):
            return z_mean(mo, base, _with(base, axes, limit=lim))
        lim = _solve(lambda s: -zl(s), 0.3 * G, G * (1.0 - 1e-12), -z)
        return _with(base, axes, limit=lim), {a: {"limit": lim}}, f"z = {z:g}"
    if w == "bias_random_walk":
        a = axes[0]
        unit = z_mean(mo, base, _with(base, axes, q=1.0), beyond_catalog=True)
        q = z / unit
        key = "q" if timed else "q_per_sample"
        return (_with(base, axes, q=q), {a: {key: q}},
                f"z = {z:g} on the drawn path, beyond every parametric catalog signature")
    key, pkey, hi = {"misalignment": ("misalignment", "delta", 0.5),
                     "nonlinearity_k2": ("k2", "k2", 0.05),
                     "cross_axis": ("k_ip", "k_ip", 0.05),
                     "bias_drift": ("drift", "rate" if timed else "rate_per_sample", 1.0),
                     "lowpass_lag": ("tau", "tau", 2.0)}[w]
    if w == "lowpass_lag":
        v = _solve(lambda s: z_mean(mo, base, _with(base, axes, tau=s)), 1e-7, hi, z)
    else:
        v = mean_size(key, hi)
    return _with(base, axes, **{key: v}), {axes[0]: {pkey: v}}, f"z = {z:g}"


def _mechanism(c: CaseDef, mo, base: dict, rng, sign: float):
    """(spec, mechanism dict, size note) of a drive-state or step-like mechanism."""
    w, z = c.what, c.z
    axes = _axes(c.axis)
    dur = float(mo.time[-1] - mo.time[0])
    mech: dict = {"kind": w, "axis": c.axis}
    if w == "move_noise":
        nm = int(mo.moving.sum())
        per = z / np.sqrt(len(axes))
        # per axis: extra variance s² with (s²/σ²)·√(N_m/2) = z/√(axes)
        mech["s"] = {a: float(np.sqrt(base["axes"][a]["sigma2"] * per * np.sqrt(2.0 / nm)))
                     for a in axes}
        ratio = ", ".join(f"{a}: {mech['s'][a] / np.sqrt(base['axes'][a]['sigma2']):.3f} σ"
                          for a in axes)
        return ({**base, "mechanisms": [mech]}, mech,
                f"χ² excess {z:g} σ over the {nm} moving samples (extra std {ratio})")
    key = {"move_vibration": "amp", "move_gain": "eps", "move_bias": "b", "speed_bias": "c",
           "accel_bias": "c", "accel_gain": "kappa", "telegraph": "h", "bias_step": "h",
           "staircase": "h"}[w]
    if w == "move_vibration":
        mech["freq"] = float(mo.rate_hz * rng.uniform(0.05, 0.2))
        mech["phase"] = float(rng.uniform(0, 2 * np.pi))
    elif w == "telegraph":
        mech["switch_times"] = np.sort(rng.uniform(0.05, 0.95, c.count) * dur).tolist()
        mech["start"] = int(rng.integers(0, 2))
    elif w == "bias_step":
        mech["at"] = float(rng.uniform(0.3, 0.7) * dur)
    elif w == "staircase":
        mech["at"] = np.sort(rng.uniform(0.1, 0.9, c.count) * dur).tolist()

    def zf(s):
        return z_mean(mo, base, {**base, "mechanisms": [{**mech, key: s}]}, beyond_catalog=True)
    unit = zf(1.0)            # every one of these is linear in its size parameter
    mech[key] = sign * z / unit
    spec = {**base, "mechanisms": [mech]}
    got = z_mean(mo, base, spec, beyond_catalog=True)
    if abs(got - z) > 1e-6 * z:
        raise RuntimeError(f"{c.case_id}: size {got} instead of {z}")
    return spec, mech, f"z = {z:g} beyond every parametric catalog signature"


def _fine_counts(c: CaseDef, base: dict) -> tuple[float, str]:
    """Counts per g whose step is c.z of the smaller stated σ."""
    sig = min(np.sqrt(base["axes"][a]["sigma2"]) for a in AXES)
    return G_UNIT / (c.z * sig), f"count step {c.z:g} σ of the smaller axis (σ = {sig:g} m/s²)"


def build(c: CaseDef, seed: int):
    """(motion, readings (N, 2) m/s², truth) of one case; the truth holds the file to write
    (``file``) and the options of ``tiltbench gap`` (``options``, ``gap_args``)."""
    rng = case_rng(seed, c.case_id)
    mo = mdesign.make(c.design, rng, c.n, c.rate, c.timing, c.sampling)
    stated = NOISE_SETS[c.noise]
    draws = Draws.draw(rng, mo.n)
    base = {"g": G, "tilt_offset": 0.0, "mechanisms": [], "draws": draws, "axes": {
        a: axis(float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.03, 0.03)), stated[i])
        for i, a in enumerate(AXES)}}
    sign = 1.0 if rng.uniform() < 0.5 else -1.0
    sens = None
    effects: list[dict] = []
    mech = None
    size = {"z_target": c.z if c.category != "clean" else None, "z": None,
            "z_beyond_catalog": None, "note": "no effect"}
    if c.category == "catalog" or (c.category == "nil" and c.what != "fine_counts"):
        spec, params, note = _catalog(c, mo, base, sign)
        if c.category == "catalog":
            effects = [{"name": c.what, "axis": a, "params": p} for a, p in params.items()]
        size["note"] = note
        size["params"] = params
        if c.what not in ("noise_level", "quantization"):
            size["z"] = z_mean(mo, base, spec)
            # the size left once every *other* parametric catalog signature is projected
            # out: small would mean the design cannot tell this effect from another
            size["z_beyond_other_catalog"] = z_mean(mo, base, spec, beyond_catalog=True,
                                                    exclude=c.what)
    elif c.category in ("drive_state", "step_like"):
        spec, mech, note = _mechanism(c, mo, base, rng, sign)
        size["note"] = note
        if c.what != "move_noise":
            size["z"] = z_mean(mo, base, spec)
            size["z_beyond_catalog"] = z_mean(mo, base, spec, beyond_catalog=True)
    else:
        spec = base
    if c.fmt == "csv_counts":
        if c.what == "fine_counts":
            sens, note = _fine_counts(c, base)
            size["note"] = note
        else:
            # a realistic converter: the count step 0.001–0.03 σ of the smaller axis
            r = float(np.exp(rng.uniform(np.log(0.001), np.log(0.03))))
            sens = G_UNIT / (r * min(np.sqrt(stated)))
    elif c.what == "fine_counts":   # the same step, in m/s² in a course file
        spec = _with(spec, AXES)
        step = c.z * min(np.sqrt(stated))
        for a in AXES:
            spec["axes"][a]["lsb"] = step
        size["note"] = f"readings rounded to {c.z:g} σ of the smaller axis"
    datos = readings(mo, spec)
    fp = files.plan(c.fmt, c.timing, c.rate, stated, c.stated_by, sens, rng)
    truth = _truth(c, seed, mo, spec, effects, mech, size, stated, sens)
    truth.update(fp)
    truth["gap_args"] = files.gap_args(fp["options"])
    return mo, datos, truth


def _jsonable(spec_axes: dict) -> dict:
    return {a: dict(p) for a, p in spec_axes.items()}


def _truth(c, seed, mo, spec, effects, mech, size, stated, sens) -> dict:
    lsb = {a: (G_UNIT / sens if sens else spec["axes"][a]["lsb"]) for a in AXES}
    words = WORDS.get("drive_state" if c.category == "drive_state" else c.what)
    mu = mean_output(mo, spec)
    return {
        "format": FORMAT, "case_id": c.case_id, "split": split_of(c.case_id), "seed": seed,
        "category": c.category, "what": c.what, "axis": c.axis, "design": c.design,
        "timing": c.timing, "sampling": mo.sampling, "rate_hz": c.rate, "n": mo.n,
        "noise_var": list(stated), "g": G,
        "expected": {"verdict": EXPECTED[c.category], "effects": effects,
                     "words": words if c.category in ("drive_state", "step_like") else None},
        "mechanism": mech,
        "size": size,
        "quantization_step": {a: lsb[a] for a in AXES},
        "quantization_step_over_sigma": {
            a: (None if lsb[a] is None else lsb[a] / np.sqrt(stated[i]))
            for i, a in enumerate(AXES)},
        "sensor": {"g": spec.get("g", G), "tilt_offset": spec.get("tilt_offset", 0.0),
                   "axes": _jsonable(spec["axes"])},
        "motion": mo.summary(),
        "mean_reading_range": [float(mu.min()), float(mu.max())],
        "units": {"noise_var": "(m/s²)²", "rate_hz": "Hz", "n": "count", "g": "m/s²",
                  "size.z": "σ (1)", "size.z_target": "σ (1)", "size.z_beyond_catalog": "σ (1)",
                  "size.z_beyond_other_catalog": "σ (1)",
                  "quantization_step": "m/s²", "quantization_step_over_sigma": "1",
                  "expected.effects.params": "docs/effects.md units per key",
                  "sensor.axes.*.bias": "m/s²", "sensor.axes.*.scale": "1",
                  "sensor.axes.*.sigma2": "(m/s²)²", "sensor.tilt_offset": "rad",
                  "mechanism.b": "m/s²", "mechanism.c (speed_bias)": "m/s² per rad/s",
                  "mechanism.c (accel_bias)": "m/s² per rad/s²", "mechanism.eps": "1",
                  "mechanism.kappa": "1 per rad/s²", "mechanism.amp": "m/s²",
                  "mechanism.freq": "Hz", "mechanism.phase": "rad",
                  "mechanism.s.*": "m/s²", "mechanism.h": "m/s²", "mechanism.at": "s",
                  "mechanism.switch_times": "s",
                  "motion.theta_min": "rad", "motion.theta_max": "rad",
                  "motion.omega_max": "rad/s", "motion.alpha_max": "rad/s²",
                  "motion.duration": "s", "mean_reading_range": "m/s²",
                  "file.sensitivity": "counts per g", "file.count_step": "m/s²",
                  "options.noise_var": "(m/s²)²", "options.rate": "Hz",
                  "options.sensitivity": "counts per g"},
    }


__all__ = ["CASES", "CATEGORIES", "CLEAN_COUNTS", "EXPECTED", "FORMAT", "HELDOUT_FRACTION",
           "NOISE_SETS", "SPLIT_SALT", "WORDS", "CaseDef", "build", "case_by_id", "case_rng",
           "split_of"]
