"""Mean reading of the extended model at new angles and times."""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, RunData, effect
from calib.gap.estimates import Reporter
from calib.gap.results import GapAnalysis


def predict(analysis: GapAnalysis, tita: np.ndarray, t: np.ndarray | None = None,
            rate: float | None = None) -> np.ndarray:
    """Mean reading of the extended model, ``A_m_hat(θ, t)`` (N, 2), m/s².

    Parameters
    ----------
    analysis : the result of :func:`analyze_gap` (its ``final`` model).
    tita : (N,) encoder angle, rad.  t : (N,) sample times, s, or ``rate`` (Hz): needed when
        the model has a low-pass, a lever arm or a drift per second.

    Notes
    -----
    ``bias + (1 + s)·[LPF_τ(clip(A_r(θ), ±L)) + extensions] + rate·(t - t0)``; a random walk
    (zero mean) and the rounding of a quantization are not included (the rounding changes the
    mean by less than ``lsb·e^{-2π²σ²/lsb²}``). The drift starts at the first sample of
    ``tita``. On the analysed run this equals ``analysis.fitted``.
    """
    final = analysis.final
    tita = np.asarray(tita, dtype=float)
    run = RunData.build(tita, np.zeros((tita.size, 2)), analysis.g, t, rate)
    for k, a in enumerate(AXES):
        st = final.state.axes[k]
        needs = any(effect(n).needs_times_to_predict(final.time_unit) for n in st.effects())
        if needs and not run.timed:
            raise ValueError(f"axis {a}: the extended model needs sample times (t or rate) "
                             "to predict (low-pass, lever arm or drift per second)")
    ext = Extensions(run, np.asarray(final.gains))
    rep = Reporter.from_params(ext, final.state, list(final.names), final.params)
    return np.column_stack([rep.mean(k) for k in range(2)])
