"""Kept for imports of ``bench.figures_trajectory`` (``bench/cli_trajectory.py``): the figure
now lives in :mod:`bench.figures.trajectory`; import it from :mod:`bench.figures`."""

from bench.figures.trajectory import save_trajectory_plot, trajectory_figure

__all__ = ["save_trajectory_plot", "trajectory_figure"]
