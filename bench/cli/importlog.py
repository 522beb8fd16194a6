"""``tiltbench import``: a measured log into the course format, with its provenance.

::

    tiltbench import LOG [--format …] [--columns …] [--axes x,y] [--units …]
                     [--poses …] [--angle-unit deg] --out DIR [--force] [--json]

Reads the log (:func:`calib.logs.reader.read_log`, docs/real-data.md), prints what it found — the
format, which column became what, the units and their conversion, the held poses and the
thresholds that found them — and writes ``ensayo.mat`` (θ known, or θ unknown with held
poses: then no ``tita``) or ``acel.mat`` (no poses), plus ``provenance.json``, as one set
(:func:`calib.logs.export.write_course_set`). ``--json`` prints one object: the files
written and the provenance record.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from bench.cli.logopts import add_log_options, log_options_from_args, reading_progress
from bench.cli.options import add_command, add_force, add_gravity, add_json, check_positive
from bench.cli.output import print_files, print_json
from bench.cli.vocabulary import add_option


def _cmd_import(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from bench.version import __version__
    from calib.logs.export import write_course_set
    from calib.logs.reader import provenance_units, read_log

    check_positive(args.g, "--g")
    if args.rate is not None:
        check_positive(args.rate, "--rate")
    options = replace(log_options_from_args(args), rate=args.rate)
    log = read_log(args.log, options,  # what it found is printed below
                   **reading_progress(args, args.log))
    paths, prov = write_course_set(log, args.out, force=args.force, tool_version=__version__)
    if args.json:
        print_json({"files": [str(p) for p in paths], "provenance": prov,
                    "units": provenance_units(prov)})
        return 0
    print(f"{args.log}: {prov['format']}, {prov.get('samples', {}).get('read', log.n)} samples")
    mapping = prov.get("mapping") or {}
    if mapping:
        print("columns: " + ", ".join(f"{role} ← {name}" for role, name in mapping.items()))
    units = prov.get("units") or {}
    if units:
        conv = units.get("acc_to_m_s2")
        with_g = "" if units.get("acc") == "m/s2" else f", g = {units.get('g'):g} m/s²"
        print(f"units: acceleration {units.get('acc')} (× {conv:.9g} → m/s²{with_g}); axes "
              f"{','.join(prov.get('axes', []))} (tilt axis {prov.get('tilt_axis')}); gyro "
              f"{units.get('gyro_from') or 'none'}"
              + (f" ({units['gyro_note']})" if units.get("gyro_note") else ""))
    poses = prov.get("poses")
    if poses and "detection" in poses:
        from calib.logs.poses import PoseDetection

        print(PoseDetection.from_dict(poses["detection"]).summary())
    elif poses:
        print(f"poses from the {poses['source']}: {', '.join(poses['labels'])}")
    if prov.get("held_samples_only"):
        print(prov["held_samples_only"])
    if prov.get("theta"):
        print(f"θ {prov['theta']}")
    if prov.get("resampled"):
        r = prov["resampled"]
        print(f"resampled onto a uniform grid of {r['step_s']:.6g} s ({r['samples_in']} → "
              f"{r['samples_out']} samples; largest deviation from it "
              f"{r['max_deviation_from_grid_s']:.3g} s)")
    print_files(paths)
    return 0


def register(sub) -> None:
    p = add_command(sub, "import", _cmd_import, help="turn a measured log (CSV, phyphox, Sensor "
                    "Logger, ROS bag, .mat) into the course files plus provenance.json")
    p.add_argument("log", help="the log: a CSV/TSV file (optionally .gz), a ROS 1 .bag, a "
                   "ROS 2 bag directory, or a .mat")
    add_log_options(p)
    add_gravity(p)
    add_option(p, "--out", required=True, type=Path)
    add_option(p, "--rate", type=float, help="sample rate in Hz of a log without a time "
               "column (its samples evenly spaced from t = 0); refused for a log with times")
    add_json(p)
    add_force(p, "existing files in --out")
