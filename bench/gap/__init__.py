"""The discrepancy workflow on the bench: re-simulate a measured run, add the missing effects.

``run_gap`` takes a measured calibration run (course format, optional ``t``) and

1. asks the estimation side (:func:`calib.gap.analyze_gap`) which catalog effects the data
   show — detection, selection and estimates live there, never here;
2. re-runs **the same experiment on the bench** (:class:`Replay`) with the fitted nominal
   parameters (bias, scale) and measures the gap: per axis χ²/dof of data − simulation with
   the stated noise, and the largest structured-signature z (:func:`calib.gap.gap_measure`);
3. adds the named effects to the bench — physical ones as ``MjSpec`` edits of a copy of the
   model (written to ``model_after.xml``), the others as sensor terms without noise —,
   refines the physical parameters with ``mujoco.sysid`` (each candidate read along the
   motion simulated once, confirmed by MuJoCo; cross-checked against the linear
   least-squares estimate of ``calib``), reads the extended table with MuJoCo and measures
   the gap again; after a correct extension it is consistent with noise alone;
4. writes a figure (PNG + SVG), a rerun recording and a Markdown report.

The package holds one job per module (none imports from this ``__init__``):

=============================== ===============================================================
:mod:`bench.gap.replay`         the experiment re-run: :class:`Replay`, :func:`make_replay`,
                                :func:`timing`, :func:`simulate` (static poses / servo replay);
                                the motion simulated once: :func:`record_motion`,
                                :func:`motion_sensordata` (any edited table read along it)
:mod:`bench.gap.readout`        the accelerometers of any site edit read along the recorded
                                motion without MuJoCo: :func:`accel_field`, :func:`readout`
:mod:`bench.gap.prediction`     the extended sensor model's prediction and residual:
                                :func:`response`, :func:`additive_output`, :func:`predict_axis`
:mod:`bench.gap.sysid`          :func:`sysid_refine` (``mujoco.sysid`` fit, candidates read by
                                the readout, confirmed by MuJoCo)
:mod:`bench.gap.report`         :class:`GapReport` (``to_dict`` = ``gap --json``, ``summary``)
:mod:`bench.gap.run`            :func:`run_gap`, the workflow in steps
:mod:`bench.gap.writers`        :func:`gap_markdown`, :func:`write_report`,
                                :func:`write_model_after`
:mod:`bench.gap.files`          ``REPORT_FILES``, the names ``--report DIR`` holds
:mod:`bench.gap.figure`         :func:`gap_figure` (matplotlib, imported when drawing)
:mod:`bench.gap.recording`      :func:`write_recording` and its blueprint (rerun, imported when
                                logging)
=============================== ===============================================================

The equations are the estimation side's: the linear fit of bias and scale is
:func:`calib.calibration.ls.fit_linear`, the forward model
:func:`calib.calibration.correct.apply_errors`, the random-walk filter
:func:`calib.filters.walk_filter`, the low-pass
:func:`calib.filters.lowpass` (through :class:`bench.terms.LowpassLag`).
"""

# The names below are loaded on first use (PEP 562): `import bench.gap.run` must not import the
# report, figure and analysis modules before the re-simulation starts (bench.gap.run).
_HOMES = {
    "AccelField": "bench.gap.readout",
    "AxisPrediction": "bench.gap.prediction",
    "FD_STEP": "bench.gap.sysid",
    "GapReport": "bench.gap.report",
    "MAX_REPLAY_STEPS": "bench.gap.replay",
    "MAX_TABLE_ACCEL": "bench.gap.replay",
    "MAX_TABLE_RATE": "bench.gap.replay",
    "MOTION_TOL": "bench.gap.replay",
    "Motion": "bench.gap.replay",
    "Piece": "bench.gap.replay",
    "READOUT_TOL": "bench.gap.readout",
    "REPORT_FILES": "bench.gap.files",
    "Replay": "bench.gap.replay",
    "ReplayMode": "bench.gap.replay",
    "SYSID_EFFECTS": "bench.gap.sysid",
    "TRACKING_LIMIT": "bench.gap.replay",
    "accel_field": "bench.gap.readout",
    "additive_output": "bench.gap.prediction",
    "find_jumps": "bench.gap.replay",
    "fit_bias_scale": "bench.gap.prediction",
    "gap_figure": "bench.gap.figure",
    "gap_markdown": "bench.gap.writers",
    "initial_state": "bench.gap.replay",
    "make_replay": "bench.gap.replay",
    "motion_sensordata": "bench.gap.replay",
    "predict_axis": "bench.gap.prediction",
    "profile": "bench.gap.replay",
    "readout": "bench.gap.readout",
    "record_motion": "bench.gap.replay",
    "replay_sensordata": "bench.gap.replay",
    "response": "bench.gap.prediction",
    "run_gap": "bench.gap.run",
    "sample_rows": "bench.gap.replay",
    "simulate": "bench.gap.replay",
    "sysid_refine": "bench.gap.sysid",
    "timing": "bench.gap.replay",
    "walk_innovations": "bench.gap.prediction",
    "write_model_after": "bench.gap.writers",
    "write_recording": "bench.gap.recording",
    "write_report": "bench.gap.writers",
}
"""Each public name and the module that holds it."""


def _module(home: str):
    """The submodule ``bench.gap.<home>`` (static imports: the import-rule checks see them)."""
    if home == "bench.gap.figure":
        from bench.gap import figure as mod
    elif home == "bench.gap.files":
        from bench.gap import files as mod
    elif home == "bench.gap.prediction":
        from bench.gap import prediction as mod
    elif home == "bench.gap.readout":
        from bench.gap import readout as mod
    elif home == "bench.gap.recording":
        from bench.gap import recording as mod
    elif home == "bench.gap.replay":
        from bench.gap import replay as mod
    elif home == "bench.gap.report":
        from bench.gap import report as mod
    elif home == "bench.gap.run":
        from bench.gap import run as mod
    elif home == "bench.gap.sysid":
        from bench.gap import sysid as mod
    elif home == "bench.gap.writers":
        from bench.gap import writers as mod
    else:
        raise AttributeError(home)
    return mod


def __getattr__(name: str):
    if name in _HOMES:
        value = getattr(_module(_HOMES[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "FD_STEP", "MAX_REPLAY_STEPS", "MAX_TABLE_ACCEL", "MAX_TABLE_RATE", "MOTION_TOL",
    "READOUT_TOL", "REPORT_FILES", "SYSID_EFFECTS", "TRACKING_LIMIT", "AccelField",
    "AxisPrediction", "GapReport", "Motion", "Piece", "Replay", "ReplayMode", "accel_field",
    "additive_output", "find_jumps", "fit_bias_scale", "gap_figure", "gap_markdown",
    "initial_state", "make_replay", "motion_sensordata", "predict_axis", "profile",
    "readout", "record_motion", "replay_sensordata", "response", "run_gap", "sample_rows",
    "simulate", "sysid_refine", "timing",
    "walk_innovations", "write_model_after", "write_recording", "write_report",
]
