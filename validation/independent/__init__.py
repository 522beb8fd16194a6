"""validation.independent — a second validation set for ``tiltbench gap``, made independently.

Written from the physics alone (the tilt-table kinematics, the course signs
``A_rx = −g sin θ``, ``A_ry = −g cos θ``, the IEEE Std 1293 model equation and the effect
definitions of ``docs/effects.md``) without reading the detector (``calib/gap``,
``calib/effects``, ``bench/gap``) or the first validation generator: it imports numpy and scipy
only, and nothing of ``validation`` outside this folder (``tests/test_imports.py``, rules e
and f). Its designs and out-of-catalog mechanisms are ones the first set does not have.

Modules: :mod:`.physics` (kinematics, reference, the yardstick that sizes effects),
:mod:`.designs` (θ schedules with exact rates), :mod:`.effects` (the sensor chain),
:mod:`.cases` (the fixed case list, the hashed tune/held-out split, building one case),
:mod:`.generate` (the writer and its CLI), :mod:`.score` (runs ``tiltbench gap`` in
subprocesses and scores per split). README.md says how to use it and the held-out rule.
"""
