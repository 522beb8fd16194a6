"""One module per log format, behind :func:`calib.logs.read_log` (the entry point).

Each reader turns a file into a :class:`calib.logread.table.RawLog`: the file's numeric
columns by role (acceleration axes, time, θ, pose label, gyro axes), the units its header
states or its format documents, and where each sample came from (line, message or index) for
messages. :mod:`calib.logs` then picks the tilt-plane axes, converts units, validates and finds
the held poses. Readers never guess a unit: they report ``None`` when nothing states it.
"""
