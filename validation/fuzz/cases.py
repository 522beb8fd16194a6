"""The fuzz cases, by kind (the kinds the issue lists), across every command.

Every case copies its inputs into its own folder under course-like names, so that one case
cannot disturb another and ``--save`` / ``--plot`` targets start absent.
"""

from __future__ import annotations

from pathlib import Path

from validation.fuzz import front_door
from validation.fuzz.runner import Case, end_check, mention_check

NMIN_FAST = ["--confirm-runs", "0", "--draws", "0", "--quiet", "--workers", "1"]
"""nmin without its Monte Carlo parts: the cases probe inputs, not the sweep."""


def _course(f: dict[str, Path], name: str, gps: Path | None = None,
            acel: Path | None = None) -> dict[str, Path]:
    files = {"ensayo.mat": f[f"{name}.ensayo"], "acel.mat": acel or f[f"{name}.acel"],
             "puntos.mat": f[f"{name}.puntos"], "datos.txt": f[f"{name}.datos"],
             "gps.mat": gps or f[f"{name}.gps"], "cal.json": f[f"{name}.cal"]}
    return files


VEH = ["--acel", "acel.mat", "--puntos", "puntos.mat", "--datos", "datos.txt"]
FUSE = ["fuse", *VEH, "--gps", "gps.mat", "--json"]


def calibration_files(f: dict[str, Path]) -> list[Case]:
    """Edited / malformed calibration files through validate, trajectory, nmin and fuse."""
    cases = []
    truth1 = f["c1.truth"]
    # control: an unedited calibration of seed 3 against its own truth is graded (0 or 1)
    cases.append(Case("cal_file", "validate own truth (control)",
                      ["validate", "--truth", "truth.json", "--calibration", "cal.json"],
                      {"truth.json": f["c3.truth"], "cal.json": f["c3.cal"]},
                      ok_codes=(0, 1)))
    for name in ("axes_edited", "params_edited", "both_edited"):
        cases.append(Case("cal_file", f"validate {name} seed-3 cal vs seed-1 truth",
                          ["validate", "--truth", "truth.json", "--calibration", "cal.json"],
                          {"truth.json": truth1, "cal.json": f[f"cal.{name}"]},
                          expect="refuse", ok_codes=(0, 1, 2)))
    refused = ("rho_gt_1", "cov_asymmetric", "cov_negative_var", "n_0", "n_1",
               "n_1000000000000", "sigma2_negative", "sigma2_huge", "bias_huge",
               "scale_minus_one", "cov_huge", "future_version", "truncated", "nan")
    for name in refused:
        files = {**_course(f, "c3"), "cal.json": f[f"cal.{name}"]}
        cases.append(Case("cal_file", f"trajectory --calibration {name}",
                          ["trajectory", "--calibration", "cal.json", *VEH, "--json"],
                          files, expect="refuse"))
        if name in ("rho_gt_1", "n_0", "n_1000000000000", "cov_negative_var", "bias_huge"):
            cases.append(Case("cal_file", f"nmin --calibration {name}",
                              ["nmin", "--calibration", "cal.json", *VEH, *NMIN_FAST,
                               "--json"], files, expect="refuse"))
            cases.append(Case("cal_file", f"fuse --calibration {name}",
                              [*FUSE, "--calibration", "cal.json"], files, expect="refuse"))
            cases.append(Case("cal_file", f"validate --calibration {name}",
                              ["validate", "--truth", "truth.json", "--calibration",
                               "cal.json"], {"truth.json": f["c3.truth"],
                                             "cal.json": f[f"cal.{name}"]},
                              expect="refuse", ok_codes=(0, 1, 2)))
    for name in ("empty_mat", "wrong_mat"):
        files = {**_course(f, "c3"), "cal.mat": f[f"cal.{name}"]}
        for cmd in ("trajectory", "fuse"):
            argv = (["trajectory", *VEH, "--json"] if cmd == "trajectory" else FUSE)
            cases.append(Case("cal_file", f"{cmd} --calibration {name}",
                              [*argv, "--calibration", "cal.mat"], files, expect="refuse"))
        cases.append(Case("cal_file", f"validate --calibration {name}",
                          ["validate", "--truth", "truth.json", "--calibration", "cal.mat"],
                          {"truth.json": f["c3.truth"], "cal.mat": f[f"cal.{name}"]},
                          expect="refuse", ok_codes=(0, 1, 2)))
    return cases


def faulty_fixes(f: dict[str, Path]) -> list[Case]:
    """fuse with faulty gps.mat: refused, flagged inconsistent, or within 5σ of the truth."""
    cases = [Case("gps_fault", "clean fixes (control)", [*FUSE, "--ensayo", "ensayo.mat"],
                  _course(f, "c1"), expect="truth", check=end_check(f["c1.truth"], "fuse"))]
    for name in ("km", "swapped", "offset50", "shift30", "shift_minus5", "outlier200"):
        cases.append(Case("gps_fault", f"fuse gps {name}", [*FUSE, "--ensayo", "ensayo.mat"],
                          _course(f, "c1", gps=f[f"gps.{name}"]), expect="truth",
                          check=end_check(f["c1.truth"], "fuse")))
    for name in ("nan", "unsorted", "one_fix", "huge", "empty"):
        cases.append(Case("gps_fault", f"fuse gps {name}", [*FUSE, "--ensayo", "ensayo.mat"],
                          _course(f, "c1", gps=f[f"gps.{name}"]),
                          expect="refuse" if name in ("nan", "empty", "huge") else "truth",
                          check=end_check(f["c1.truth"], "fuse")))
    return cases


def turning(f: dict[str, Path]) -> list[Case]:
    """Turning runs: bad gyro into fuse; trajectory and nmin on a turning run."""
    truth = f["t1.truth"]
    cases = [Case("turning", "fuse turning clean (control)", [*FUSE, "--ensayo", "ensayo.mat"],
                  _course(f, "t1"), expect="truth", check=end_check(truth, "fuse"))]
    for name in ("missing", "zeros", "degps", "absurd", "constant", "nan"):
        cases.append(Case("turning", f"fuse gyro {name}", [*FUSE, "--ensayo", "ensayo.mat"],
                          _course(f, "t1", acel=f[f"gyro.{name}"]),
                          expect="refuse" if name == "nan" else "truth",
                          check=end_check(truth, "fuse")))
    for psi0 in ("3", "100", "1e6"):
        cases.append(Case("turning", f"fuse --psi0 {psi0}",
                          [*FUSE, "--ensayo", "ensayo.mat", "--psi0", psi0],
                          _course(f, "t1"), expect="truth", check=end_check(truth, "fuse")))
    cases.append(Case("turning", "trajectory on a turning run",
                      ["trajectory", "--ensayo", "ensayo.mat", *VEH, "--json"],
                      _course(f, "t1"), expect="truth",
                      check=end_check(truth, "trajectory", flag="turn|gyro")))
    cases.append(Case("turning", "nmin on a turning run",
                      ["nmin", "--ensayo", "ensayo.mat", *VEH, *NMIN_FAST, "--json"],
                      _course(f, "t1"), expect="truth",
                      check=mention_check("turn|gyro", "the gyro of a turning run")))
    return cases


def malformed_truth(f: dict[str, Path]) -> list[Case]:
    cases = []
    for name in ("empty", "not_json", "list", "empty_object", "end_text", "end_nan",
                 "no_trajectory", "truncated"):
        files = {**_course(f, "t1"), "bad_truth.json": f[f"truth.{name}"]}
        cases.append(Case("truth_file", f"fuse --truth {name}",
                          [*FUSE, "--ensayo", "ensayo.mat", "--truth", "bad_truth.json",
                           "--plot", "f.png"], files))
        cases.append(Case("truth_file", f"validate --truth {name}",
                          ["validate", "--truth", "bad_truth.json", "--calibration",
                           "cal.json"], files, ok_codes=(0, 1, 2),
                          # the sensor truth validate reads is intact in the other files
                          expect="refuse" if name in ("empty", "not_json", "list",
                                                      "empty_object", "truncated") else "any"))
    return cases


ABSURD_NV = ("100,100", "1e300,1e300", "1e-300,1e-300", "1e50,1e50", "1e-50,0.64")


def absurd_noise(f: dict[str, Path]) -> list[Case]:
    """Absurd --noise-var (the issue's runaway: gap … --noise-var 100,100)."""
    cases = []
    for nv in ABSURD_NV:
        for src in ("c1", "q1", "q2", "sw"):
            cases.append(Case("noise_var", f"gap {src} --noise-var {nv}",
                              ["gap", "ensayo.mat", "--noise-var", nv, "--json"],
                              {"ensayo.mat": f[f"{src}.ensayo"]}))
        cases.append(Case("noise_var", f"calibrate --noise-var {nv}",
                          ["calibrate", "ensayo.mat", "--noise-var", nv, "--json"],
                          {"ensayo.mat": f["c1.ensayo"]}))
        cases.append(Case("noise_var", f"design --noise-var {nv}",
                          ["design", "--effects", "misalignment", "--designs", "uniform",
                           "--n", "201", "--noise-var", nv, "--json", "--workers", "1",
                           "--quiet"]))
    return cases


def tiny_runs(f: dict[str, Path]) -> list[Case]:
    """Valid small runs (N = 3, 4, 5; noiseless too), one-sample vehicle runs, empty files."""
    cases = []
    for n in ("n3", "n4", "n5", "n3_exact", "n4_exact", "n5_exact"):
        ens = {"ensayo.mat": f[f"ens.{n}"]}
        for extra in ([], ["--noise-var", "0.25,0.64"], ["--method", "wls"]):
            cases.append(Case("tiny_run", f"calibrate {n} {' '.join(extra)}".strip(),
                              ["calibrate", "ensayo.mat", *extra, "--json"], ens))
        cases.append(Case("tiny_run", f"gap {n}", ["gap", "ensayo.mat", "--noise-var",
                                                   "0.25,0.64", "--json"], ens))
        cases.append(Case("tiny_run", f"gap {n} (σ² estimated)",
                          ["gap", "ensayo.mat", "--json"], ens))
        cases.append(Case("tiny_run", f"trajectory {n}",
                          ["trajectory", "--ensayo", "ensayo.mat", *VEH, "--json"],
                          {**_course(f, "c1"), **ens}))
        cases.append(Case("tiny_run", f"fuse {n}",
                          [*FUSE, "--ensayo", "ensayo.mat"], {**_course(f, "c1"), **ens}))
    for name in ("n2", "empty", "zero_rows", "same_theta", "huge", "constant"):
        ens = {"ensayo.mat": f[f"ens.{name}"]}
        cases.append(Case("tiny_run", f"calibrate {name}",
                          ["calibrate", "ensayo.mat", "--json"], ens))
        cases.append(Case("tiny_run", f"gap {name}",
                          ["gap", "ensayo.mat", "--noise-var", "0.25,0.64", "--json"], ens))
    for name in ("n3", "n1", "empty", "zero_dt"):
        files = {**_course(f, "c1"), "acel.mat": f[f"acel.{name}"]}
        cases.append(Case("tiny_run", f"trajectory acel {name}",
                          ["trajectory", "--ensayo", "ensayo.mat", *VEH, "--json"], files))
        cases.append(Case("tiny_run", f"fuse acel {name}",
                          [*FUSE, "--ensayo", "ensayo.mat"], files))
    files = {**_course(f, "c1"), "acel.mat": f["acel.n3"], "gps.mat": f["gps.n3_run"]}
    cases.append(Case("tiny_run", "fuse 3-sample run, 2 fixes",
                      [*FUSE, "--ensayo", "ensayo.mat"], files))
    for name in ("empty", "one"):
        files = {**_course(f, "c1"), "puntos.mat": f[f"puntos.{name}"]}
        cases.append(Case("tiny_run", f"trajectory puntos {name}",
                          ["trajectory", "--ensayo", "ensayo.mat", *VEH, "--json"], files))
    for name in ("empty", "garbage"):
        files = {**_course(f, "c1"), "datos.txt": f[f"datos.{name}"]}
        cases.append(Case("tiny_run", f"trajectory datos {name}",
                          ["trajectory", "--ensayo", "ensayo.mat", *VEH, "--json"], files))
    for name in ("still3", "header_only"):
        cases.append(Case("tiny_run", f"noise {name}", ["noise", "log.csv", "--json"],
                          {"log.csv": f[f"log.{name}"]}))
        cases.append(Case("tiny_run", f"import {name}",
                          ["import", "log.csv", "--out", "imp", "--json"],
                          {"log.csv": f[f"log.{name}"]}))
    cases.append(Case("tiny_run", "generate calibration --count 3",
                      ["generate", "calibration", "--count", "3", "--out", "g", "--json"]))
    cases.append(Case("tiny_run", "design --n 3",
                      ["design", "--effects", "misalignment", "--designs", "uniform", "--n",
                       "3", "--json", "--workers", "1", "--quiet"]))
    return cases


def _opt(kind: str, name: str, argv: list[str], files: dict | None = None) -> Case:
    return Case(kind, name, argv, files or {}, expect="refuse")


def options(f: dict[str, Path]) -> list[Case]:
    """NaN / Inf / absurd numeric options, every command: each must be refused in one line."""
    c1 = _course(f, "c1")
    t1 = _course(f, "t1")
    ens = {"ensayo.mat": f["c1.ensayo"]}
    cases = []
    gen = {
        "calibration": [("--bias", "nan,0"), ("--scale", "inf,0"), ("--noise-var", "nan,1"),
                        ("--g", "nan"), ("--theta-range", "0,inf"), ("--count", "nan")],
        "vehicle": [("--gyro-sigma", "nan"), ("--gps-sigma", "inf"), ("--gps-rate", "nan"),
                    ("--gps-latency", "inf"), ("--gps-outage", "nan,3"), ("--p0", "nan,0"),
                    ("--gps-sigma", "-1"), ("--gps-rate", "1e300")],
        "course": [("--min-separation", "inf"), ("--g", "0"), ("--bias", "1e300,0"),
                   ("--noise-var", "inf,1")],
        "class": [("--students", "nan"), ("--students", "-1")],
    }
    for kind, opts in gen.items():
        for opt, val in opts:
            extra = ["--gps"] if opt.startswith("--gps-") else []
            if kind == "vehicle" and opt == "--gyro-sigma":
                extra = ["--turning"]
            cases.append(_opt("option", f"generate {kind} {opt} {val}",
                              ["generate", kind, *extra, f"{opt}={val}", "--out", "o"]))
    for opt, val in (("--g", "nan"), ("--level", "nan"), ("--level", "1"), ("--g", "inf"),
                     ("--noise-var", "inf,1"), ("--sensitivity", "nan"),
                     ("--static-window", "nan"), ("--min-hold", "inf")):
        extra = ["--units", "counts"] if opt == "--sensitivity" else []
        src = {"log.csv": f["log.poses"]} if opt in ("--sensitivity", "--static-window",
                                                      "--min-hold") else ens
        arg = "log.csv" if "log.csv" in src else "ensayo.mat"
        cases.append(_opt("option", f"calibrate {opt} {val}",
                          ["calibrate", arg, *extra, f"{opt}={val}", "--json"], src))
    for cmd in ("trajectory", "nmin"):
        fast = NMIN_FAST if cmd == "nmin" else []
        for opt, val in (("--p0", "nan,0"), ("--v0", "0,inf"), ("--level", "nan"),
                         ("--g", "-9.8"), ("--level", "0")):
            cases.append(_opt("option", f"{cmd} {opt} {val}",
                              [cmd, "--ensayo", "ensayo.mat", *VEH, *fast, f"{opt}={val}",
                               "--json"], c1))
    for opt, val in (("--draws", "-1"), ("--mc-n", "nan"), ("--steps", "0"),
                     ("--confirm-runs", "nan"), ("--steps", "1e300")):
        cases.append(_opt("option", f"nmin {opt} {val}",
                          ["nmin", "--ensayo", "ensayo.mat", *VEH, "--quiet", "--workers",
                           "1", f"{opt}={val}", "--json"], c1))
    for opt, val in (("--psi0", "nan"), ("--psi0", "inf"), ("--psi0", "1e300"),
                     ("--psi0-sigma", "nan"), ("--psi0-sigma", "-1"),
                     ("--psi0-sigma", "1e300"), ("--gyro-sigma", "nan"),
                     ("--gyro-sigma", "0"), ("--gyro-sigma", "1e300")):
        cases.append(_opt("option", f"fuse turning {opt} {val}",
                          [*FUSE, "--ensayo", "ensayo.mat", f"{opt}={val}"], t1))
    for opt, val in (("--gps-sigma", "nan"), ("--gps-sigma", "0"), ("--gps-sigma", "-1"),
                     ("--gps-sigma", "1e300"), ("--gps-sigma", "1e-300"),
                     ("--gps-vel-sigma", "nan"), ("--p0-std", "nan"), ("--p0-std", "inf"),
                     ("--p0-std", "1e300"), ("--v0-std", "-1"), ("--level", "nan"),
                     ("--psi0", "nan")):
        cases.append(_opt("option", f"fuse {opt} {val}",
                          [*FUSE, "--ensayo", "ensayo.mat", f"{opt}={val}"], c1))
    for opt, val in (("--rate", "nan"), ("--g", "inf"), ("--g", "0")):
        cases.append(_opt("option", f"gap {opt} {val}",
                          ["gap", "ensayo.mat", "--noise-var", "0.25,0.64", f"{opt}={val}",
                           "--json"], ens))
    log = {"log.csv": f["log.still"]}
    for opt, val in (("--rate", "nan"), ("--level", "nan"), ("--alpha", "inf"),
                     ("--tau-range", "nan,1"), ("--static-window", "nan"),
                     ("--static-shift", "inf"), ("--static-var-ratio", "nan"),
                     ("--level", "1"), ("--alpha", "0")):
        cases.append(_opt("option", f"noise {opt} {val}",
                          ["noise", "log.csv", f"{opt}={val}", "--json"], log))
    for opt, val in (("--n", "nan"), ("--rate", "nan"), ("--alpha", "nan"),
                     ("--size", "misalignment=nan"), ("--noise-var", "nan,1"),
                     ("--scale", "inf"), ("--mc-grid", "nan"), ("--runs", "-1"),
                     ("--size", "misalignment=1e300")):
        cases.append(_opt("option", f"design {opt} {val}",
                          ["design", "--effects", "misalignment", "--designs", "uniform",
                           f"{opt}={val}", "--json", "--workers", "1", "--quiet"]))
    cases.append(_opt("option", "validate --level nan",
                      ["validate", "--truth", "truth.json", "--calibration", "cal.json",
                       "--level=nan"], {"truth.json": f["c1.truth"], "cal.json": f["c1.cal"]}))
    plog = {"log.csv": f["log.poses"]}
    for opt, val in (("--g", "nan"), ("--sensitivity", "inf"), ("--static-window", "nan"),
                     ("--min-hold", "-1"), ("--poses", "nan,1,2,3")):
        extra = ["--units", "counts"] if opt == "--sensitivity" else []
        cases.append(_opt("option", f"import {opt} {val}",
                          ["import", "log.csv", *extra, f"{opt}={val}", "--out", "imp"],
                          plog))
    return cases


def writers(f: dict[str, Path]) -> list[Case]:
    """Concurrent writers of one path, the input as the output, kills before the rename."""
    two = {"a.mat": f["c1.ensayo"], "b.mat": f["c3.ensayo"]}
    cases = []
    for opt, target in (("--save", "cal.json"), ("--save", "cal.mat"), ("--plot", "fit.png")):
        cases.append(Case("writers", f"two calibrate {opt} {target} at once",
                          ["calibrate", "a.mat", "--noise-var", "0.25,0.64", opt, target],
                          two, parallel=[["calibrate", "b.mat", "--noise-var", "0.25,0.64",
                                          opt, target]]))
    c1 = _course(f, "c1")
    cases.append(Case("writers", "two fuse --plot at once",
                      [*FUSE, "--ensayo", "ensayo.mat", "--plot", "f.png"], c1,
                      parallel=[[*FUSE, "--calibration", "cal.json", "--plot", "f.png"]]))
    cases.append(Case("writers", "calibrate --save onto its input --force",
                      ["calibrate", "a.mat", "--noise-var", "0.25,0.64", "--save", "a.mat",
                       "--force"], two, inputs_unchanged=("a.mat",)))
    cases.append(Case("writers", "calibrate --plot onto its input --force",
                      ["calibrate", "a.mat", "--noise-var", "0.25,0.64", "--plot", "a.mat",
                       "--force"], two, inputs_unchanged=("a.mat",)))
    cases.append(Case("writers", "noise --save onto its input --force",
                      ["noise", "log.csv", "--save", "log.csv", "--force"],
                      {"log.csv": f["log.still"]}, inputs_unchanged=("log.csv",)))
    cases.append(Case("writers", "import --out its own folder --force",
                      ["import", "log.csv", "--out", ".", "--force"],
                      {"log.csv": f["log.poses"]}, inputs_unchanged=("log.csv",)))
    for delay in (2.0, 3.0, 4.0):
        cases.append(Case("writers", f"calibrate --save killed at {delay} s, then rerun",
                          ["calibrate", "a.mat", "--noise-var", "0.25,0.64", "--save",
                           "cal.json", "--force"], two, kill_after=delay))
        cases.append(Case("writers", f"generate class killed at {delay} s, then rerun",
                          ["generate", "class", "--students", "3", "--workers", "1", "--quiet",
                           "--out", "cls", "--force"], kill_after=delay))
    return cases


SWEEP_VALUES = ("nan", "-inf", "1e300", "1e-300", "-1")
"""Values tried on every numeric option: NaN/±Inf must be refused; the others must give a
finite answer or a one-line refusal (-1 is meaningful for some options)."""


def option_sweep(f: dict[str, Path]) -> list[Case]:
    """Every numeric (float) option of every command (``tiltbench X --help``) × the values
    of :data:`SWEEP_VALUES`, on small valid inputs."""
    c1, t1 = _course(f, "c1"), _course(f, "t1")
    ens = {"ensayo.mat": f["c1.ensayo"]}
    plog, slog = {"log.csv": f["log.poses"]}, {"log.csv": f["log.still"]}
    design = ["design", "--effects", "misalignment", "--designs", "uniform", "--n", "201",
              "--json", "--workers", "1", "--quiet"]
    table = [
        (["calibrate", "ensayo.mat", "--json"], ens, ("--g", "--level")),
        (["calibrate", "log.csv", "--poses", "0,90,180,270", "--angle-unit", "deg",
          "--json"], plog, ("--static-window", "--min-hold")),
        (["calibrate", "log.csv", "--units", "counts", "--json"], plog, ("--sensitivity",)),
        (["trajectory", "--ensayo", "ensayo.mat", *VEH, "--json"], c1, ("--level", "--g")),
        (["nmin", "--ensayo", "ensayo.mat", *VEH, *NMIN_FAST, "--json"], c1, ("--level",)),
        ([*FUSE, "--ensayo", "ensayo.mat"], c1,
         ("--gps-sigma", "--gps-vel-sigma", "--p0-std", "--v0-std", "--level")),
        ([*FUSE, "--ensayo", "ensayo.mat"], t1, ("--gyro-sigma", "--psi0", "--psi0-sigma")),
        (["gap", "ensayo.mat", "--noise-var", "0.25,0.64", "--json"], ens, ("--rate", "--g")),
        (["noise", "log.csv", "--json"], slog,
         ("--rate", "--level", "--alpha", "--static-window", "--static-shift",
          "--static-var-ratio")),
        (design, {}, ("--alpha", "--scale")),
        (["validate", "--truth", "truth.json", "--calibration", "cal.json"],
         {"truth.json": f["c1.truth"], "cal.json": f["c1.cal"]}, ("--level",)),
        (["import", "log.csv", "--poses", "0,90,180,270", "--angle-unit", "deg", "--out",
          "imp", "--json"], plog, ("--g", "--static-window", "--min-hold")),
        (["generate", "calibration", "--count", "201", "--out", "o", "--json"], {}, ("--g",)),
        (["generate", "calibration", "--mode", "sweep", "--duration", "2", "--out", "o",
          "--json"], {}, ("--rate", "--cycles")),
        (["generate", "vehicle", "--duration", "5", "--gps", "--out", "o", "--json"], {},
         ("--rate", "--gps-rate", "--gps-sigma", "--gps-vel-sigma", "--gps-latency")),
        (["generate", "vehicle", "--duration", "5", "--turning", "--out", "o", "--json"], {},
         ("--gyro-sigma",)),
        (["generate", "course", "--count", "201", "--duration", "5", "--out", "o", "--json"],
         {}, ("--min-separation",)),
    ]
    cases = []
    for argv, files, opts in table:
        for opt in opts:
            for val in SWEEP_VALUES:
                expect = "refuse" if val in ("nan", "-inf") else "any"
                cases.append(Case("opt_sweep", f"{argv[0]} {opt}={val}",
                                  [*argv, f"{opt}={val}"], files, expect=expect,
                                  ok_codes=(0, 1, 2) if argv[0] == "validate" else (0, 2)))
    return cases


INT_VALUES = ("-1", "1e15")
"""Counts tried on every integer option: a negative one and an absurd size (each must be
refused in one line, or run and end within the hang limit)."""


def int_sweep(f: dict[str, Path]) -> list[Case]:
    """Every count / size / seed option (``tiltbench X --help``) × :data:`INT_VALUES`."""
    c1 = _course(f, "c1")
    design = ["design", "--effects", "saturation", "--designs", "uniform", "--n", "201",
              "--json", "--workers", "1", "--quiet"]
    nmin = ["nmin", "--ensayo", "ensayo.mat", *VEH, "--quiet", "--workers", "1", "--json"]
    table = [
        (design, {}, ("--runs", "--mc-grid", "--seed", "--n")),
        ([*nmin, "--confirm-runs", "0", "--draws", "0"], c1,
         ("--runs", "--mc-n", "--steps", "--seed")),
        ([*nmin, "--confirm-runs", "0"], c1, ("--draws",)),
        ([*nmin, "--draws", "0"], c1, ("--confirm-runs",)),
        (["generate", "calibration", "--out", "o", "--json"], {},
         ("--count", "--positions", "--seed")),
        (["generate", "calibration", "--positions", "4", "--out", "o", "--json"], {},
         ("--per-position",)),
        (["generate", "class", "--out", "o", "--quiet", "--workers", "1"], {}, ("--students",)),
        (["generate", "course", "--out", "o", "--json"], {}, ("--count",)),
    ]
    cases = []
    for argv, files, opts in table:
        for opt in opts:
            for val in INT_VALUES:
                cases.append(Case("int_sweep", f"{argv[0]} {opt}={val}",
                                  [*argv, f"{opt}={val}"], files))
    return cases


LONG_DIR = "/".join(["a-folder-whose-name-is-long-enough"] * 4)
"""A relative folder of 139 characters: its paths are wider than a terminal of 100 columns
(a message shows such a path whole, alone on its line)."""


def messages(f: dict[str, Path]) -> list[Case]:
    """A refusal of each kind on every command: argparse's own errors (an unknown command,
    kind, action, option or choice; a missing or malformed argument), a missing input, a
    folder or a file of the wrong kind given for an input, an existing output without
    ``--force``, an output onto its input, a path wider than the terminal. Each must be one
    error message (wrapped at 100 columns like every line) that names what it refuses."""
    c1 = _course(f, "c1")
    ens = {"ensayo.mat": f["c1.ensayo"]}
    veh = ["--calibration", "cal.json", *VEH]
    cal = {"truth.json": f["c1.truth"], "cal.json": f["c1.cal"]}
    argvs = [
        ("unknown command", ["calibrat", "ensayo.mat"], ens),
        ("unknown option", ["calibrate", "ensayo.mat", "--noise-variance", "1,1"], ens),
        ("invalid choice", ["calibrate", "ensayo.mat", "--method", "ml"], ens),
        ("required options missing", ["trajectory", "--ensayo", "ensayo.mat"], ens),
        ("not an integer", ["generate", "class", "--students", "many", "--out", "o"], {}),
        ("unknown generate kind", ["generate", "calibratoin", "--out", "o"], {}),
        ("unknown record action", ["record", "write", "x.rrd"], {}),
        ("unknown effect", ["design", "--effects", "misalignmnet", "--json"], {}),
        ("runs below the minimum", ["fusion-study", "--runs", "1", "--out", "fs"], {}),
        ("level out of range", ["demo", "--level", "2", "--out", "d"], {}),
        ("calibrate missing input", ["calibrate", "missing.mat"], {}),
        ("gap missing input", ["gap", "missing.mat"], {}),
        ("trajectory missing input", ["trajectory", "--calibration", "cal.json", "--acel",
                                      "acel.mat", "--puntos", "missing.mat"], c1),
        ("nmin missing input", ["nmin", "--calibration", "cal.json", "--acel", "missing.mat",
                                "--puntos", "puntos.mat", *NMIN_FAST], c1),
        ("fuse missing input", ["fuse", *veh, "--gps", "missing.mat"], c1),
        ("validate missing input", ["validate", "--truth", "missing.json", "--calibration",
                                    "cal.json"], cal),
        ("noise missing input", ["noise", "missing.csv"], {}),
        ("apply missing input", ["apply", "missing.csv", "--calibration", "cal.json", "--out",
                                 "corrected.csv"], cal),
        ("import missing input", ["import", "missing.csv", "--out", "imp"], {}),
        ("record missing input", ["record", "read", "missing.rrd"], {}),
        ("demo missing course data", ["demo", "--course-data", "nowhere", "--out", "d"], {}),
        ("a folder for a file", ["calibrate", "."], {}),
        ("a JSON file for a recording", ["record", "entities", "truth.json"], cal),
        ("a JSON file for a .mat", ["gap", "truth.json"], cal),
        ("a path wider than the terminal", ["calibrate", f"{LONG_DIR}/ensayo.mat",
                                            "--noise-var", "nan,1"],
         {f"{LONG_DIR}/ensayo.mat": f["c1.ensayo"]}),
        ("a missing path wider than the terminal", ["gap", f"{LONG_DIR}/missing.mat"], {}),
        ("existing output without --force", ["calibrate", "ensayo.mat", "--save",
                                             "cal.json"], {**ens, "cal.json": f["c1.cal"]}),
        ("existing outputs without --force", ["generate", "course", "--out", "set"],
         {"set/ensayo.mat": f["c1.ensayo"]}),
        ("existing example without --force", ["examples", "ex"],
         {"ex/data/README.md": f["c1.datos"]}),
        ("fusion-study table without --force", ["fusion-study", "--runs", "2", "--out", "fs"],
         {"fs/fusion-study.md": f["c1.datos"]}),
        ("output onto its input", ["calibrate", "ensayo.mat", "--save", "ensayo.mat",
                                   "--force"], ens),
    ]
    return [Case("message", name, argv, files, expect="refuse",
                 inputs_unchanged=tuple(n for n in files if n == "ensayo.mat"))
            for name, argv, files in argvs]


KINDS = {
    "cal_file": calibration_files,
    "gps_fault": faulty_fixes,
    "turning": turning,
    "truth_file": malformed_truth,
    "noise_var": absurd_noise,
    "tiny_run": tiny_runs,
    "option": options,
    "opt_sweep": option_sweep,
    "int_sweep": int_sweep,
    "writers": writers,
    "message": messages,
    **front_door.KINDS,  # issue 31: the log readers and the commands that read logs
}


def all_cases(f: dict[str, Path], kinds: list[str] | None = None) -> list[Case]:
    out = []
    for kind, make in KINDS.items():
        if kinds is None or kind in kinds:
            out += make(f)
    return out
