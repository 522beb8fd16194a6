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

from bench.gap.figure import gap_figure
from bench.gap.prediction import (
    AxisPrediction,
    additive_output,
    fit_bias_scale,
    predict_axis,
    response,
    walk_innovations,
)
from bench.gap.readout import READOUT_TOL, AccelField, accel_field, readout
from bench.gap.recording import write_recording
from bench.gap.replay import (
    MAX_REPLAY_STEPS,
    MAX_TABLE_ACCEL,
    MAX_TABLE_RATE,
    MOTION_TOL,
    TRACKING_LIMIT,
    Motion,
    Piece,
    Replay,
    ReplayMode,
    find_jumps,
    initial_state,
    make_replay,
    motion_sensordata,
    profile,
    record_motion,
    replay_sensordata,
    sample_rows,
    simulate,
    timing,
)
from bench.gap.report import GapReport
from bench.gap.run import run_gap
from bench.gap.sysid import FD_STEP, SYSID_EFFECTS, sysid_refine
from bench.gap.writers import REPORT_FILES, gap_markdown, write_model_after, write_report

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
