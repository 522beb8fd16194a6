"""bench — the simulation side of tiltbench: MuJoCo models, sensor error models, run
generators, datasets, recordings, the discrepancy workflow and the command line.

``bench`` may import ``calib``; never the other way round.
"""

__version__ = "0.1.0"
