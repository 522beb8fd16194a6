"""Full course sets: calibration run, vehicle run, candidate points, answer key.

A course set is what one student gets (``ensayo.mat``, ``acel.mat``, ``puntos.mat``,
``datos.txt``, same variable names as ``../shared/course-data``) plus the private
``truth.json``. Both runs use the **same** two accelerometers (one :class:`SensorErrorModel`).

Random streams (all from the user's seed):

* the calibration run uses ``SeedSequence(seed)`` itself, through
  :func:`bench.tilt.generate_calibration` (so ``tiltbench generate calibration --seed S`` with
  the same sensor errors reproduces ``ensayo.mat`` byte for byte);
* ``SeedSequence(seed).spawn(3)`` gives independent streams for (0) the scenario: sensor
  errors and acceleration profile, (1) the vehicle's white noise, (2) the answer letter and the
  decoy points;
* receiver fixes (``gps.mat``, only when asked for) use the child ``spawn_key=(13,)``
  (:func:`bench.gnss.gnss_rng`), so the other files do not change.

Candidates: exactly one is the true arrival point (MuJoCo's final position); its letter is
drawn uniformly. One decoy sits near where the **uncorrected** trajectory ends (within
``raw_jitter`` m, as point B of the course), pushed out along the raw-minus-true direction if
that is closer than ``min_separation`` to the truth. The truth and the remaining decoys form
one cluster in which the truth is not special: a cluster centre ``c`` is drawn uniformly in the
disc of radius ``cluster_radius`` around the truth, and the decoys uniformly in the disc of the
same radius around ``c`` (so, seen from ``c``, the truth is distributed like any decoy and
geometry — "the point in the middle" — does not give the answer away). All points are at least
``min_separation`` apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bench.gnss import GPS_FILE, GnssFixes
from bench.model import TableEdits
from bench.sensors import SensorErrorModel
from bench.tilt import CalibrationConfig, CalibrationRun, ThetaDesign, generate_calibration
from bench.vehicle import (
    Segment,
    VehicleConfig,
    VehicleRun,
    make_vehicle_run,
)
from calib.conventions import G
from calib.files.atomic import atomic_dir

COURSE_FILES = ("ensayo.mat", "acel.mat", "puntos.mat", "datos.txt", "truth.json")
LETTERS = ("A", "B", "C", "D")


@dataclass(frozen=True)
class CourseConfig:
    """Everything that defines a course set (besides the seed).

    vehicle : run timing, P0, V0 (course: 60 s at 100 Hz, P0 = (0, 0), V0 = (1, 3)); its
        ``profile`` is used when ``random_profile`` is False; its ``sensor`` is ignored (the
        course's sensor is ``sensor`` below or drawn).
    random_profile : draw ``n_segments`` equal segments with accelerations uniform in
        ``±accel_limits`` (m/s², x and y) from the seed, so every student gets another path.
    sensor : true sensor errors; None draws bias uniform in ±``bias_limit`` m/s² and scale in
        ±``scale_limit`` per axis, with ``noise_var`` (course: 0.25, 0.64 (m/s²)²).
    theta : calibration θ design (course: 20001 angles over [0, 2π]).
    min_separation : smallest distance between candidates, m (course: ≈ 107 m).
    raw_jitter : the raw-end decoy lies within this distance of the uncorrected end, m.
    """

    vehicle: VehicleConfig = field(default_factory=VehicleConfig)
    random_profile: bool = True
    n_segments: int = 3
    accel_limits: tuple[float, float] = (0.6, 0.3)
    sensor: SensorErrorModel | None = None
    noise_var: tuple[float, float] = (0.25, 0.64)
    bias_limit: float = 0.1
    scale_limit: float = 0.05
    theta: ThetaDesign = field(default_factory=ThetaDesign)
    letters: tuple[str, ...] = LETTERS
    min_separation: float = 100.0
    raw_jitter: float = 10.0
    g: float = G

    def to_dict(self) -> dict:
        return {"random_profile": self.random_profile, "n_segments": self.n_segments,
                "accel_limits": list(self.accel_limits), "noise_var": list(self.noise_var),
                "bias_limit": self.bias_limit, "scale_limit": self.scale_limit,
                "letters": list(self.letters), "min_separation": self.min_separation,
                "raw_jitter": self.raw_jitter, "g": self.g}


def random_profile(rng: np.random.Generator, duration: float, rate: float, n_segments: int,
                   accel_limits) -> tuple[Segment, ...]:
    """``n_segments`` segments covering ``duration`` (whole samples), accelerations uniform in
    ``±accel_limits`` (m/s²), rounded to 0.01 m/s² (values a student can read off a plot)."""
    if n_segments < 1:
        raise ValueError(f"n_segments must be >= 1, got {n_segments}")
    m = int(round(duration * rate))
    edges = np.round(np.linspace(0, m, n_segments + 1)).astype(int)
    lim = np.asarray(accel_limits, dtype=float)
    segs = []
    for k in range(n_segments):
        acc = np.round(rng.uniform(-lim, lim), 2)
        segs.append(Segment(float((edges[k + 1] - edges[k]) / rate), (float(acc[0]),
                                                                       float(acc[1]))))
    return tuple(segs)


def random_sensor(rng: np.random.Generator, noise_var, bias_limit: float, scale_limit: float
                  ) -> SensorErrorModel:
    """Bias uniform in ±bias_limit (m/s²), scale uniform in ±scale_limit, per axis."""
    bias = rng.uniform(-bias_limit, bias_limit, 2)
    scale = rng.uniform(-scale_limit, scale_limit, 2)
    return SensorErrorModel.from_pairs(bias, scale, noise_var)


def _unit(rng: np.random.Generator) -> np.ndarray:
    phi = rng.uniform(0.0, 2.0 * np.pi)
    return np.array([np.cos(phi), np.sin(phi)])


def place_candidates(truth, raw_end, rng: np.random.Generator, letters=LETTERS,
                     min_separation: float = 100.0, raw_jitter: float = 10.0,
                     max_tries: int = 100000, cluster_radius: float | None = None,
                     ) -> tuple[dict[str, np.ndarray], str, str]:
    """Candidate points: the truth under a random letter plus plausible decoys (module doc).

    Returns ``(candidates, answer letter, letter of the raw-end decoy)``.
    """
    truth = np.asarray(truth, dtype=float)
    raw_end = np.asarray(raw_end, dtype=float)
    k = len(letters)
    if k < 2:
        raise ValueError("need at least two letters")
    answer = letters[int(rng.integers(k))]
    near = raw_end + raw_jitter * np.sqrt(rng.uniform()) * _unit(rng)
    if np.linalg.norm(near - truth) < min_separation:
        d = raw_end - truth
        direction = d / np.linalg.norm(d) if np.linalg.norm(d) > 0 else _unit(rng)
        near = truth + direction * min_separation * rng.uniform(1.05, 1.3)
    decoys = [near]
    radius = cluster_radius if cluster_radius is not None else 1.6 * min_separation
    centre = truth + radius * np.sqrt(rng.uniform()) * _unit(rng)
    tries = 0
    while len(decoys) < k - 1:
        tries += 1
        if tries > max_tries:
            raise RuntimeError("could not place the decoys; lower min_separation")
        p = centre + radius * np.sqrt(rng.uniform()) * _unit(rng)
        if all(np.linalg.norm(p - q) >= min_separation for q in [truth, *decoys]):
            decoys.append(p)
    others = [x for x in letters if x != answer]
    order = rng.permutation(len(others))
    cands = {answer: truth}
    for i, j in enumerate(order):
        cands[others[j]] = decoys[i]
    return {x: cands[x] for x in letters}, answer, others[order[0]]


@dataclass(frozen=True)
class CourseSet:
    """A generated course set with its truth."""

    # fields alike sensor_twin.StaticRun's in shape only: a different run, nothing to share
    calibration: CalibrationRun
    vehicle: VehicleRun
    candidates: dict
    answer: str
    raw_decoy: str
    sensor: SensorErrorModel
    config: CourseConfig
    seed: int
    gps: GnssFixes | None = None
    """Receiver fixes on the vehicle run (:mod:`bench.gnss`), or None: no ``gps.mat``."""

    def truth(self) -> dict:
        out = {
            "kind": "course", "answer": self.answer, "raw_end_decoy": self.raw_decoy,
            "candidates": {k: np.asarray(v).tolist() for k, v in self.candidates.items()},
            "true_final_position": self.vehicle.truth.final_position.tolist(),
            "raw_final_position": self.vehicle.raw_final_position().tolist(),
            "sensor": self.sensor.to_dict(), "course": self.config.to_dict(),
            "vehicle": self.vehicle.truth_dict(), "calibration": self.calibration.truth(),
            "files": list(COURSE_FILES[:-1]),
        }
        if self.gps is not None:
            out["gps"] = self.gps.truth_dict()
            out["files"].append(GPS_FILE)
        return out


def make_course_set(config: CourseConfig | None = None, seed: int = 0) -> CourseSet:
    """Generate a course set in memory (see the module docstring for the streams)."""
    config = config or CourseConfig()
    scen, noise, cands = (np.random.default_rng(s)
                          for s in np.random.SeedSequence(int(seed)).spawn(3))
    sensor = config.sensor or random_sensor(scen, config.noise_var, config.bias_limit,
                                            config.scale_limit)
    vcfg = config.vehicle
    profile = (random_profile(scen, vcfg.duration, vcfg.rate, config.n_segments,
                              config.accel_limits) if config.random_profile else vcfg.profile)
    vcfg = replace(vcfg, profile=profile, sensor=sensor, g=config.g)
    calibration = generate_calibration(
        CalibrationConfig(theta=config.theta, sensor=sensor, table=TableEdits(g=config.g)),
        int(seed))
    vehicle = make_vehicle_run(vcfg, int(seed), rng=noise)
    candidates, answer, raw_letter = place_candidates(
        vehicle.truth.final_position, vehicle.raw_final_position(), cands, config.letters,
        config.min_separation, config.raw_jitter)
    return CourseSet(calibration, vehicle, candidates, answer, raw_letter, sensor, config,
                     int(seed))


def write_course_files(course: CourseSet, folder: str | Path, truth: bool = True
                       ) -> dict[str, Path]:
    """Write the set's files into the existing, empty ``folder`` (no checks, no lock): the
    body of :func:`write_course`, also used inside a class set and the demo's output.
    ``truth=False`` leaves ``truth.json`` out (a student folder)."""
    from bench.dataset import save_mat, write_datos, write_gps, write_truth

    folder = Path(folder)
    v = course.vehicle
    nv = [course.sensor.x.noise_var, course.sensor.y.noise_var]
    paths = {
        "ensayo": save_mat(folder / "ensayo.mat", {"tita": course.calibration.tita,
                                                   "datos": course.calibration.datos},
                           force=True),
        "acel": save_mat(folder / "acel.mat", {"t": v.t, "Aerr": v.aerr,
                                               **({} if v.gyro is None else {"gyro": v.gyro})},
                         force=True),
        "puntos": save_mat(folder / "puntos.mat",
                           {k: np.asarray(p, float).reshape(1, 2)
                            for k, p in course.candidates.items()}, force=True),
        "datos": write_datos(folder / "datos.txt", v.config.p0, v.config.v0, nv, force=True),
    }
    if course.gps is not None:
        paths["gps"] = write_gps(folder / GPS_FILE, course.gps, force=True)
    if truth:
        paths["truth"] = write_truth(folder / "truth.json", course.truth(), course.seed,
                                     force=True)
    return paths


def write_course(course: CourseSet, out: str | Path, force: bool = False) -> dict[str, str]:
    """Write the five files (six with ``gps.mat``) into ``out`` as one set
    (:func:`calib.files.atomic.atomic_dir`).

    The files go to a temporary directory beside ``out``, which replaces ``out`` as a whole
    when complete: an interrupted run leaves the old set or the new one, never a mix; other
    files in ``out`` are kept. Refuses to overwrite without ``force`` (before writing) and
    while another run writes ``out`` (:class:`calib.files.atomic.OutputBusyError`).
    """
    out = Path(out)
    owned = COURSE_FILES + (() if course.gps is None else (GPS_FILE,))
    clash = [n for n in owned if (out / n).exists()]
    if clash and not force:  # checked again under the lock by atomic_dir
        raise FileExistsError(f"{out}: {', '.join(clash)} already exist(s)")
    with atomic_dir(out, force, owned=owned) as tmp:
        written = write_course_files(course, tmp)
    return {k: str(out / p.name) for k, p in written.items()}


def generate_course(out: str | Path, seed: int = 0, force: bool = False,
                    config: CourseConfig | None = None) -> CourseSet:
    """Generate a course set and write it (``tiltbench generate course``)."""
    # shaped as vehicle.generate_vehicle: each kind's own make and write, too thin to share
    course = make_course_set(config, seed)
    write_course(course, out, force)
    return course


__all__ = [
    "COURSE_FILES", "CourseConfig", "CourseSet", "generate_course", "make_course_set",
    "place_candidates", "random_profile", "random_sensor", "write_course",
    "write_course_files",
]
