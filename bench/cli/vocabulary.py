"""The option vocabulary: every option name of every command, its meaning and unit, declared once.

An option name means one thing in every command (issue 29): ``--rate`` is a sample rate in Hz
wherever it appears, ``--count`` a number of calibration samples, ``--level`` a confidence
level, ``--scale`` a scale-factor error pair x,y. :data:`VOCABULARY` declares each name once:
its meaning, its unit, and the argparse form every command shares (a flag, a metavar).
Commands add their options with :func:`add_option`, which takes the term from here (a name
that is not declared is a ``KeyError`` when the parser is built), attaches it to the argparse
action (``action.term``) and uses the term's own help when the command gives none. A
command's help may add what is particular to it, but states the term's unit
(:func:`vocabulary_problems` checks it).

Defaults belong to the commands: they differ where the task differs, and the term says why
(``Term.defaults``): ``--level`` is 0.95 for parameter intervals, 0.997 for the course's
arrival region, 0.99 for ``validate``'s test and 0.683 for ``noise``'s Allan intervals;
``--static-window`` is 0.5 s for the pose detector and 1 s for ``noise``'s static check.

A renamed option keeps its old spelling as a deprecated alias (:data:`RENAMED`,
``add_option(..., old=…)``): it still works, says ``warning: --n is deprecated; use --count``
on stderr, and is not shown by ``--help``.

:func:`option_table` derives the table of every option of every command from a parser (its
``_actions``: argparse keeps no public list); :func:`vocabulary_problems` checks that table
against the vocabulary (``tests/test_option_vocabulary.py``).

Start-up time: nothing here imports numpy, scipy or mujoco (``tiltbench --help`` builds every
parser).
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any

PHYSICAL_UNITS = ("Hz", "s", "m", "m/s", "m/s²", "(m/s²)²", "rad", "rad/s", "s : m/s²", "deg")
"""Units a command's own help of the option must state (the other units — ``1``, ``count``,
``file``, ``folder``, ``—`` — and the units of options whose unit is another option's choice
need not be spelled out). ``deg`` is the one angle not in radians: a site's latitude, as maps
give it."""


@dataclass(frozen=True)
class Term:
    """One option name: what it means and in which unit, in every command.

    ``unit``: an SI unit (:data:`PHYSICAL_UNITS`), ``1`` (dimensionless: probabilities,
    ratios, scale-factor errors), ``count`` (a whole number of things), ``file`` / ``folder``
    (a path), ``—`` (a flag, a name, a choice, text), ``counts/g``, or ``--angle-unit`` (the
    unit that option states). ``flag``: a switch (``store_true``) in
    every command that has it unless a command states another action; ``metavar``: how its
    value is written in the help. ``defaults``: why its default differs between commands,
    where it does.
    """

    name: str
    meaning: str
    unit: str
    flag: bool = False
    metavar: str | None = None
    defaults: str = ""

    @property
    def help(self) -> str:
        """The help of a command that adds nothing of its own: the meaning, and the unit when
        it is physical."""
        return f"{self.meaning}, {self.unit}" if self.unit in PHYSICAL_UNITS else self.meaning


_LEVEL_DEFAULTS = ("calibrate: 0.95 (parameter intervals); trajectory, nmin, fuse, demo: 0.997 "
                   "(the course's arrival region, 3σ); validate: 0.99 (the pass probability "
                   "of an honest estimator); noise: 0.683 (one sigma, the Allan-deviation "
                   "convention of IEEE Std 952, and the interval sensor.json hands to "
                   "gap --sensor, which searches the walk's q within it)")
_WINDOW_DEFAULTS = ("the pose detector (log options): 0.5 s, or 25 samples without sample "
                    "times — short, to find the edges of short holds; noise's static check: "
                    "1 s — each window's variance needs a few samples at the 5–10 Hz of phone "
                    "loggers (2 samples would fail the variance-ratio test by chance in most "
                    "10-minute logs) and its mean must average the noise below --static-shift")

VOCABULARY: tuple[Term, ...] = (
    # ---------------------------------------------------------------- files in and out
    Term("--acel", "vehicle run acel.mat (t, Aerr) or a measured log", "file"),
    Term("--calibration", "calibration file cal.json (calibrate --save)", "file",
         metavar="CAL"),
    Term("--course-data", "a folder with the course files (ensayo.mat, acel.mat, puntos.mat, "
         "datos.txt)", "folder", metavar="DIR"),
    Term("--datos", "course datos.txt (P0, V0, noise variances)", "file"),
    Term("--ensayo", "calibration run ensayo.mat (tita, datos) or a measured log", "file"),
    Term("--estimates", "est.json: the calibrate --json object or {axes: {x: {bias, scale}, "
         "y: {...}}}", "file"),
    Term("--gps", "GNSS position fixes gps.mat: t_gps M×1 s, pos M×2 m, optional vel M×2 m/s "
         "(generate writes it, fuse reads it; docs/gnss.md)", "file"),
    Term("--puntos", "candidate points puntos.mat (A, B, …)", "file"),
    Term("--sensor", "sensor profile sensor.json (tiltbench noise --save)", "file",
         metavar="SENSOR_JSON"),
    Term("--theta-from", "an ensayo.mat whose θ schedule (every sample, in order) the run "
         "repeats", "file", metavar="ENSAYO"),
    Term("--truth", "truth.json of a generated set (validate: or a class answer_key.json)",
         "file"),
    Term("--out", "where the output goes: a folder (apply: the corrected log file)", "path",
         metavar="DIR"),
    Term("--plot", "write a figure (.png or .svg)", "file", metavar="F"),
    Term("--report", "write the report files into this folder", "folder", metavar="DIR"),
    Term("--rrd", "write a rerun recording to this file", "file", metavar="F"),
    Term("--save", "write the command's result file (calibrate: cal.json or cal.mat; noise: "
         "sensor.json)", "file"),
    Term("--figures", "figure format(s) written", "—"),
    Term("--force", "overwrite existing outputs", "—", flag=True),
    Term("--json", "print one JSON object on stdout and nothing else there",
         "—", flag=True),
    Term("--quiet", "no progress lines on stderr", "—", flag=True),
    Term("--no-rrd", "do not write the rerun recording", "—", flag=True),
    Term("--all", "also list the JSON tree nodes", "—", flag=True),
    # ---------------------------------------------------------------- reading a measured log
    Term("--format", "log format (auto: recognized from the content)", "—"),
    Term("--columns", "column names by role: t=…,x=…,y=…,z=…,theta=…,label=…,gyro=… (topic=… "
         "for a bag)", "—"),
    Term("--axes", "the log's axes that are the tilt plane's x,y, with signs (e.g. -y,z)", "—"),
    Term("--units", "acceleration unit of the log", "—"),
    Term("--sensitivity", "counts per g (with --units counts)", "counts/g"),
    Term("--gyro-unit", "unit of the gyro columns", "—"),
    Term("--time-unit", "unit of a CSV log's time column", "—"),
    Term("--angle-unit", "unit of θ, --poses and label angles", "—"),
    Term("--map", ".mat variable names: tita=NAME,datos=NAME,t=NAME", "—"),
    Term("--allow-gaps", "read a log with gaps in time", "—", flag=True),
    Term("--allow-saturation", "read a log with stretches at a column's extreme value", "—",
         flag=True),
    Term("--poses", "angle of each held pose, in order", "--angle-unit"),
    Term("--label-angles", "angle of each value of the label column", "--angle-unit"),
    Term("--theta-source", "where θ of every sample comes from: the poses' angles or the "
         "integrated gyro", "—"),
    Term("--static-window", "window of the stillness test (samples when the log has no sample "
         "times)", "s", metavar="S", defaults=_WINDOW_DEFAULTS),
    Term("--min-hold", "shortest held pose (samples when the log has no sample times)", "s",
         metavar="S"),
    Term("--static-shift", "largest window-mean shift of a held pose", "m/s²", metavar="MS2"),
    Term("--static-var-ratio", "largest window variance over the median window's", "1",
         metavar="R"),
    # ---------------------------------------------------------------- the sensor and the table
    Term("--bias", "the sensor's bias x,y (x,y,z: a 3-axis sensor)", "m/s²", metavar="BX,BY"),
    Term("--scale", "the sensor's scale-factor error x,y (x,y,z: a 3-axis sensor; gain 1 + "
         "scale)", "1",
         metavar="SX,SY", defaults="generate: -0.03,0.01 (a sensor with errors, near the "
         "course's); design: 0,0 (an ideal gain unless told)"),
    Term("--noise-var", "noise variances per axis x,y (x,y,z: a 3-axis sensor)", "(m/s²)²",
         metavar="VAR_X,VAR_Y"),
    Term("--misalignment", "a 3-axis sensor's misalignment angles m_xy,m_xz,m_yx,m_yz,m_zx,m_zy "
         "(K = (I + S)(I + M))", "rad", metavar="MXY,MXZ,MYX,MYZ,MZX,MZY"),
    Term("--faces", "the faces of a 3-axis sensor's case held up, in order (e.g. "
         "+x,-x,+y,-y,+z,-z)", "—", metavar="FACES"),
    Term("--holds-per-face", "how many times the list of faces is held", "count", metavar="K"),
    Term("--hold-seconds", "length of each hold", "s", metavar="S"),
    Term("--between-hold-std", "std of each hold's placement tilt about each horizontal axis",
         "rad", metavar="RAD"),
    Term("--g", "local gravity the sensor feels (not the unit g, which is 9.80665 m/s²)",
         "m/s²"),
    Term("--latitude", "geodetic latitude of the site, for the WGS84 normal gravity (north +)",
         "deg"),
    Term("--height", "height of the site above the WGS84 ellipsoid, with --latitude", "m"),
    Term("--effect", "a catalog effect added to the run (docs/effects.md)", "—",
         metavar="NAME:AXIS:KEY=VALUE[,KEY=VALUE]"),
    Term("--mode", "how the table moves: held poses (static) or a servo sweep", "—"),
    Term("--theta", "table angle", "rad"),
    Term("--theta-range", "θ range start,stop", "rad"),
    Term("--theta-list", "explicit θ values, comma-separated", "rad"),
    Term("--positions", "number of discrete held positions", "count"),
    Term("--per-position", "samples held at each position", "count"),
    Term("--count", "number of calibration samples N", "count", metavar="N",
         defaults="generate: 20001 (the course's run); design: 2001 (a quick first look at "
         "each design)"),
    Term("--sweep-profile", "commanded angle profile of a sweep", "—"),
    Term("--sweep-rate", "mean angular rate ω̄ of a sweep", "rad/s", metavar="RADPS"),
    Term("--cycles", "up-down or sine cycles of a sweep", "1"),
    Term("--duration", "length of the run", "s",
         defaults="generate calibration: 20 s (a sweep); vehicle, course: 60 s (the course's "
         "run); static: 600 s (a noise log: the Allan deviation needs long τ)"),
    Term("--rate", "sample rate of the readings", "Hz", metavar="HZ"),
    # ---------------------------------------------------------------- the vehicle and fixes
    Term("--profile", "the vehicle's acceleration segments 'dur:ax,ay;…' or 'course'",
         "s : m/s²"),
    Term("--p0", "initial position x,y", "m", metavar="X,Y"),
    Term("--v0", "initial velocity x,y", "m/s", metavar="VX,VY"),
    Term("--p0-std", "σ of the initial position per axis", "m", metavar="M"),
    Term("--v0-std", "σ of the initial velocity per axis", "m/s", metavar="MPS"),
    Term("--turning", "a turning vehicle: free yaw hinge, body-frame readings and a gyro",
         "—", flag=True),
    Term("--gyro-sigma", "white gyro noise std", "rad/s", metavar="RADPS"),
    Term("--psi0", "initial heading from world +x", "rad", metavar="RAD"),
    Term("--psi0-sigma", "std of the initial heading", "rad", metavar="RAD"),
    Term("--gps-rate", "fix rate", "Hz", metavar="HZ"),
    Term("--gps-sigma", "position fix noise std per axis", "m", metavar="M"),
    Term("--gps-vel-sigma", "velocity fix noise std per axis", "m/s", metavar="MPS"),
    Term("--gps-latency", "age of a fix: the fix at t reports the state at t - S", "s",
         metavar="S"),
    Term("--gps-outage", "no fixes for A <= t <= B", "s", metavar="A,B"),
    Term("--min-separation", "smallest distance between candidate points", "m"),
    # ---------------------------------------------------------------- estimation and decisions
    Term("--method", "calibration method", "—"),
    Term("--integrator", "double integration rule", "—", metavar="RULE"),
    Term("--level", "confidence level of every interval, region or test the command reports",
         "1", metavar="L", defaults=_LEVEL_DEFAULTS),
    Term("--alpha", "significance (false-alarm probability) of the command's test", "1",
         defaults="design: 0.001, the gap's family α; noise: 0.05, one-sided, per term"),
    Term("--gate-alpha", "innovation gate's false-rejection probability per fix", "1",
         metavar="A"),
    Term("--consistency-alpha", "false-alarm probability of the windowed NIS test", "1",
         metavar="A"),
    Term("--nis-window", "fixes per window of the NIS test", "count", metavar="K"),
    Term("--smoother", "also run the Rauch-Tung-Striebel smoother", "—", flag=True),
    Term("--std", "which standard deviations are graded", "—"),
    Term("--tau-range", "fit only the octave τ within MIN,MAX", "s", metavar="MIN,MAX"),
    Term("--save-failed-fit", "write the sensor profile even when no model describes an axis's "
         "Allan curve (fit_ok: false in sensor.json)", "—", flag=True),
    Term("--allow-failed-fit", "accept a sensor profile saved from a failed fit (fit_ok: false)",
         "—", flag=True),
    Term("--twin", "simulate the fitted profile for the log's length and rate and test its "
         "Allan deviation against the log's (twin closure, docs/noise.md)", "—", flag=True),
    Term("--datasheet", "a sensor's datasheet values, each with its own unit (µg/√Hz, °/h, …), "
         "to check the measured noise terms against: [SCOPE.]TERM=VALUE UNIT items or a JSON "
         "file (docs/noise.md)", "—", metavar="SPEC|FILE"),
    # ---------------------------------------------------------------- Monte Carlo and sweeps
    Term("--seed", "seed of every random draw", "—"),
    Term("--runs", "Monte Carlo runs per case", "count",
         defaults="nmin: 0 (its synthetic runs are opt-in); design: 10 per cell; fusion-study: "
         "200 per scenario (a NEES band of about ±0.6 around 2)"),
    Term("--draws", "draws from the calibration's sampling law", "count"),
    Term("--confirm-runs", "regenerated calibrations at the fixed-run N", "count"),
    Term("--coverage-runs", "fresh synthetic calibrations in the coverage check", "count"),
    Term("--mc-n", "calibration sizes N of fresh synthetic runs (comma-separated)", "count"),
    Term("--mc-grid", "Monte Carlo sizes on a grid around the asked size", "count",
         metavar="K"),
    Term("--steps", "subsampling steps (every k-th sample, comma-separated)", "count"),
    Term("--workers", "local processes for the Monte Carlo runs (default: every core; 1 = "
         "this process); results do not depend on it", "count", metavar="K"),
    Term("--scheduler", "run the Monte Carlo on a dask.distributed cluster whose scheduler is "
         "at ADDR (tcp://host:port); needs tiltbench[cluster]", "—", metavar="ADDR"),
    Term("--designs", "θ designs (comma-separated)", "—"),
    Term("--effects", "catalog effects (comma-separated)", "—"),
    Term("--size", "effect size in the effect's unit (docs/effects.md)", "—",
         metavar="NAME=VALUE"),
    Term("--axis", "axis carrying the per-axis effects", "—"),
    # ---------------------------------------------------------------- a class
    Term("--students", "number of students K", "count", metavar="K"),
    Term("--student", "student folder name (e.g. student_001)", "—"),
    Term("--prefix", "folder prefix (student_001, …)", "—"),
)
"""Every option name of every command, once (:func:`vocabulary_problems` checks it)."""

TERMS: dict[str, Term] = {t.name: t for t in VOCABULARY}

RENAMED: tuple[tuple[str, str, str], ...] = (
    ("design", "--n", "--count"),
    ("design", "--rate", "--sweep-rate"),
    ("generate calibration", "--profile", "--sweep-profile"),
)
"""(command, old spelling, new name) of each renamed option: the old spelling still works as
a hidden deprecated alias (issue 29: ``--rate`` is a sample rate in Hz everywhere, ``--count``
the number of calibration samples, ``--profile`` the vehicle's acceleration segments)."""


def deprecated(old: str, new: str) -> None:
    """The one warning line of a deprecated spelling, on stderr."""
    print(f"warning: {old} is deprecated; use {new}", file=sys.stderr)


class DeprecatedAlias(argparse.Action):
    """The old spelling of a renamed option: stores into the new option's destination and
    says, once per use, which name to use instead (:func:`deprecated`)."""

    def __init__(self, option_strings, dest, renamed_to: str, **kwargs) -> None:
        super().__init__(option_strings, dest, **kwargs)
        self.renamed_to = renamed_to

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        deprecated(option_string or self.option_strings[0], self.renamed_to)
        setattr(namespace, self.dest, values)


def add_option(p, name: str, *, old: str | None = None, **kwargs: Any) -> argparse.Action:
    """``p.add_argument(name, **kwargs)`` with the term of ``name`` (:data:`VOCABULARY`):
    its help when ``kwargs`` has none, ``store_true`` for a flag, its metavar for a value; the
    term is kept on the action (``action.term``). ``old``: the option's former spelling,
    added as a hidden :class:`DeprecatedAlias` (listed in :data:`RENAMED`).

    ``p`` is a parser, an argument group or a mutually exclusive group.
    """
    try:
        term = TERMS[name]
    except KeyError:
        raise KeyError(f"{name}: not in bench.cli.vocabulary.VOCABULARY; declare its meaning "
                       "and unit there first") from None
    kwargs.setdefault("help", term.help)
    if (term.unit in PATH_UNITS and not term.flag
            and kwargs.get("action") in (None, "store", "append")):
        kwargs["type"] = _nonempty_path(kwargs.get("type"), name)
    if term.flag:
        kwargs.setdefault("action", "store_true")
    elif term.metavar is not None and kwargs.get("action") not in ("store_true", "store_false"):
        kwargs.setdefault("metavar", term.metavar)
    action = p.add_argument(name, **kwargs)
    action.term = term
    if old is not None:
        alias = p.add_argument(old, dest=action.dest, action=DeprecatedAlias, renamed_to=name,
                               type=action.type, choices=action.choices, metavar=action.metavar,
                               default=argparse.SUPPRESS, help=argparse.SUPPRESS)
        alias.term = None
    return action


PATH_UNITS = ("file", "folder", "path")
"""Units of options that name a file or folder: an empty value is refused by the parser."""


def _nonempty_path(convert: Any, name: str):
    """An argparse ``type`` that refuses an empty or blank path (``--out ''`` would write into
    the current folder) and then applies ``convert`` (e.g. ``Path``), if any."""
    def parse(text: str) -> Any:
        if not str(text).strip():
            raise argparse.ArgumentTypeError("an empty path; give a file or folder name")
        return text if convert is None else convert(text)

    parse.__name__ = getattr(convert, "__name__", "path")  # argparse names the type in errors
    return parse


# ---------------------------------------------------------------- the table and its check
@dataclass(frozen=True)
class OptionRow:
    """One option of one command, as its parser holds it."""

    command: str
    """``"generate calibration"``, ``"design"``, …"""
    name: str
    term: Term | None
    """None: added without :func:`add_option` (no declared meaning)."""
    flag: bool
    """Takes no value."""
    help: str | None
    renamed_to: str | None
    """The new name when this is a deprecated alias."""
    dest: str


def _subcommands(parser: argparse.ArgumentParser) -> Iterator[tuple[str, Any]]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            yield from action.choices.items()


def option_table(parser: argparse.ArgumentParser, command: str = "") -> list[OptionRow]:
    """Every option (not positional) of every command and sub-command under ``parser``, in
    the order of the parsers; ``--help`` and ``--version`` left out."""
    rows = []
    for action in parser._actions:
        if not action.option_strings or isinstance(
                action, (argparse._HelpAction, argparse._VersionAction)):
            continue
        for name in action.option_strings:
            rows.append(OptionRow(command=command, name=name,
                                  term=getattr(action, "term", None), flag=action.nargs == 0,
                                  help=action.help,
                                  renamed_to=getattr(action, "renamed_to", None),
                                  dest=action.dest))
    for sub, subparser in _subcommands(parser):
        rows += option_table(subparser, f"{command} {sub}".strip())
    return rows


def states_unit(text: str, unit: str) -> bool:
    """Whether ``text`` names ``unit`` as a word (``s`` in "length, s", not in "m/s" or
    "samples")."""
    # not inside a longer unit: "m/s" is no "s", "(m/s²)²" no "m/s²"
    pattern = r"(?<![\w/])" + re.escape(unit) + r"(?![\w/²]|\)²)"
    return re.search(pattern, text) is not None


def _listed(commands: Iterable[str]) -> str:
    return ", ".join(sorted(set(commands)))


def vocabulary_problems(rows: list[OptionRow], vocabulary: tuple[Term, ...] = VOCABULARY,
                        renamed: tuple[tuple[str, str, str], ...] = RENAMED) -> list[str]:
    """What is wrong with the option table ``rows`` (:func:`option_table`): one line per
    problem, none when every name means one thing.

    * a name declared twice in ``vocabulary``;
    * an option added without a term (its meaning and unit declared nowhere);
    * a name whose rows carry different meanings or units (two commands, two meanings), or a
      term other than the vocabulary's;
    * a command's help of an option with a physical unit that does not state that unit;
    * a deprecated alias not listed in ``renamed``, shown in the help, or whose new name is
      not an option of the same command with the same destination; a ``renamed`` entry
      without its alias.
    """
    problems = []
    declared: dict[str, Term] = {}
    for term in vocabulary:
        if term.name in declared:
            problems.append(f"{term.name}: declared twice in the vocabulary")
        declared.setdefault(term.name, term)
    live = [r for r in rows if r.renamed_to is None]
    meanings: dict[str, dict[tuple[str, str], list[str]]] = {}
    for r in live:
        if r.term is None:
            problems.append(f"{r.command}: {r.name} has no declared meaning (add it with "
                            "bench.cli.vocabulary.add_option, its term in VOCABULARY)")
            continue
        meanings.setdefault(r.name, {}).setdefault((r.term.meaning, r.term.unit),
                                                   []).append(r.command)
        if r.term.name != r.name:
            problems.append(f"{r.command}: {r.name} carries the term of {r.term.name}")
        elif declared.get(r.name) != r.term:
            said = declared.get(r.name)
            problems.append(f"{r.command}: {r.name} means '{r.term.meaning}' ({r.term.unit}); "
                            + (f"the vocabulary declares '{said.meaning}' ({said.unit})"
                               if said else "the vocabulary does not declare it"))
        if (r.term.unit in PHYSICAL_UNITS and r.help not in (None, argparse.SUPPRESS)
                and not states_unit(r.help, r.term.unit)):
            problems.append(f"{r.command}: the help of {r.name} does not state its unit "
                            f"{r.term.unit}: {r.help!r}")
    for name, found in meanings.items():
        if len(found) > 1:
            problems.append(f"{name} has {len(found)} meanings: " + "; ".join(
                f"'{meaning}' ({unit}) in {_listed(cmds)}"
                for (meaning, unit), cmds in found.items()))
    problems += _alias_problems(rows, renamed)
    return problems


def _alias_problems(rows: list[OptionRow], renamed: tuple[tuple[str, str, str], ...]
                    ) -> list[str]:
    problems = []
    listed = set(renamed)
    found = set()
    by_command: dict[str, dict[str, OptionRow]] = {}
    for r in rows:
        if r.renamed_to is None:
            by_command.setdefault(r.command, {})[r.name] = r
    for r in rows:
        if r.renamed_to is None:
            continue
        key = (r.command, r.name, r.renamed_to)
        found.add(key)
        new = by_command.get(r.command, {}).get(r.renamed_to)
        if key not in listed:
            problems.append(f"{r.command}: {r.name} is a deprecated alias of {r.renamed_to} "
                            "not listed in RENAMED")
        if new is None or new.dest != r.dest:
            problems.append(f"{r.command}: {r.name} is a deprecated alias of {r.renamed_to}, "
                            "which the command does not have (with the same destination)")
        if r.help is not argparse.SUPPRESS:
            problems.append(f"{r.command}: the deprecated {r.name} is shown in --help")
    for key in sorted(listed - found):
        problems.append(f"{key[0]}: RENAMED lists {key[1]} → {key[2]}, but the command has no "
                        f"such alias")
    return problems


def unused_terms(rows: list[OptionRow], vocabulary: tuple[Term, ...] = VOCABULARY
                 ) -> list[str]:
    """Names declared in ``vocabulary`` that no option of ``rows`` uses."""
    used = {r.name for r in rows}
    return [t.name for t in vocabulary if t.name not in used]


__all__ = ["PHYSICAL_UNITS", "RENAMED", "TERMS", "VOCABULARY", "DeprecatedAlias",
           "OptionRow", "Term", "add_option", "deprecated", "option_table", "states_unit",
           "unused_terms", "vocabulary_problems"]
