"""``python -m bench.cli``: the same as the ``tiltbench`` command."""

import sys

from bench.cli import console

sys.exit(console())
