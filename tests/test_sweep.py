"""calib.stats.runs and bench.sweep: chunks, streams, and mappers that keep task order."""

from __future__ import annotations

import numpy as np
import pytest

from bench.sweep import make_mapper, process_map
from calib.stats.runs import chunk_ranges, run_seeds, serial_map


def _square(x: int) -> int:
    return x * x


def test_chunk_ranges_cover_in_order():
    for runs, chunk in ((10, 3), (10, 10), (10, 100), (1, 1)):
        parts = chunk_ranges(runs, chunk)
        assert [k for r in parts for k in r] == list(range(runs))
        assert all(len(r) <= chunk for r in parts)
    with pytest.raises(ValueError, match="chunk"):
        chunk_ranges(5, 0)


def test_run_seeds_do_not_depend_on_the_count():
    a = run_seeds(3, 5, (7,))
    b = run_seeds(3, 9, (7,))
    assert [s.generate_state(2).tolist() for s in a] == \
        [s.generate_state(2).tolist() for s in b[:5]]
    assert a[0].generate_state(2).tolist() != run_seeds(3, 5)[0].generate_state(2).tolist()


def test_mappers_keep_order_and_report_progress():
    seen = []
    tasks = list(range(7))
    want = [t * t for t in tasks]
    assert serial_map(_square, tasks, lambda d, t: seen.append((d, t))) == want
    assert seen == [(k, 7) for k in range(1, 8)]
    seen.clear()
    assert process_map(2)(_square, tasks, lambda d, t: seen.append((d, t))) == want
    assert sorted(seen) == [(k, 7) for k in range(1, 8)]
    assert make_mapper(1) is serial_map
    assert make_mapper(2)(_square, tasks) == want
    assert np.array_equal(make_mapper(3)(_square, []), [])
