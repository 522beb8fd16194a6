"""Measured logs: the logs people have, read into one record, checked, their held poses found.

:func:`calib.logs.reader.read_log` is the entry point. One module per format turns a file into
a :class:`calib.logs.table.RawLog`: the file's numeric columns by role (acceleration axes,
time, θ, pose label, gyro axes), the units its header states or its format documents, and
where each sample came from (line, message or index) for messages. Readers never guess a unit:
they report ``None`` when nothing states it. :mod:`calib.logs.reader` then picks the
tilt-plane axes, converts units, validates and finds the held poses.

* :mod:`calib.logs.reader`     — :func:`read_log`, :class:`LogOptions`, :class:`ImuLog`.
* :mod:`calib.logs.table`      — :class:`RawLog`, the units readers recognize.
* :mod:`calib.logs.csvlog`, :mod:`calib.logs.matlog`, :mod:`calib.logs.rosbag` — the formats.
* :mod:`calib.logs.export`     — a log written out as course files.
* :mod:`calib.logs.poses`      — the static-segment detector (held poses).
* :mod:`calib.logs.gyro_angle` — θ(t) from a gyro about the tilt axis.
* :mod:`calib.logs.static_log` — the checks of a still log (rate, quantization, stillness).
"""
