"""``python -m bench.record docs/recordings.md``: rewrite the entity table of the docs."""

import sys

from bench.record.schema import update_docs

for arg in sys.argv[1:] or ["docs/recordings.md"]:
    print(f"{arg}: {'updated' if update_docs(arg) else 'up to date'}")
