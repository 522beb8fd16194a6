"""Statistics shared by the wings: Monte Carlo runs and what their counts support, residual
diagnostics.

One job per module:

* :mod:`calib.stats.runs`        — one random stream per run, chunks, the map that runs them.
* :mod:`calib.stats.consistency` — NEES and coverage bands over R runs.
* :mod:`calib.stats.proportion`  — exact (Clopper–Pearson) intervals for a proportion.
* :mod:`calib.stats.diagnostics` — residual diagnostics: the gap workflow's yardstick.
* :mod:`calib.stats.binning`     — binned means of a scattered signal.
"""
