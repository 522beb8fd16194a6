"""``tiltbench demo``: the whole job end to end on embedded defaults.

Steps (each timed; its start and end go to the optional progress callback):

1. generate a course set with the bench (:func:`bench.course.make_course_set`, MuJoCo tilt
   table and vehicle) into ``OUT/data`` — or, with ``course_data``, use real course files;
2. calibrate ``ensayo.mat`` (per-axis OLS, noise variances from ``datos.txt``: the same as
   ``tiltbench calibrate OUT/data/ensayo.mat --datos OUT/data/datos.txt --json``);
3. correct and integrate ``acel.mat``, confidence region of the arrival point and decision
   (``tiltbench trajectory``), N analysis (:mod:`calib.vehicle.nmin`);
4. validate the estimates against ``truth.json`` (:mod:`bench.validate`) and check the
   honesty of the intervals on fresh synthetic calibrations with the same design (Monte
   Carlo pass rate of the joint test against its level);
5. fusion with position fixes (:func:`calib.fusion.linear.fuse`): on a generated set, fixes of the
   default receiver (:class:`bench.gnss.Receiver`: 1 Hz, σ = 3 m) simulated on the same MuJoCo
   run with the seed's receiver stream (the fixes ``tiltbench generate course --seed S --gps``
   writes); on course files, their ``gps.mat`` if there is one (else the step says it is
   skipped and why); the fused final-position std against dead reckoning's;
6. figures (:mod:`bench.figures`), a rerun recording (:mod:`bench.record`, read back to check
   that truth and estimates are recoverable) and a Markdown report.

Outputs in ``OUT``: ``data/`` (the student's files + ``truth.json``), ``estimates.json``,
``trajectory.json``, ``validation.json``, ``figures/*.png`` and ``*.svg``, ``demo.rrd``,
``report.md``.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from calib.calibration.tilt_plane import Calibration, calibrate
from calib.conventions import AXES, G
from calib.files.atomic import atomic_dir, write_text
from calib.files.course import (
    Acel,
    Ensayo,
    dumps,
    read_acel,
    read_datos,
    read_ensayo,
    read_puntos,
)
from calib.stats.runs import Mapper, serial_map
from calib.vehicle.region import ArrivalRegion, arrival_region
from calib.vehicle.report import trajectory_tree
from calib.vehicle.trajectory import Trajectory, compute_trajectory

DEFAULT_SEED = 0
"""Seed of the embedded demo (the generators' default seed)."""
DEFAULT_LEVEL = 0.997
"""Level of the arrival region (the course's 3σ ≈ 99.7 %)."""
VALIDATE_LEVEL = 0.99
"""Level of the ground-truth test (``tiltbench validate`` default)."""
COVERAGE_RUNS = 2000
"""Fresh synthetic calibrations in the coverage check: with the batched engine (≈ 0.5 ms a
run) 2,000 runs cost about a second and pin the pass rate to ± 0.019 (4 binomial σ at 0.95);
300 runs allowed only ± 0.050."""
COVERAGE_LEVEL = 0.95
"""Level of the coverage check (0.95: about 100 expected failures in 2,000 runs, so a rate far
from the level is visible; at 0.99 the check would have little power)."""

OUTPUT_NAMES = ("estimates.json", "trajectory.json", "validation.json", "demo.rrd",
                "report.md")


class _Steps:
    """Numbered, timed steps: ``[k/total] label ...`` before and ``[k/total] label: done
    (1.23 s)`` after each, through the progress callback; the times go into the report."""

    def __init__(self, labels: list[str], progress: Callable[[str], None] | None) -> None:
        self.labels = labels
        self.progress = progress
        self.k = 0
        self.t0 = time.perf_counter()
        self.times: dict[str, float] = {}

    @contextmanager
    def step(self) -> Iterator[None]:
        label = self.labels[self.k]
        self.k += 1
        head = f"[{self.k}/{len(self.labels)}] {label}"
        if self.progress:
            self.progress(f"{head} ...")
        start = time.perf_counter()
        yield
        dt = time.perf_counter() - start
        self.times[label] = dt
        if self.progress:
            self.progress(f"{head}: done ({dt:.2f} s)")

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.t0


@dataclass
class CourseAnalysis:
    """Calibration, trajectory and decision of one course set (files already read)."""

    ensayo: Ensayo
    acel: Acel
    candidates: dict[str, np.ndarray]
    p0: np.ndarray
    v0: np.ndarray
    noise_var: np.ndarray | None
    cal: Calibration
    traj: Trajectory
    region: ArrivalRegion
    method: str = "ols"
    warnings: list[str] = field(default_factory=list)

    def trajectory_json(self) -> dict:
        return trajectory_tree(self.traj, self.region, self.cal, self.method,
                               "given" if self.noise_var is not None else "estimated")


def analyze_course_dir(course_dir: str | Path, level: float = DEFAULT_LEVEL,
                       method: str = "ols") -> CourseAnalysis:
    """Read ``ensayo.mat``, ``acel.mat``, ``puntos.mat`` and ``datos.txt`` of a course set and
    run calibration, trajectory and decision (as ``tiltbench trajectory --datos``)."""
    d = Path(course_dir)
    ensayo = read_ensayo(d / "ensayo.mat")
    acel = read_acel(d / "acel.mat")
    candidates = read_puntos(d / "puntos.mat")
    datos = read_datos(d / "datos.txt")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = calibrate(ensayo, datos.noise_var, method)  # type: ignore[arg-type]
    traj = compute_trajectory(acel, cal, datos.p0, datos.v0)
    region = arrival_region(traj, cal, candidates, datos.noise_var, level)
    return CourseAnalysis(ensayo, acel, candidates, datos.p0, datos.v0, datos.noise_var, cal,
                          traj, region, method, [str(w.message) for w in caught])


def _count_progress(progress, what: str) -> Callable[[int, int], None] | None:
    """``progress(done, total)`` for a sweep: a :class:`bench.cli.progress.Progress` counter
    when the caller passed one, else a line per update, else None."""
    if progress is None:
        return None
    if hasattr(progress, "count"):
        return lambda done, total: progress.count(done, total, what)
    return lambda done, total: progress(f"{what} {done}/{total}")


def coverage_check(truth: dict, runs: int = COVERAGE_RUNS, level: float = COVERAGE_LEVEL,
                   seed: int = 0, mapper: Mapper = serial_map,
                   progress: Callable[[int, int], None] | None = None) -> dict:
    """Pass rate of :func:`bench.validate.validate` on fresh synthetic calibrations.

    Each run redraws the readings of the truth's design (θ rebuilt from ``truth.json``) with
    the course model and the true parameters (numpy, no MuJoCo: the static table reproduces
    ``[-g sin θ, -g cos θ]`` to 1e-15), calibrates with known σ² and applies the joint test.
    The runs are the batched engine :func:`calib.calibration.montecarlo.simulate_calibrations` (run
    k's stream: ``SeedSequence(seed, spawn_key=(7, k))``; ``mapper`` and the chunking do not
    change the numbers). The joint test
    ``d² = eᵀΣ⁻¹e ≤ χ²₄(level)`` and the per-parameter ``|z| ≤ q`` are evaluated for all runs
    at once; the constants of the test (quantiles, the std check, which is the same for
    every run since σ² is known) come from :func:`bench.validate.validate` on run 0.
    An honest estimator passes with probability ``level``; the binomial tolerance is
    ``4·sqrt(level(1 − level)/runs)``.
    """
    from bench.validate import design_theta, true_sensor_params, validate
    from calib.calibration.montecarlo import simulate_calibrations

    tp = true_sensor_params(truth)
    if tp is None:
        raise ValueError("truth has no sensor parameters")
    theta = design_theta(truth)
    g = float(truth.get("course", {}).get("g", truth.get("g", G)))
    scale = np.array([tp["scale_x"], tp["scale_y"]])
    bias = np.array([tp["bias_x"], tp["bias_y"]])
    nv = np.array([tp["noise_var_x"], tp["noise_var_y"]])
    # spawn_key (7,): a stream family of its own, independent of the course set's streams
    mc = simulate_calibrations(theta, bias, scale, nv, runs, seed, "given", g, spawn_key=(7,),
                               mapper=mapper, progress=progress)
    v0 = validate(truth, mc.estimates(0), level)
    each = np.abs(mc.errors() / v0.std) <= v0.quantile
    passed = (mc.nees() <= v0.chi2_limit) & (v0.std_passed is not False)
    tol = 4.0 * np.sqrt(level * (1 - level) / runs)
    rate = int(passed.sum()) / runs
    return {"runs": runs, "level": level, "pass_rate": rate, "tolerance": tol,
            "consistent": bool(abs(rate - level) <= tol),
            "pass_rate_each": dict(zip(("bias_x", "scale_x", "bias_y", "scale_y"),
                                       (each.sum(axis=0) / runs).tolist(), strict=True)),
            "n": int(theta.size), "seed": seed}


FUSION_UNITS = {"fusion.n_fixes": "count", "fusion.sigma_pos": "m", "fusion.rate_hz": "Hz",
                "fusion.final_position": "m", "fusion.final_std": "m",
                "fusion.dead_reckoning_std": "m", "fusion.std_ratio": "1"}
"""Units of the demo's ``fusion`` object (``demo --json``)."""


def fusion_step(ana: CourseAnalysis, fixes, data_dir: Path, seed: int | None) -> dict:
    """Fuse the vehicle run with position fixes; the fused final-position std against dead
    reckoning's (``ana.region``), per axis, m.

    ``fixes``: simulated :class:`bench.gnss.GnssFixes` (generated set), else ``gps.mat`` in
    ``data_dir`` is read; without either the step is skipped and ``skipped`` says why. P0 and
    V0 exact (course), Q from σ² of datos.txt and the calibration covariance, R = σ² I of the
    receiver (σ = 3 m for a gps.mat, the default receiver's).
    """
    from bench.gnss import Receiver
    from calib.fusion.linear import fuse

    if fixes is not None:
        t_gps, pos, sigma, rate = fixes.t_gps, fixes.pos, fixes.receiver.pos_sigma_m, \
            fixes.receiver.rate_hz
        source = (f"simulated on the generated run (default receiver, seed {seed}; "
                  f"`tiltbench generate course --seed {seed} --gps` writes the same fixes)")
    elif (data_dir / "gps.mat").exists():
        from calib.files.course import read_gps

        g = read_gps(data_dir / "gps.mat")
        t = ana.acel.t
        inside = (g.t_gps >= t[0]) & (g.t_gps <= t[-1])
        if not np.any(inside):
            return {"skipped": f"{data_dir / 'gps.mat'}: no fix within the vehicle run"}
        t_gps, pos, sigma = g.t_gps[inside], g.pos[inside], Receiver().pos_sigma_m
        rate = float(1.0 / np.median(np.diff(t_gps))) if t_gps.size > 1 else float("nan")
        source = f"{data_dir / 'gps.mat'} (σ = {sigma:g} m assumed, the default receiver's)"
    else:
        return {"skipped": f"no position fixes: {data_dir} has no gps.mat and the course "
                           "files are not generated here (nothing to fuse)"}
    nv = (ana.noise_var if ana.noise_var is not None
          else np.array([ana.cal.fits[a].sigma2.item() for a in AXES]))
    res = fuse(ana.acel.t, ana.acel.aerr, t_gps, pos, bias=ana.cal.bias, scale=ana.cal.scale,
               cal_cov=ana.cal.cov, noise_var=nv, sigma_pos=sigma, p0=ana.p0, v0=ana.v0,
               p0_cov=0.0, v0_cov=0.0, keep="fixes")
    std = np.sqrt(np.diag(res.final_position_cov))
    dr = ana.region.std
    return {"skipped": None, "source": source, "n_fixes": int(t_gps.size), "rate_hz": rate,
            "sigma_pos": float(sigma), "final_position": res.final_position.tolist(),
            "final_std": std.tolist(), "dead_reckoning_std": np.asarray(dr).tolist(),
            "std_ratio": float(np.sqrt(np.sum(np.square(dr)) / np.sum(np.square(std))))}


def _fusion_lines(f: dict | None) -> list[str]:
    """The fusion step in words (summary and report)."""
    if f is None:
        return []
    if f["skipped"]:
        return [f"Fusion with position fixes: skipped — {f['skipped']}."]
    s, d = f["final_std"], f["dead_reckoning_std"]
    return [f"Fusion with position fixes ({f['n_fixes']} fixes at {f['rate_hz']:g} Hz, "
            f"σ = {f['sigma_pos']:g} m; {f['source']}):",
            f"  final-position std ({s[0]:.2f}, {s[1]:.2f}) m fused against ({d[0]:.2f}, "
            f"{d[1]:.2f}) m by dead reckoning: {f['std_ratio']:.1f}× smaller"]


@dataclass
class DemoResult:
    """What :func:`run_demo` produced: paths written and the numbers of the summary."""

    out: Path
    files: dict[str, Path]
    analysis: CourseAnalysis
    truth: dict | None
    validation: Any
    coverage: dict | None
    nmin: dict
    recovered: bool | None
    times: dict[str, float]
    elapsed: float
    source: str
    fusion: dict | None = None
    """:func:`fusion_step`'s numbers (or why it was skipped)."""
    data_dir: Path | None = None
    """Where the course files are once the demo is done (``OUT/data`` when generated: the
    files are written in a staging directory first, whose name must not reach the user)."""
    recording_skipped: str | None = None
    """Why ``demo.rrd`` was not written (``record=False``, or the ``rrd`` extra is missing);
    None when it was."""

    def summary(self) -> str:
        return demo_summary(self)


RRD_EXTRA_MISSING = ('rerun-sdk is not installed (the "rrd" extra: '
                     'pip install "tiltbench[rrd]")')
"""Why the recording is skipped on a core install."""


def recording_available() -> bool:
    """True if rerun-sdk (the ``rrd`` extra) can be imported — checked before any work, so a
    core install runs the demo without the recording instead of failing at its last step."""
    try:
        import rerun  # noqa: F401  (the recording step imports it anyway)
    except ImportError:
        return False
    return True


def _prepare(out: Path, force: bool, generate: bool, formats: tuple[str, ...],
             record: bool = True) -> list[str]:
    """Refuse existing outputs without ``force``; return the outputs (relative paths)."""
    from bench.course import COURSE_FILES

    names = [n for n in OUTPUT_NAMES if record or n != "demo.rrd"]
    names += [f"figures/{n}.{f}" for n in FIGURE_NAMES for f in formats]
    if generate:
        names += [f"data/{n}" for n in COURSE_FILES]
    clash = [n for n in names if (out / n).exists()]
    if clash and not force:
        raise FileExistsError(f"{out}: {', '.join(clash[:4])}{' …' if len(clash) > 4 else ''} "
                              "already exist(s)")
    return names


FIGURE_FORMATS = ("png", "svg")
FIGURE_NAMES = ("calibration_x", "calibration_y", "parameters", "trajectory", "acceleration",
                "uncertainty_growth", "nmin")


def _step_labels(generate: bool, has_truth: bool, coverage: bool, seed: int,
                 coverage_runs: int, formats: tuple[str, ...],
                 record: bool = True) -> list[str]:
    """The steps the demo will run, in order (their count is the ``total`` of ``k/total``)."""
    labels = [f"generating a course set with the MuJoCo bench (seed {seed})"] if generate else []
    labels.append("calibrating, correcting, integrating and deciding")
    if has_truth:
        labels.append("validating the estimates against truth.json")
    if coverage:
        labels.append(f"coverage check: {coverage_runs} fresh calibrations, same design")
    labels.append("fusion with position fixes (Kalman filter)")
    labels.append(f"figures ({', '.join(formats)})")
    if record:
        labels.append("rerun recording (written, then read back)")
    labels.append("report")
    return labels


@dataclass
class _Truth:
    """What the demo knows of the truth: the manifest and the true path / accelerations."""

    manifest: dict | None = None
    path: np.ndarray | None = None
    acc: np.ndarray | None = None
    fixes: Any = None
    """:class:`bench.gnss.GnssFixes` simulated on the generated run (fusion step), or None."""

    @property
    def final(self) -> np.ndarray | None:
        if self.manifest is None or "true_final_position" not in self.manifest:
            return None
        return np.asarray(self.manifest["true_final_position"], dtype=float)


def _generate(out: Path, seed: int, files: dict[str, Path]) -> _Truth:
    """Generate and write the course set into ``out/data``; return its true path."""
    from bench.course import make_course_set, write_course_files
    from bench.gnss import Receiver, fixes_for_seed

    course = make_course_set(None, seed)
    (out / "data").mkdir()
    written = write_course_files(course, out / "data")
    files.update({f"data/{Path(p).name}": Path(p) for p in written.values()})
    return _Truth(path=course.vehicle.truth.pos, acc=course.vehicle.truth.acc,
                  fixes=fixes_for_seed(Receiver(), course.vehicle.truth, seed))


def _read_truth(data_dir: Path, truth: _Truth) -> _Truth:
    """Add ``truth.json`` of ``data_dir`` (if any) and, without a simulated path, its samples."""
    from bench.validate import load_json

    path = data_dir / "truth.json"
    if not path.exists():
        return truth
    manifest = load_json(path, "truth")
    true_path = truth.path
    if true_path is None:
        samples = manifest.get("vehicle", {}).get("trajectory", {}).get("samples", {})
        if "pos" in samples:
            true_path = np.asarray(samples["pos"], dtype=float)
    return _Truth(manifest, true_path, truth.acc, truth.fixes)


def _write_json(out: Path, name: str, obj: Any, files: dict[str, Path]) -> None:
    files[name] = write_text(out / name, dumps(obj), True)


def _figures(out: Path, ana: CourseAnalysis, truth: _Truth, formats: tuple[str, ...],
             files: dict[str, Path], nmin: dict) -> None:
    from bench import figures

    fdir = out / "figures"  # each figure built once, written in every format
    files.update({f"figures/{p.name}": p for p in figures.write_calibration_figures(
        fdir, ana.cal, ana.ensayo, truth.manifest, 0.95, formats, True).values()})
    files.update({f"figures/{p.name}": p for p in figures.write_vehicle_figures(
        fdir, ana.traj, ana.region, ana.cal, ana.ensayo.n, truth.final, truth.path,
        truth.acc, formats, True, nmin.get("fixed_run")).values()})


def _recording(out: Path, ana: CourseAnalysis, truth: _Truth, est: dict, tj: dict,
               files: dict[str, Path]) -> bool:
    """Write ``demo.rrd``, read it back; True if estimates, trajectory and truth come back."""
    from bench.record import read_recording, record_course

    rrd = record_course(out / "demo.rrd", cal=ana.cal, ensayo=ana.ensayo, traj=ana.traj,
                        region=ana.region, force=True, truth=truth.manifest,
                        true_path=truth.path, true_acc=truth.acc, tree=tj)
    files["demo.rrd"] = rrd
    back = read_recording(rrd)
    recovered = back["estimates"] == _jsonable(est) and back["trajectory"] == _jsonable(tj)
    if truth.manifest is not None:
        recovered = recovered and back["truth"] == truth.manifest
    return recovered


def run_demo(out: str | Path = "demo-out", seed: int = DEFAULT_SEED, force: bool = False,
             course_data: str | Path | None = None, level: float = DEFAULT_LEVEL,
             coverage_runs: int = COVERAGE_RUNS,
             progress: Callable[[str], None] | None = None,
             formats: tuple[str, ...] = FIGURE_FORMATS,
             mapper: Mapper = serial_map, record: bool = True) -> DemoResult:
    """Run the demo (module docstring); return what was written and computed.

    Parameters
    ----------
    out : output directory.  seed : seed of the generated course set.
    force : overwrite existing outputs (checked before anything is written; else
        :class:`FileExistsError`).
    course_data : directory with real course files (ensayo.mat, acel.mat, puntos.mat,
        datos.txt; truth.json used if present) instead of generating a set.
    level : level of the arrival region, in (0, 1).  coverage_runs : Monte Carlo runs
        (0: skip).
    progress : called with one line of text at the start and at the end of each step (None:
        silent); the command line passes :class:`bench.cli.progress.Progress`.
    formats : figure formats written side by side ("png", "svg").
    mapper : where the coverage check's runs execute (:mod:`calib.stats.runs`; same numbers).
    record : write and read back ``demo.rrd``. Without rerun-sdk (the ``rrd`` extra) the
        recording is skipped and everything else written; ``recording_skipped`` says why.
    """
    from bench.validate import validate

    out = Path(out)
    generate = course_data is None
    if not 0.0 < level < 1.0:  # arguments are checked before anything is written
        raise ValueError(f"level must be in (0, 1), got {level}")
    if coverage_runs < 0:
        raise ValueError(f"coverage_runs must be >= 0, got {coverage_runs}")
    if not formats or set(formats) - {"png", "svg"}:
        raise ValueError(f"figure formats must be png and/or svg, got {', '.join(formats)}")
    skipped = ("not asked for (--no-rrd)" if not record else
               None if recording_available() else RRD_EXTRA_MISSING)
    record = skipped is None
    owned = _prepare(out, force, generate, formats, record)
    # The output directory is one set (calib.files.atomic.atomic_dir): everything is written to a
    # temporary directory beside OUT (`work`) and replaces OUT's outputs as a whole at the
    # end; an interrupted demo leaves the old outputs or the new ones, never a mix.
    with atomic_dir(out, force, owned=owned) as work:
        data_dir = work / "data" if generate else Path(course_data)
        has_truth = generate or (data_dir / "truth.json").exists()
        steps = _Steps(_step_labels(generate, has_truth, generate and coverage_runs > 0, seed,
                                    coverage_runs, formats, record), progress)
        files: dict[str, Path] = {}
        truth = _Truth()
        if generate:
            with steps.step():
                truth = _generate(work, seed, files)
            source = f"generated course set, seed {seed}"
        else:
            source = f"course files in {data_dir}"
        truth = _read_truth(data_dir, truth)
        with steps.step():
            ana = analyze_course_dir(data_dir, level)
            est = ana.cal.to_dict()
            tj = ana.trajectory_json()
            _write_json(work, "estimates.json", est, files)
            _write_json(work, "trajectory.json", tj, files)
            nmin = _nmin(ana)
        val = cov = None
        if truth.manifest is not None:
            with steps.step():
                val = validate(truth.manifest, est, VALIDATE_LEVEL)
                _write_json(work, "validation.json", val.to_dict(), files)
            if generate and coverage_runs > 0:
                with steps.step():
                    cov = coverage_check(truth.manifest, coverage_runs, COVERAGE_LEVEL, seed,
                                         mapper, _count_progress(progress, "coverage chunks"))
        with steps.step():
            fusion = fusion_step(ana, truth.fixes, data_dir, seed if generate else None)
        with steps.step():
            _figures(work, ana, truth, formats, files, nmin)
        recovered = None
        if record:
            with steps.step():
                recovered = _recording(work, ana, truth, est, tj, files)
        result = DemoResult(out, files, ana, truth.manifest, val, cov, nmin, recovered,
                            steps.times, 0.0, source, fusion,
                            out / "data" if generate else Path(course_data), skipped)
        with steps.step():
            files["report.md"] = write_text(work / "report.md", report_markdown(result), True)
    result.files = {k: out / p.relative_to(work) for k, p in files.items()}
    result.elapsed = steps.elapsed
    return result


def _jsonable(obj: Any) -> Any:
    import json

    return json.loads(dumps(obj))


def _nmin(ana: CourseAnalysis) -> dict:
    """Design and a-posteriori N, and the course question's fixed-run N
    (:func:`calib.vehicle.nmin.fixed_run_nmin`, 10⁵ draws, seed 0; shared with the nmin figure)."""
    from calib.vehicle.nmin import PositionCovModel, design_nmin, fixed_run_nmin, posterior_nrange

    reg = ana.region
    truth = reg.decision or min(reg.mahalanobis, key=reg.mahalanobis.get)
    model = PositionCovModel.from_region(ana.region, ana.cal.g)
    cal_only = PositionCovModel.from_region(ana.region, ana.cal.g, include_noise=False)
    return {"design": design_nmin(ana.region.candidates, model, ana.region.level),
            "design_calibration_only": design_nmin(ana.region.candidates, cal_only,
                                                   ana.region.level),
            "posterior": posterior_nrange(ana.region.estimate, ana.region.candidates, model,
                                          ana.region.level),
            "fixed_run": fixed_run_nmin(reg, truth, 10**5, 0, ana.cal.g)}


def _param_rows(res: DemoResult) -> list[tuple[str, float | None, float, float, float | None]]:
    from bench.validate import true_sensor_params

    tp = true_sensor_params(res.truth) if res.truth else None
    rows = []
    for a in AXES:
        f = res.analysis.cal.fits[a]
        for j, p in enumerate(("bias", "scale")):
            name = f"{p}_{a}"
            est, std = float(f.params[j]), float(f.std[j])
            tv = tp[name] if tp else None
            rows.append((name, tv, est, std, None if tv is None else (est - tv) / std))
    return rows


def demo_summary(res: DemoResult) -> str:
    """The text printed at the end of the demo."""
    ana = res.analysis
    r = ana.region
    lines = [f"tiltbench demo — {res.source}", "",
             f"Calibration (per-axis OLS, σ² from datos.txt, N = {ana.ensayo.n}):",
             f"  {'parameter':<10}{'unit':<6}{'true':>14}{'estimate':>14}{'std':>12}{'z':>8}"]
    for name, tv, est, std, z in _param_rows(res):
        unit = "m/s²" if name.startswith("bias") else "1"
        lines.append(f"  {name:<10}{unit:<6}{'—' if tv is None else format(tv, '.6g'):>14}"
                     f"{est:>14.6g}{std:>12.3g}{'' if z is None else format(z, '+.2f'):>8}")
    answer = res.truth.get("answer") if res.truth else None
    lines += ["", f"Arrival ({100 * r.level:g}% region): estimate ({r.estimate[0]:.2f}, "
              f"{r.estimate[1]:.2f}) m, std ({r.std[0]:.2f}, {r.std[1]:.2f}) m",
              f"  decision: {r.decision or 'undecided'}"
              + (f"   true arrival point: {answer}" if answer else "")
              + f"   (uncorrected path ends at ({ana.traj.final_raw[0]:.1f}, "
              f"{ana.traj.final_raw[1]:.1f}) m)"]
    d = res.nmin["design"]
    dn = (str(d["n"]) if d["n"] is not None else
          "none suffices (the vehicle-noise part does not shrink with N)")
    fr = res.nmin["fixed_run"]
    frn = (f"N ≥ {fr['n']}" if fr["n"] is not None else "no N up to "
           f"{fr['grid_n'][-1]:.0f} reaches it")
    lines.append(f"  N analysis: this vehicle run given, a new calibration needs {frn} for "
                 f"P(decision made and right) ≥ {100 * r.level:g}% ({fr['draws']} draws); "
                 f"design N (regions disjoint) = {dn}; calibration part only: "
                 f"{res.nmin['design_calibration_only']['n']}")
    if res.validation is not None:
        v = res.validation
        lines += ["", f"Validation against truth.json (joint test of the 4 estimates against "
                  f"the true parameters) at {100 * v.level:g}%: "
                  f"{'PASS' if v.passed else 'FAIL'} (d² = {v.chi2:.2f}, "
                  f"{'≤' if v.passed else '>'} {v.chi2_limit:.2f})"]
    elif res.truth is None:
        lines += ["", "Validation: not done (no truth.json next to the data: the estimates "
                  "are not checked against any truth)"]
    if res.coverage is not None:
        c = res.coverage
        L = f"{100 * c['level']:g}%"
        lines.append(f"Coverage at {L}: {c['runs']} fresh calibrations (same θ design and true "
                     f"parameters), each tested against the truth at {L}; "
                     f"{c['pass_rate']:.3f} pass (expected {c['level']:g} ± "
                     f"{c['tolerance']:.3f}, 4 binomial σ) → "
                     f"{'consistent' if c['consistent'] else 'NOT consistent'}")
    if res.recovered is not None:
        what = ("truth, estimates and trajectory" if res.truth is not None
                else "estimates and trajectory (no truth to record)")
        lines.append(f"Recording read back: {what} "
                     f"{'come back exactly' if res.recovered else 'DIFFER from what was written'}")
    if res.recording_skipped:
        lines.append(f"Recording (demo.rrd): skipped, {res.recording_skipped}")
    fl = _fusion_lines(res.fusion)
    if fl:
        lines += ["", *fl]
    data = res.data_dir or Path(res.analysis.ensayo.source).parent
    lines += ["", "Reproduce the estimates:",
              f"  tiltbench calibrate {data / 'ensayo.mat'} --datos {data / 'datos.txt'} --json",
              "",
              "Files written:"]
    for k in sorted(res.files):
        p = res.files[k]
        lines.append(f"  {p}  ({_size(p)})")
    lines.append(f"\nDone in {res.elapsed:.1f} s." + (
        f" Open the recording with: rerun {res.files['demo.rrd']}" if "demo.rrd" in res.files
        else ""))
    return "\n".join(lines)


def _size(path: Path) -> str:
    n = path.stat().st_size
    return f"{n} B" if n < 1024 else f"{n / 1024:.0f} KiB"


def report_markdown(res: DemoResult) -> str:
    """The Markdown report (``report.md``) of a demo run."""
    ana = res.analysis
    r = ana.region
    L = f"{100 * r.level:g}%"
    nv_text = ana.noise_var.tolist() if ana.noise_var is not None else "estimated"
    md = ["# tiltbench demo report", "", f"Source: {res.source}.", ""]
    md += ["## Calibration", "",
           f"Per-axis least squares of `A_m = (1 + scale)·A_r + bias + v` with "
           f"`A_rx = -g sin θ`, `A_ry = -g cos θ`, g = {ana.cal.g} m/s², N = {ana.ensayo.n}, "
           f"noise variances from datos.txt ({nv_text} (m/s²)²).",
           "", "| parameter | true | estimate | std | z |", "|---|---|---|---|---|"]
    for name, tv, est, std, z in _param_rows(res):
        md.append(f"| {name} | {'—' if tv is None else f'{tv:.6g}'} | {est:.6g} | {std:.3g} | "
                  f"{'—' if z is None else f'{z:+.2f}'} |")
    md += ["", "χ²/dof: " + ", ".join(f"{a} {ana.cal.fits[a].chi2_dof:.3f}" for a in AXES), ""]
    md += ["![x axis](figures/calibration_x.png)", "", "![y axis](figures/calibration_y.png)",
           "", "![parameters](figures/parameters.png)", ""]
    if res.validation is not None:
        md += ["## Validation against the truth", "", "```", res.validation.summary(), "```",
               ""]
    if res.coverage is not None:
        c = res.coverage
        md += [f"Coverage check: {c['runs']} fresh calibrations with the same θ design and "
               f"true parameters; the joint test passes at rate {c['pass_rate']:.3f} "
               f"(expected {c['level']:g}, binomial tolerance ±{c['tolerance']:.3f}): "
               f"{'consistent' if c['consistent'] else 'not consistent'}. Per parameter: "
               + ", ".join(f"{k} {v:.3f}" for k, v in c["pass_rate_each"].items()) + ".", ""]
    if res.recording_skipped:
        md += [f"Recording (`demo.rrd`): skipped, {res.recording_skipped}.", ""]
    md += ["## Trajectory and arrival decision", "", "```", ana.traj.summary(), r.summary(),
           "```", ""]
    if res.truth and "answer" in res.truth:
        ok = r.decision == res.truth["answer"]
        md += [f"True arrival point: **{res.truth['answer']}** — the decision is "
               f"{'right' if ok else ('undecided' if r.decision is None else 'WRONG')}.", ""]
    md += ["![trajectory](figures/trajectory.png)", "",
           "![acceleration](figures/acceleration.png)", "",
           "![uncertainty growth](figures/uncertainty_growth.png)", "",
           *(["## Fusion with position fixes", "", *_fusion_lines(res.fusion), ""]
             if res.fusion is not None else []),
           "## How many calibration samples?", ""]
    d, dc, p = res.nmin["design"], res.nmin["design_calibration_only"], res.nmin["posterior"]
    fr = res.nmin["fixed_run"]
    md += ["* this vehicle run given (the course question), a new calibration needs "
           + (f"N ≥ {fr['n']}" if fr["n"] is not None else "more samples than searched")
           + f" for P(decision made and right) ≥ {L} ({fr['draws']} draws from the "
           f"estimator's sampling law; `tiltbench nmin` confirms it by regenerating "
           f"calibrations);",
           f"* design N making the {L} regions of the candidates disjoint: "
           f"{d['n'] if d['n'] is not None else 'none suffices'} "
           f"(calibration part only: {dc['n'] if dc['n'] is not None else 'none'});",
           f"* with this estimate fixed, exactly one candidate ({p['letter']}) is inside for "
           f"N ≥ {p['n_min']}" + ("" if p["n_max"] is None else f" up to {p['n_max']}")
           + "." if p["n_min"] is not None else "* with this estimate fixed: never decided.",
           "", "![N analysis](figures/nmin.png)", "",
           "## Files", "", "| file | size |", "|---|---|"]
    for k in sorted(res.files):
        md.append(f"| `{k}` | {_size(res.files[k])} |")
    md += ["", "Step times: " + "; ".join(f"{k}: {v:.2f} s" for k, v in res.times.items()), ""]
    return "\n".join(md)
