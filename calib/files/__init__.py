"""Files: the course files read strictly, and every output written atomically.

One job per module:

* :mod:`calib.files.course`     — ``ensayo.mat``, ``acel.mat``, ``puntos.mat``, ``gps.mat``,
  ``datos.txt``: validated readers (shape, NaN/Inf, monotone ``t``) → :class:`Ensayo`,
  :class:`Acel`, :class:`Fixes`.
* :mod:`calib.files.datos_txt`  — the ``datos.txt`` parser (text as editors write it).
* :mod:`calib.files.angles`     — radians or degrees, told from the readings, never a range.
* :mod:`calib.files.degeneracy` — degenerate calibration data named before any fit runs.
* :mod:`calib.files.atomic`     — atomic files, atomic sets of files, the lock between runs.

The calibration file (``cal.json``) is a calibration's own format: :mod:`calib.calibration.calfile`.
"""
