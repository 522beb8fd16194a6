"""What ``tiltbench gap --report DIR`` writes: the file names alone.

Kept apart from :mod:`bench.gap.writers` (which imports numpy, MuJoCo and the report) so the
command line can name the files in its help without importing the domain at start-up.
"""

REPORT_FILES = ("gap.json", "gap.md", "gap.png", "gap.svg", "model_after.xml")
"""What :func:`bench.gap.writers.write_report` writes into the report directory."""
