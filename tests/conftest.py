from __future__ import annotations

import os

# One BLAS thread: numpy's and scipy's OpenBLAS pools otherwise fight (~10x slower LS).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import gc  # noqa: E402
from pathlib import Path  # noqa: E402

from bench.cli import GC_YOUNG, keep_freed_memory  # noqa: E402  (no domain module)

# The program's process settings (bench.cli.console), before numpy is imported: freed arrays
# stay in the process and numpy asks for no huge pages, and the collector's youngest
# generation runs every GC_YOUNG new objects. Measured on five test modules (test_angles,
# test_sixface, test_region, test_multiposition3d, test_gap_switching), two alternating runs
# each: 97.1 and 88.2 s → 89.0 and 83.2 s, system time 5.6 and 4.5 s → 2.2 and 1.5 s.
gc.set_threshold(GC_YOUNG, *gc.get_threshold()[1:])
keep_freed_memory()

import matplotlib  # noqa: E402
import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

matplotlib.use("Agg")

# Property tests draw the same examples on every machine and every run (a green suite stays
# green on a fresh clone, where no example database exists); `pytest --hypothesis-profile
# explore` draws new ones, to search for failures on purpose.
settings.register_profile("repeatable", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile("repeatable")

REPO = Path(__file__).resolve().parents[1]
COURSE_DATA = REPO.parent / "shared" / "course-data"


@pytest.fixture(scope="session")
def course_dir() -> Path:
    """The real course files, read in place from ../shared (never copied into the repo)."""
    if not (COURSE_DATA / "ensayo.mat").exists():
        raise RuntimeError(f"course data not found at {COURSE_DATA}; CI must place ../shared "
                           "beside the checkout")
    return COURSE_DATA


@pytest.fixture(autouse=True)
def _isolated_home(tmp_path_factory, monkeypatch):
    """The rerun binary writes analytics settings under the home directory: keep it in tmp."""
    home = tmp_path_factory.getbasetemp() / "xdg"
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home / "config"))
    monkeypatch.setenv("XDG_DATA_HOME", str(home / "data"))
    monkeypatch.setenv("RERUN_ANALYTICS", os.environ.get("RERUN_ANALYTICS", "0"))


@pytest.fixture(scope="session")
def course(course_dir):
    """The course files read and calibrated the course way (σ² = 0.25, 0.64, per-axis OLS):
    ``(ensayo, acel, puntos, calibration, trajectory)``."""
    from calib.calibration.tilt_plane import calibrate
    from calib.files.course import read_acel, read_ensayo, read_puntos
    from calib.vehicle.trajectory import compute_trajectory
    from tests.reference import course_2009 as ref

    ensayo = read_ensayo(course_dir / "ensayo.mat")
    acel = read_acel(course_dir / "acel.mat")
    cal = calibrate(ensayo, ref.NOISE_VAR)
    return ensayo, acel, read_puntos(course_dir / "puntos.mat"), cal, compute_trajectory(acel, cal)


class FuzzCounter:
    """Cases tried by the fuzz and fault tests, by kind (printed at the end of the run)."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}

    def tried(self, kind: str, n: int = 1) -> None:
        self.counts[kind] = self.counts.get(kind, 0) + n


_FUZZ = FuzzCounter()


@pytest.fixture(scope="session")
def fuzz_counter() -> FuzzCounter:
    """Count a case: ``fuzz_counter.tried("readers")`` (session scope: usable in @given)."""
    return _FUZZ


FUZZ_MODULES = ("test_readers_fuzz", "test_options_fuzz", "test_validate_inputs",
                "test_faults", "test_angles")
"""Modules whose cases are counted: one per explicit test, one per hypothesis example."""


def _counted(kind: str, inner):
    def run(*args, **kwargs):
        _FUZZ.tried(kind)
        return inner(*args, **kwargs)
    return run


def pytest_collection_modifyitems(items):
    for item in items:
        module = item.module.__name__.rsplit(".", 1)[-1] if item.module else ""
        if module not in FUZZ_MODULES:
            continue
        handle = getattr(item.obj, "hypothesis", None)  # @given: count every example
        if handle is not None and not getattr(handle.inner_test, "_counted", False):
            handle.inner_test = _counted(module, handle.inner_test)
            handle.inner_test._counted = True
        elif handle is None:
            item.user_properties.append(("fuzz_kind", module))


@pytest.fixture(autouse=True)
def _count_explicit_case(request):
    kind = dict(request.node.user_properties).get("fuzz_kind")
    if kind is not None:
        _FUZZ.tried(kind)


def pytest_terminal_summary(terminalreporter):
    if _FUZZ.counts:
        parts = ", ".join(f"{k} {v}" for k, v in sorted(_FUZZ.counts.items()))
        terminalreporter.write_line(
            f"fuzz and fault cases tried: {sum(_FUZZ.counts.values())} ({parts})")
