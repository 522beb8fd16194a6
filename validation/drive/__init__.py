"""validation.drive — a validation part for ``tiltbench gap`` aimed at what the table's drive
does to a sensor, at step-like bias changes and at effects too small to matter.

Written apart from the detector, from the physics alone: the course signs
``A_rx = −g sin θ``, ``A_ry = −g cos θ``, the sensor model ``A_m = (1 + scale)·A_r + bias + v``
and the public effect definitions of ``docs/effects.md``. It imports numpy and scipy only
(``tests/test_imports.py``, rules e and g, and ``tests/test_drive_validation.py``); the scorer
runs the ``tiltbench`` command line and imports neither ``bench`` nor ``calib``.

Modules: :mod:`.motion` (table-motion designs with exact θ, ω, α), :mod:`.sensor` (the sensor
chain: catalog effects, drive-state effects, step-like biases, output stage, and the yardstick
that sizes them), :mod:`.cases` (the fixed case list, the hashed tune/held-out split, building
one case), :mod:`.files` (course ``ensayo.mat``, CSV logs in m/s² or raw counts,
``datos.txt``), :mod:`.generate` (the writer and its CLI), :mod:`.score` (runs
``tiltbench gap`` per case in a subprocess and scores per category and split). README.md says
what is in it and the held-out rule.
"""
