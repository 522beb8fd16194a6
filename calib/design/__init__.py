"""Experiment design with power: which θ design, N and sweep rate detect an effect.

For candidate experiments (:mod:`~calib.design.experiments`) and the catalog effects at given
sizes, :func:`analyze_design` reports the nominal fit's parameter std, the power to detect
each effect with the gap workflow's own test and α, the smallest size detected with 80 % and
95 % power (Monte Carlo effects: with ``mc_grid``), and the power to tell apart the
confusable pairs.

One job per module:

* :mod:`~calib.design.experiments` — :class:`Experiment`: θ(t), t of a design (no MuJoCo).
* :mod:`~calib.design.signals`     — an effect at a given size: its linear coefficients, and
  synthetic readings for the Monte Carlo.
* :mod:`~calib.design.power`       — analytic: non-central χ² power, λ, smallest sizes.
* :mod:`~calib.design.montecarlo`  — Monte Carlo through :func:`calib.gap.analyze_gap`.
* :mod:`~calib.design.grid`        — Monte Carlo effects on a grid of sizes (``mc_grid``):
  strength, isotonic fit, the 80 % / 95 % sizes.
* :mod:`~calib.design.pairs`       — the confusable pairs.
* :mod:`~calib.design.result`      — :class:`DesignResult`.
* :mod:`~calib.design.analysis`    — :func:`analyze_design`, end to end.
"""

from calib.design.analysis import DEFAULT_SIZES, analyze_design
from calib.design.experiments import DESIGNS, Experiment
from calib.design.pairs import PAIRS
from calib.design.power import detection_power, noncentrality, power_from_lambda
from calib.design.result import DesignResult

__all__ = ["DEFAULT_SIZES", "DESIGNS", "PAIRS", "DesignResult", "Experiment", "analyze_design",
           "detection_power", "noncentrality", "power_from_lambda"]
