"""The discrepancy workflow's run: :func:`run_gap`, in the steps of ``docs/gap.md``.

1. the estimation side's analysis (:func:`calib.gap.analyze_gap`);
2. the nominal re-simulation and its gap (:func:`_nominal_gap`), alongside step 1;
3. the extension: the named effects in the bench model, physical ones refined by
   ``mujoco.sysid`` (:func:`_extension`);
4. the extended re-simulation and its gap (:func:`_extended_gap`); steps 3 and 4 start
   beside step 1's adequacy checks once it has named its effects (:class:`_Ahead`);
5. the outputs (:func:`_write_outputs`).

The library never prints: progress messages go to the ``progress`` callable when one is given.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

# The replay's modules only (MuJoCo, numpy, scipy.interpolate): the nominal re-simulation
# starts on its thread before the analysis side is imported (the catalog and the checks take
# ≈ 0.3 s to import, GIL-bound; MuJoCo's rollout runs without the GIL meanwhile). The other
# modules are imported where they are used.
from bench.gap.readout import record_field
from bench.gap.replay import (
    MOTION_TOL,
    Replay,
    make_replay,
    sample_torque,
    simulate,
    timing,
)
from bench.model import ACC_SENSORS, ENCODER, TableEdits
from calib.conventions import AXES, G
from calib.input_rules import stated_variances

if TYPE_CHECKING:
    from bench.effects import EffectSpec
    from bench.gap.prediction import AxisPrediction
    from bench.gap.readout import AccelField
    from bench.gap.report import GapReport
    from bench.sensors import SensorErrorModel
    from calib.files.course import Ensayo
    from calib.noise.sensor_profile import SensorProfile

PathLike = str | os.PathLike
Progress = Callable[[str], None] | None


def run_gap(ensayo: Ensayo, noise_var: Sequence[float] | np.ndarray, g: float = G,
            rate: float | None = None, report_dir: PathLike | None = None,
            rrd: PathLike | None = None, force: bool = False, *,
            family_alpha: float | None = None, progress: Progress = None,
            sensor: SensorProfile | None = None) -> GapReport:
    """Run the discrepancy workflow on a measured calibration run.

    Parameters
    ----------
    ensayo : :class:`calib.files.course.Ensayo` (θ rad, readings m/s², optional t s; time order).
    noise_var : (2,) stated noise variances [σx², σy²], (m/s²)².
    g : gravity, m/s² (default :data:`calib.conventions.G`).
    rate : sample rate, Hz, of a run without ``t`` (samples in time order).
    report_dir : write ``gap.json``, ``gap.md``, ``gap.png``, ``gap.svg`` and
        ``model_after.xml`` there (refuses to overwrite unless ``force``).
    rrd : write a rerun recording there.
    family_alpha : family-wise level of the detection and of "consistent with noise" (None:
        the analysis' default, :data:`calib.gap.selection.FAMILY_ALPHA`).
    progress : called with one line per step and its duration (e.g. a function printing to
        stderr); None: silent.
    sensor : a sensor profile: the bias random walk's q comes from it
        (:func:`calib.gap.analyze_gap`).

    Returns
    -------
    GapReport
    """
    noise_var = _check_inputs(noise_var, report_dir, rrd, force)
    t = timing(ensayo.t, ensayo.n, rate)
    timing_src = "t" if ensayo.t is not None else ("rate" if rate is not None else "none")
    datos = np.asarray(ensayo.datos, dtype=float)
    tita = np.asarray(ensayo.tita, dtype=float)

    base = TableEdits(g=g)
    # The nominal re-simulation does not depend on the analysis: it runs alongside it on a
    # second thread (mujoco.rollout and numpy's large operations release the GIL). The
    # replay and its drive torque come first; the analysis asks for the torque when its
    # drive-state checks need it.
    #
    # The worker thread never imports a module: two threads importing into one package's
    # import cycle at once can deadlock (Python then raises _DeadlockError in one of them:
    # 2 of 822 drive-validation runs, seeds 7 and 8, before this rule). Its first jobs (replay,
    # torque, motion) use only the modules this module imports at its top; the nominal gap,
    # which uses the analysis side's modules, is queued only once this thread has imported
    # them (tests/test_gap_threads.py checks that no import happens off the main thread).
    with ThreadPoolExecutor(max_workers=1) as pool:
        if progress is not None:
            progress("simulating the nominal bench alongside the analysis…")
        first = pool.submit(_replay_and_torque, tita, t)
        motion = pool.submit(_motion_run, first, base)
        from bench.gap.report import GapReport
        from calib.gap import analyze_gap
        from calib.gap.selection import FAMILY_ALPHA

        _import_nominal_gap_modules()
        job = pool.submit(_nominal_run, motion, datos, noise_var)
        alpha = FAMILY_ALPHA if family_alpha is None else float(family_alpha)
        ahead = _Ahead(pool, job, datos, noise_var, base)

        with _step(progress, f"analysing {ensayo.n} samples (calib.gap)…", "analysis done"):
            analysis = analyze_gap(ensayo, noise_var, g=g, rate=rate, family_alpha=alpha,
                                   sensor=sensor, drive_torque=lambda: first.result()[1],
                                   on_named=ahead.start)
        named = _named(analysis.effects, analysis.reported)
        extension = ahead.result(named)
        replay, nominal, seconds = job.result()
    if progress is not None:
        progress(f"nominal re-simulation ({replay.mode}) done in {seconds:.1f} s")
    where = "the extension ran beside the analysis' checks:"
    if extension is None:  # the checks withdrew a named effect: extend the final model now
        if progress is not None:
            progress("extending the final model (mujoco.sysid, MuJoCo)…")
        extension = _extend(named, replay, datos, noise_var, base, nominal)
        where = "the final model extended:"
    if progress is not None:
        extension.tell(progress, where)
    effects, table_after, sysid_out, after = (extension.effects, extension.table_after,
                                              extension.sysid, extension.after)

    report = GapReport(analysis=analysis, effects=tuple(effects), sysid=sysid_out,
                       replay=replay, tracking_error=nominal.tracking, noise_var=noise_var,
                       g=float(g), timing=timing_src, nominal=nominal.params,
                       after=after.predictions, table_after=table_after,
                       sensor_after=after.sensor, gap_before=nominal.gap,
                       gap_after=after.gap, residual_before=nominal.residual,
                       residual_after=after.residual, family_alpha=alpha,
                       chi2_after_stated=after.chi2_stated, readings_change=after.change)
    files = _write_outputs(report, report_dir, rrd, force, progress)
    return replace(report, files=files)


# ----------------------------------------------------------------------------- steps

@contextmanager
def _step(progress: Progress, start: str | None, done: str
          ) -> Iterator[Callable[[str], None]]:
    """Report ``start``, then ``done`` with the step's duration (and any noted detail)."""
    detail: list[str] = []
    if progress is not None and start is not None:
        progress(start)
    clock = time.perf_counter()
    yield detail.append
    if progress is not None:
        progress(f"{done}{''.join(detail)} in {time.perf_counter() - clock:.1f} s")


def _replay_and_torque(tita: np.ndarray, t: np.ndarray | None
                       ) -> tuple[Replay, np.ndarray | None, float]:
    """The replay of the measured run (:func:`bench.gap.replay.make_replay`), the drive
    torque at its samples (:func:`bench.gap.replay.sample_torque`, N·m; None for a static
    replay) and the seconds they took."""
    clock = time.perf_counter()
    replay = make_replay(tita, t)
    return replay, sample_torque(replay), time.perf_counter() - clock


def _motion_run(first, base: TableEdits) -> tuple[Replay, AccelField, float]:
    """The replay (``first``: the future of :func:`_replay_and_torque`), its motion simulated
    once on ``base``'s table and read as an acceleration field
    (:func:`bench.gap.readout.record_field`: MuJoCo's steps and the probes in one pass), and the
    seconds replay and motion took. On one rollout thread: the analysis runs meanwhile on the
    other core (old and new alternating, 2 × 10 pairs at N = 60001: median 1.93 → 1.81 s and
    1.77 → 1.69 s; this thread's path still ends long before the analysis names its effects)."""
    replay, _, seconds = first.result()
    clock = time.perf_counter()
    accel = record_field(replay, base, threads=1)
    return replay, accel, seconds + time.perf_counter() - clock


def _nominal_run(motion, datos: np.ndarray, noise_var: np.ndarray
                 ) -> tuple[Replay, _Nominal, float]:
    """The nominal gap (:func:`_nominal_gap`) of the motion (``motion``: the future of
    :func:`_motion_run`) and the seconds replay, motion and gap took."""
    replay, accel, seconds = motion.result()
    clock = time.perf_counter()
    nominal = _nominal_gap(replay, accel, datos, noise_var)
    return replay, nominal, seconds + time.perf_counter() - clock


def _needs_sysid(effects: Sequence[EffectSpec]) -> bool:
    """True when ``effects`` hold a physical effect that ``mujoco.sysid`` refines."""
    from bench.gap.sysid import SYSID_EFFECTS

    return any(e.name in SYSID_EFFECTS for e in effects)


def _check_inputs(noise_var: Sequence[float] | np.ndarray, report_dir: PathLike | None,
                  rrd: PathLike | None, force: bool) -> np.ndarray:
    """The stated noise as a (2,) array; refuses existing outputs unless ``force``."""
    noise_var = stated_variances(noise_var)  # the one check of the statement
    if report_dir is not None and not force:
        from bench.gap.writers import check_outputs

        check_outputs(report_dir, rrd)
    elif rrd is not None and not force and Path(rrd).exists():
        raise FileExistsError(f"{rrd}: exists; pass --force to overwrite")
    return noise_var


@dataclass(frozen=True)
class _Nominal:
    """The nominal re-simulation: true specific force (N, 2) and encoder (N,), the encoder
    tracking error (rad), per axis (bias, scale), residual (N, 2) and gap measure, and the
    recorded motion's acceleration field (:class:`bench.gap.readout.AccelField`)."""

    a: np.ndarray
    enc: np.ndarray
    tracking: float
    params: dict[str, tuple[float, float]]
    residual: np.ndarray
    gap: dict
    accel: AccelField


def _import_nominal_gap_modules() -> None:
    """Import, on the calling (main) thread, the modules :func:`_nominal_gap` uses on the
    worker thread, which never imports (:func:`run_gap`)."""
    import bench.gap.prediction  # noqa: F401
    import calib.gap.practical  # noqa: F401
    import calib.stats.diagnostics  # noqa: F401


def _nominal_gap(replay: Replay, accel: AccelField, datos: np.ndarray, noise_var: np.ndarray
                 ) -> _Nominal:
    """The nominal bench's readings, bias and scale fitted per axis, and the gap.

    The replay was simulated once (:func:`_motion_run`); the nominal readings are MuJoCo's
    sensors along it, read together with the probe accelerometers that later give any edited
    table's readout (``accel``, :func:`bench.gap.readout.record_field`). Runs on the worker
    thread: what it imports here and in :func:`_known_lattice` is imported beforehand
    (:func:`_import_nominal_gap_modules`).
    """
    from bench.gap.prediction import fit_bias_scale
    from calib.stats.diagnostics import gap_measure

    tita, t = replay.tita, replay.t
    a_nom = np.column_stack([accel.column(ACC_SENSORS[a])[:, 0] for a in AXES])
    enc = accel.column(ENCODER)[:, 0]
    tracking = (max(float(np.max(np.abs(enc - tita))), accel.motion.miss)
                if replay.mode == "sweep" else 0.0)
    params, residual, gap = {}, np.empty_like(datos), {}
    for k, ax in enumerate(AXES):
        bias, scale, r = fit_bias_scale(datos[:, k], a_nom[:, k])
        params[ax] = (bias, scale)
        residual[:, k] = r
        gap[ax] = gap_measure(r, tita, float(noise_var[k]), t,
                              other_ref=a_nom[:, 1 - k], own_ref=a_nom[:, k],
                              readings=datos[:, k], n_params=2,
                              model_lsb=_known_lattice(datos[:, k], float(noise_var[k])))
    return _Nominal(a_nom, enc, tracking, params, residual, gap, accel)


def _known_lattice(y: np.ndarray, sigma2: float) -> float | None:
    """The step of a lattice of the readings too fine to matter (reported, not named:
    :func:`calib.gap.practical.lattice_matters`), m/s², which the nominal gap is told about;
    None when there is none or when it matters (then it is a gap the model must close)."""
    from calib.gap.practical import lattice_matters
    from calib.stats.diagnostics import detect_lattice

    lat = detect_lattice(y)
    if lat.found and not lattice_matters(lat.lsb, sigma2):
        return float(lat.lsb)
    return None


def _effect_spec(est: Any) -> EffectSpec:
    """Catalog :class:`EffectSpec` of a ``calib.gap`` effect estimate (name, axis, params),
    or of a reported effect's dict (``GapAnalysis.reported``)."""
    from bench.effects import EffectSpec

    if isinstance(est, dict):
        return EffectSpec(str(est["name"]), str(est["axis"]),
                          {k: float(v) for k, v in est["params"].items()})
    return EffectSpec(str(est.name), str(est.axis), {k: float(v) for k, v in
                                                     dict(est.params).items()})


def _axis_count(effects: Sequence[EffectSpec], k: int) -> int:
    """Number of effect parameters fitted on axis ``k`` (for the χ² degrees of freedom)."""
    return sum(len(e.params) for e in effects if AXES[k] in e.axes
               and e.name != "gravity_mismatch")


def _bench_model(effects: Sequence[EffectSpec], base: TableEdits
                 ) -> tuple[TableEdits, SensorErrorModel]:
    """The nominal table and a noiseless sensor with ``effects`` added (``gravity_mismatch``
    is not identifiable on one table and is left out)."""
    from bench.effects import apply_to_model
    from bench.sensors import SensorErrorModel

    sensor0 = SensorErrorModel.from_pairs((0.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    return apply_to_model([e for e in effects if e.name != "gravity_mismatch"], base, sensor0)


def _extension(effects: Sequence[EffectSpec], reported: Sequence[EffectSpec], replay: Replay,
               datos: np.ndarray, noise_var: np.ndarray, base: TableEdits, accel: AccelField
               ) -> tuple[list[EffectSpec], TableEdits, SensorErrorModel, dict[int, dict]]:
    """The named effects in the bench model; physical ones refined by ``mujoco.sysid``
    (each candidate read along the recorded motion ``accel``, :mod:`bench.gap.sysid`).

    A refinement replaces the ``calib`` estimate when it lowered the cost and has finite
    intervals (:func:`bench.gap.sysid.sysid_usable`); when sysid fails, the reason is kept in
    its entry and the estimate stays. Effects the analysis reported but did not name
    (``reported``: below the practical threshold, :mod:`calib.gap.practical`) are in the
    model too, as estimated (not refined, not listed among the named ones).
    """
    from bench.effects import EffectSpec
    from bench.gap.sysid import SYSID_EFFECTS, sysid_refine, sysid_usable

    table_after, sensor_after = _bench_model([*effects, *reported], base)
    if not _needs_sysid(effects):
        return list(effects), table_after, sensor_after, {}
    sigma2 = np.array([sensor_after.axis(a).noise_var or noise_var[k]
                       for k, a in enumerate(AXES)])
    try:
        sysid_out = sysid_refine(effects, replay, datos, sigma2, table_after, sensor_after,
                                 accel=accel)
    except Exception as exc:  # the LS estimate stays usable; say why sysid did not run
        sysid_out = {i: {"error": f"{type(exc).__name__}: {exc}"}
                     for i, e in enumerate(effects) if e.name in SYSID_EFFECTS}
    used = list(effects)
    for i, s in sysid_out.items():
        if "params" in s and sysid_usable(s):
            used[i] = EffectSpec(effects[i].name, effects[i].axis, s["params"])
    table_after, sensor_after = _bench_model([*used, *reported], base)
    return used, table_after, sensor_after, sysid_out


@dataclass(frozen=True)
class _Named:
    """The effects an analysis named and those it reported without naming them, as catalog
    specs (:func:`_effect_spec`): what the extension of the bench model depends on."""

    effects: tuple[EffectSpec, ...]
    reported: tuple[EffectSpec, ...]


def _named(effects: Sequence[Any], reported: Sequence[Any]) -> _Named:
    return _Named(tuple(_effect_spec(e) for e in effects),
                  tuple(_effect_spec(r) for r in reported))


def _import_extension_modules(named: _Named) -> None:
    """Import, on the calling (main) thread, what :func:`_extend` uses (the worker thread
    never imports: :func:`run_gap`); ``mujoco.sysid`` (0.1–0.2 s, GIL-bound) only when a
    physical effect is named."""
    import bench.effects  # noqa: F401
    import bench.gap.prediction  # noqa: F401
    import bench.gap.sysid  # noqa: F401
    import bench.sensors  # noqa: F401

    if _needs_sysid(named.effects):
        from bench.gap.sysid import preload_sysid

        preload_sysid()


@dataclass(frozen=True)
class _Extension:
    """The bench model extended by the named effects (:func:`_extension`) and its gap
    (:func:`_extended_gap`), with the seconds each took (sysid's None when it did not run)."""

    effects: list[EffectSpec]
    table_after: TableEdits
    sysid: dict[int, dict]
    after: _Extended
    sysid_seconds: float | None
    extended_seconds: float

    def tell(self, progress: Callable[[str], None], where: str) -> None:
        """The progress lines of the two steps, after a line saying ``where`` they ran."""
        progress(where)
        if self.sysid_seconds is not None:
            progress(f"sysid done in {self.sysid_seconds:.1f} s")
        progress(f"extended re-simulation ({self.after.how}) in {self.extended_seconds:.1f} s")


def _extend(named: _Named, replay: Replay, datos: np.ndarray, noise_var: np.ndarray,
            base: TableEdits, nominal: _Nominal) -> _Extension:
    """Steps 3 and 4 of the run (module docstring): the extension, physical effects refined
    by ``mujoco.sysid``, and the extended re-simulation's gap, timed (progress lines:
    :meth:`_Extension.tell`; this runs on the worker thread, which never prints)."""
    clock = time.perf_counter()
    used, table_after, sensor_after, sysid_out = _extension(
        named.effects, named.reported, replay, datos, noise_var, base, nominal.accel)
    sysid_seconds = time.perf_counter() - clock if _needs_sysid(named.effects) else None
    clock = time.perf_counter()
    after = _extended_gap(replay, [*used, *named.reported], table_after, sensor_after,
                          nominal, datos, noise_var, base)
    return _Extension(used, table_after, sysid_out, after, sysid_seconds,
                      time.perf_counter() - clock)


class _Ahead:
    """The extension started on the worker thread as soon as the analysis has named its
    effects (``analyze_gap(on_named=…)``), alongside the analysis' adequacy checks (at
    N = 60 000 the checks take ≈ 0.5 s, the refinement and the extended re-simulation ≈ 0.3 s;
    the extension's MuJoCo reading runs on one thread, :meth:`AccelField.mujoco_read`).

    Its result is used only when the analysis ends with the same named and reported effects
    (the checks may withdraw one: a walk that did not earn its place, a swap for a term
    outside the catalog); otherwise the final model is extended afterwards, as it always
    was. Either way the numbers are those of :func:`_extend` on the final effects."""

    def __init__(self, pool: ThreadPoolExecutor, nominal_job: Future, datos: np.ndarray,
                 noise_var: np.ndarray, base: TableEdits) -> None:
        self._pool, self._nominal_job = pool, nominal_job
        self._args = (datos, noise_var, base)
        self._named: _Named | None = None
        self._job: Future | None = None

    def start(self, effects: Sequence[Any], reported: Sequence[Any]) -> None:
        """``on_named`` of :func:`calib.gap.analyze_gap` (main thread): import what the
        extension uses, then queue it behind the nominal re-simulation."""
        self._named = _named(effects, reported)
        _import_extension_modules(self._named)
        self._job = self._pool.submit(self._run, self._named)

    def _run(self, named: _Named) -> _Extension:
        replay, nominal, _ = self._nominal_job.result()
        return _extend(named, replay, *self._args, nominal)

    def result(self, named: _Named) -> _Extension | None:
        """The extension started ahead when it is that of ``named``, else None (and the
        job is cancelled if it has not started yet)."""
        if self._job is None:
            return None
        if named != self._named:
            self._job.cancel()
            return None
        return self._job.result()


@dataclass(frozen=True)
class _Extended:
    """The extended re-simulation: per axis prediction and gap, residual (N, 2), the
    extended sensor model with its fitted bias and scale, χ²/dof against the stated noise,
    how much the named effects change the simulated readings and how MuJoCo was run."""

    predictions: dict[str, AxisPrediction]
    residual: np.ndarray
    gap: dict
    sensor: SensorErrorModel
    chi2_stated: dict[str, float]
    change: dict[str, dict[str, float]]
    how: str


def _extended_readings(replay: Replay, table_after: TableEdits, nominal: _Nominal
                       ) -> tuple[np.ndarray, str]:
    """MuJoCo's true specific force (N, 2) of the extended table, and how it was obtained.

    The edited model is read by MuJoCo along the recorded motion (one batched rollout,
    :func:`bench.gap.replay.motion_sensordata`: the same sensordata as re-simulating the run,
    since site edits leave the motion unchanged); if it does not move as recorded (an edit
    that changed the physics), the replay is re-simulated in full.
    """
    model, sd, step_error = nominal.accel.mujoco_read(table_after)
    if step_error <= MOTION_TOL:
        cols = [int(model.sensor(ACC_SENSORS[a]).adr[0]) for a in AXES]
        return sd[:, cols], "MuJoCo along the recorded motion"
    a_ext, _ = simulate(replay, table_after)
    return a_ext, (f"full re-simulation: the extended model leaves the recorded motion by "
                   f"{step_error:.1e}")


def _extended_gap(replay: Replay, effects: Sequence[EffectSpec], table_after: TableEdits,
                  sensor_after: SensorErrorModel, nominal: _Nominal, datos: np.ndarray,
                  noise_var: np.ndarray, base: TableEdits | None = None) -> _Extended:
    """Simulate the extended bench, predict each axis and measure the gap after.

    The structure (signatures, and ``gap`` itself) is measured with the extended model's
    noise (a named ``noise_level`` replaces the stated σ²); χ²/dof is also measured against
    the **stated** σ² (``chi2_stated``: the same prediction built on the stated noise), which
    is the gap that remains — a named ``noise_level`` does not close it, it explains it.
    ``change``: ``max_abs`` (m/s²) and ``norm_over_sigma`` = ‖Δ‖/σ_stated of the change
    Δ = extended − nominal simulated mean reading.
    """
    from bench.gap.prediction import axis_term, predict_axis
    from bench.sensors import AxisErrors, SensorErrorModel
    from calib.stats.diagnostics import gap_measure

    tita, t, a_nom = replay.tita, replay.t, nominal.a
    if not effects:
        a_ext, how = a_nom, "nominal: nothing added"
    elif base is not None and table_after == base:  # sensor terms only: the table's readings
        a_ext, how = a_nom, "nominal table, sensor terms added"
    else:
        a_ext, how = _extended_readings(replay, table_after, nominal)
    preds, residual, gap, axes, chi2_stated, change = {}, np.empty_like(datos), {}, {}, {}, {}
    for k, ax in enumerate(AXES):
        stated = float(noise_var[k])
        sigma2_k = sensor_after.axis(ax).noise_var or stated
        pred = predict_axis(datos[:, k], a_ext, t, sensor_after, k, sigma2_k)
        preds[ax] = pred
        residual[:, k] = pred.residual
        quant = axis_term(sensor_after, k, "quantization")
        gap[ax] = gap_measure(pred.residual, tita, pred.sigma2, t,
                              other_ref=a_nom[:, 1 - k], own_ref=a_nom[:, k],
                              readings=datos[:, k],
                              model_lsb=None if quant is None else quant.lsb,
                              n_params=2 + _axis_count(effects, k))
        on_stated = (pred if sigma2_k == stated else
                     predict_axis(datos[:, k], a_ext, t, sensor_after, k, stated))
        chi2_stated[ax] = float(on_stated.residual @ on_stated.residual / on_stated.sigma2
                                / gap[ax].dof)
        delta = pred.mean - (datos[:, k] - nominal.residual[:, k])
        change[ax] = {"max_abs": float(np.max(np.abs(delta))),
                      "norm_over_sigma": float(np.linalg.norm(delta) / np.sqrt(stated))}
        axes[ax] = AxisErrors(pred.bias, pred.scale, sigma2_k, sensor_after.axis(ax).terms)
    return _Extended(preds, residual, gap, SensorErrorModel(axes["x"], axes["y"]),
                     chi2_stated, change, how)


def _write_outputs(report: GapReport, report_dir: PathLike | None, rrd: PathLike | None,
                   force: bool, progress: Progress) -> dict[str, str]:
    """Write the report directory and the recording asked for; name → path."""
    files: dict[str, str] = {}
    if report_dir is None and rrd is None:
        return files
    from bench.gap.recording import write_recording
    from bench.gap.writers import write_report

    with _step(progress, "writing the report…", "report written"):
        if report_dir is not None:
            files.update(write_report(report, report_dir, force=force))
        if rrd is not None:
            files["rrd"] = str(write_recording(report, rrd, force=force))
    return files
