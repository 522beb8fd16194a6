"""Options shared by several commands, the parsing of option values, and the help formatter.

Each option has one meaning and unit across commands, declared once in
:mod:`bench.cli.vocabulary` (``--count``: calibration samples; ``--rate``: a sample rate in Hz;
``--g``: gravity in m/s²; ``--force``: overwrite existing outputs; ``--json``: one JSON object on
stdout and nothing else there); every option is added through
:func:`bench.cli.vocabulary.add_option`.

Start-up time: nothing here imports numpy, scipy or mujoco at module level. Defaults that are
domain constants (``calib.conventions.G``, ``calib.vehicle.nmin.COURSE_STEPS``, …) are
:class:`Deferred`: read when the command runs or when its help is printed, so that
``tiltbench --help`` does not import the domain (about a second with scipy and mujoco).
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable, Iterator
from typing import Any

from bench.cli.vocabulary import DeprecatedAlias, add_option


class OptionError(ValueError):
    """An option value that cannot be used; the message names the option and the fix.

    (A ``ValueError``, like :class:`calib.files.course.DataError`, so ``main`` reports both the same
    way; not ``DataError`` itself because importing ``calib.files.course`` imports numpy: start-up
    time.)
    """

DEFAULT_BIAS = "0.08,-0.02"
DEFAULT_SCALE = "-0.03,0.01"
DEFAULT_NOISE = "0.25,0.64"
FULL_TURN = f"0,{2 * math.pi!r}"
"""Default θ range of a calibration run, rad: one full turn."""


class Deferred:
    """A domain constant used as an option default or choice list, read only when needed.

    ``read`` returns the value; it imports the domain module itself. :func:`resolve_deferred`
    replaces deferred defaults by their values after parsing; help text shows ``str(value)``;
    as ``choices`` it behaves as the sequence ``read()`` returns.
    """

    def __init__(self, read: Callable[[], Any]) -> None:
        self.read = read

    def __str__(self) -> str:
        value = self.read()
        return ",".join(map(str, value)) if isinstance(value, tuple) else str(value)

    def __iter__(self) -> Iterator[Any]:
        return iter(self.read())

    def __contains__(self, item: object) -> bool:
        return item in self.read()


def resolve_deferred(args: argparse.Namespace) -> argparse.Namespace:
    """Replace every :class:`Deferred` default left in ``args`` by its value (in place); the
    names of those options go to ``args.deferred_defaults`` (they were not given)."""
    defaulted = [key for key, value in vars(args).items() if isinstance(value, Deferred)]
    for key in defaulted:
        setattr(args, key, getattr(args, key).read())
    args.deferred_defaults = frozenset(defaulted)
    return args


def _gravity() -> float:
    from calib.conventions import G  # imports numpy: read when needed (start-up time)

    return G


GRAVITY = Deferred(_gravity)
"""Default of ``--g``: :data:`calib.conventions.G`, m/s²."""


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows an option's default when it has one worth showing (not None, not a flag's False)
    and its help text does not already state it; lines fit 100 columns on any terminal (as
    every other line the commands print, :func:`bench.cli.output.fit_line`)."""

    def __init__(self, prog: str, indent_increment: int = 2, max_help_position: int = 24,
                 width: int | None = None) -> None:
        import shutil

        if width is None:  # argparse's own default, capped at the project's 100 columns
            width = min(shutil.get_terminal_size().columns, 100) - 2
        super().__init__(prog, indent_increment, max_help_position, min(width, 98))

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if any(action.default is v for v in (None, False, argparse.SUPPRESS)) or "default" in text:
            return text
        return super()._get_help_string(action)


class RawDescriptionHelpFormatter(argparse.RawDescriptionHelpFormatter, HelpFormatter):
    """:class:`HelpFormatter` that keeps the description's and epilog's line breaks."""


class Parser(argparse.ArgumentParser):
    """argparse that takes negative number pairs as option values: ``--bias -0.02,0.08``.

    Plain argparse (< 3.13) only treats ``-5`` or ``-0.5`` as a value, so ``--p0 -5,3`` was an
    "expected one argument" error. Sub-parsers inherit the class (and the help formatter).
    """

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d[\d.eE+\-,\s]*$")

    def error(self, message: str):
        """One line on stderr, exit code 2 (argparse prints the usage first: two lines)."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def parse_known_args(self, args=None, namespace=None):
        """argparse's, then :func:`check_number` on every ``type=float`` option given: NaN,
        ±Inf and absurd magnitudes are found here for every command (each sub-command's
        parser runs this on its own options) and kept in ``numbers_refused`` for
        :func:`refuse_numbers`, which ``main`` calls where errors become one line."""
        namespace, extras = super().parse_known_args(args, namespace)
        refused = list(getattr(namespace, "numbers_refused", []))
        for action in self._actions:
            if isinstance(action, DeprecatedAlias):  # its value is the new option's: checked there
                continue
            value = getattr(namespace, action.dest, None)
            if "--seed" in action.option_strings and isinstance(value, int) and value < 0:
                refused.append(f"--seed must be >= 0 (a numpy seed), got {value}")
            if action.type is not float or not isinstance(value, float) or \
                    value is action.default:
                continue
            try:
                check_number(value, max(action.option_strings, key=len, default=action.dest))
            except OptionError as exc:
                refused.append(str(exc))
        namespace.numbers_refused = refused
        return namespace, extras


def refuse_numbers(args: argparse.Namespace) -> None:
    """Raise :class:`OptionError` for the first numeric option :class:`Parser` refused."""
    refused = getattr(args, "numbers_refused", [])
    if refused:
        raise OptionError(refused[0])


# ---------------------------------------------------------------- commands and option groups
def add_command(sub, name: str, handler: Callable[[argparse.Namespace], int], **kwargs):
    """A command's (or a ``generate`` kind's) parser: ``sub.add_parser(name, **kwargs)`` run
    by ``handler`` (a function of the parsed args that returns the exit code)."""
    p = sub.add_parser(name, **kwargs)
    p.set_defaults(handler=handler)
    return p


def add_json(p: argparse.ArgumentParser) -> None:
    add_option(p, "--json")


def add_force(p: argparse.ArgumentParser, what: str = "existing outputs") -> None:
    add_option(p, "--force", help=f"overwrite {what}")


def add_gravity(p: argparse.ArgumentParser, local: bool = False) -> None:
    """``--g``; ``local``: also ``--latitude``/``--height`` (WGS84 normal gravity) for the
    commands that calibrate measured logs."""
    add_option(p, "--g", type=float, default=GRAVITY)
    if local:
        add_option(p, "--latitude", type=float, default=None,
                   help="geodetic latitude of the site in deg (north +): g becomes the WGS84 "
                   "normal gravity there (instead of --g)")
        add_option(p, "--height", type=float, default=None,
                   help="height of the site above the WGS84 ellipsoid in m (with --latitude; "
                   "default 0)")


def gravity_from_args(args: argparse.Namespace) -> tuple[float, str]:
    """The local gravity g (m/s²) and where it came from: ``--latitude [--height]`` (WGS84
    normal gravity, :func:`calib.conventions.normal_gravity`), ``--g``, or the course value
    assumed (``"assumed"``)."""
    lat, height = getattr(args, "latitude", None), getattr(args, "height", None)
    given = "g" not in getattr(args, "deferred_defaults", frozenset({"g"}))
    if height is not None and lat is None:
        raise OptionError("--height needs --latitude (the WGS84 normal gravity of the site)")
    if lat is not None:
        if given:
            raise OptionError("--g and --latitude both set the local gravity; give one of them")
        from calib.conventions import normal_gravity

        h = 0.0 if height is None else height
        try:
            g = normal_gravity(lat, h)
        except ValueError as exc:
            raise OptionError(f"--latitude/--height: {exc}") from None
        return g, f"WGS84 normal gravity at latitude {lat:g} deg, height {h:g} m"
    return float(args.g), ("--g" if given else "assumed")


def add_noise_inputs(p: argparse.ArgumentParser, stated: bool = False) -> None:
    """``--noise-var`` / ``--datos`` of the commands that read measured data."""
    add_option(p, "--noise-var", help=f"{'stated ' if stated else ''}noise variances x,y in "
               "(m/s²)², e.g. 0.25,0.64")
    add_option(p, "--datos", help="course datos.txt (noise variances are read from it)")


def add_generate_common(p: argparse.ArgumentParser) -> None:
    """``--seed``, ``--out``, ``--force``, ``--json`` of every ``generate`` kind."""
    add_option(p, "--seed", type=int, default=0)
    add_option(p, "--out", required=True)
    add_force(p, "existing files")
    add_json(p)


def add_sensor_options(p: argparse.ArgumentParser) -> None:
    """True sensor errors of a generated run (``--bias``, ``--scale``, ``--noise-var``, ``--g``)."""
    add_option(p, "--bias", default=DEFAULT_BIAS, help="true bias x,y in m/s²")
    add_option(p, "--scale", default=DEFAULT_SCALE, help="true scale-factor error x,y")
    add_option(p, "--noise-var", default=DEFAULT_NOISE, help="noise variances x,y (m/s²)²")
    add_option(p, "--sensor", help="simulate a measured sensor (`tiltbench noise --save`): "
               "its white noise, bias instability, rate random walk and quantization replace "
               "--noise-var, its calibration (if any) --bias/--scale (docs/noise.md)")
    add_gravity(p)


# ---------------------------------------------------------------- option values
# Rules for numbers, checked where an option enters, before any work (issue 11, part 2):
# every value is finite; rates, durations, cycles, gravity and distances are > 0; counts are
# integers >= 1 (or the command's minimum); levels leave room for a finite quantile; and the
# magnitudes below keep every derived number (squares, sums over a run, positions after a
# run) far from overflow, so that a result is finite or the option is refused.
MAGNITUDE_LIMITS: dict[str, float] = {
    "--p0": 1e9,      # m: a million km; positions stay resolved to < 1 µm in float64
    "--v0": 1e6,      # m/s: far past any vehicle; v0·t over a day stays < 1e11 m
    "--bias": 1e6,    # m/s²: 10⁵ g
    "--scale": 1e6,   # dimensionless gain error
    "--profile": 1e6,  # m/s², segment accelerations
    "--g": 1e4,       # m/s²: ≈ 1000 g (the Sun's surface: 274)
    "--min-separation": 1e7,  # m: the size of the Earth
    "--rate": 1e9,    # Hz (sizes are checked separately: bench.limits)
    "--duration": 1e9,  # s
    "--cycles": 1e9,
    "--psi0": 1e6,    # rad: a heading (resolved to 1e-10 rad at this size)
    "--static-window": 1e9,  # s (or samples): as --duration; window lengths stay integers
    "--min-hold": 1e9,       # s (or samples)
}
"""Largest magnitude of each numeric option (each has one meaning across commands)."""

VARIANCE_RANGE = (1e-100, 1e100)
"""Noise variances, (m/s²)²: positive, not subnormal, and within these bounds, so that
residuals²/σ² summed over any run and σ²·(HᵀH)⁻¹ stay finite."""

LEVEL_MAX = 1.0 - 1e-12
"""Largest confidence level: the tail 1 − level must be resolved in double precision (its
spacing near 1 is 1.1e-16; at 1e-12 the quantile is known to 1e-4 relative, and
(1 + level)/2 of a two-sided quantile stays below 1, so the quantile is finite)."""


STD_RANGE = (1e-50, 1e50)
"""Standard deviations given as options, in their unit: 0 (where the command accepts it) or
within this range, so that σ² stays within :data:`VARIANCE_RANGE`."""

STD_OPTIONS = ("--gps-sigma", "--gps-vel-sigma", "--gyro-sigma", "--psi0-sigma", "--p0-std",
               "--v0-std")
"""Options that are standard deviations (checked against :data:`STD_RANGE`)."""


def check_number(value: float, what: str) -> float:
    """A number option ``what`` as given: finite, within :data:`MAGNITUDE_LIMITS` and, for
    :data:`STD_OPTIONS`, 0 or within :data:`STD_RANGE` (signs and ranges of meaning, such as
    a level in (0, 1), are the command's); :class:`OptionError` naming the option."""
    if not math.isfinite(value):
        raise OptionError(f"{what} must be a finite number, got {value}")
    _check_magnitude(value, what)
    low = MINIMUM_LIMITS.get(what)
    if low is not None and 0 < abs(value) < low:
        raise OptionError(f"{what}: magnitude at least {low:g} (or the command's own rule), "
                          f"got {value:g}")
    lo, hi = STD_RANGE
    if what in STD_OPTIONS and value != 0 and not lo <= abs(value) <= hi:
        raise OptionError(f"{what} is a standard deviation: 0 or between {lo:g} and {hi:g} "
                          f"(its square must stay finite and normal), got {value:g}")
    return value


LEVEL_MIN = 1e-12
"""Smallest confidence level, the mirror of :data:`LEVEL_MAX`: a region's quantile, area and
the ratios between areas stay normal numbers (at 1e-300 a ratio of areas was infinite)."""

MINIMUM_LIMITS: dict[str, float] = {
    "--g": 1e-3,      # m/s²: a comet's surface; below, every reference reading is ~0
}
"""Smallest magnitude of a non-zero numeric option (the command says whether 0 is allowed)."""


def _check_magnitude(value: float, what: str) -> None:
    limit = MAGNITUDE_LIMITS.get(what)
    if limit is not None and abs(value) > limit:
        raise OptionError(f"{what}: magnitude at most {limit:g} (a sane value keeps every "
                          f"result finite), got {value:g}")


def parse_pair(text: str, what: str):
    """Parse ``'a,b'`` into a (2,) float array; :class:`OptionError` names the option ``what``.

    Both values must be finite and, for the options of :data:`MAGNITUDE_LIMITS`, within it.
    """
    import numpy as np  # start-up time: only when a pair is parsed

    try:
        vals = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        raise OptionError(f"{what}: expected two numbers 'x,y', got {text!r}") from None
    if len(vals) != 2 or not all(math.isfinite(v) for v in vals):
        raise OptionError(f"{what}: expected two finite numbers 'x,y', got {text!r}")
    for v in vals:
        _check_magnitude(v, what)
    return np.array(vals)


def parse_variances(text: str, what: str = "--noise-var", allow_zero: bool = False):
    """Parse ``'σx²,σy²'`` into a (2,) array of variances, (m/s²)², in :data:`VARIANCE_RANGE`
    (``allow_zero``: 0 also, a noiseless generated run)."""
    nv = parse_pair(text, what)
    lo, hi = VARIANCE_RANGE
    for v in nv:
        if allow_zero and v == 0:
            continue
        if v <= 0:
            raise OptionError(f"{what}: variances must be positive, got {text}")
        if not lo <= v <= hi:
            raise OptionError(f"{what}: variances must be between {lo:g} and {hi:g} (m/s²)² "
                              f"(smaller or larger ones overflow the fit), got {text}")
    return nv


def parse_floats(text: str, what: str) -> tuple[float, ...]:
    """Parse ``'a,b,…'`` into finite floats."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise OptionError(f"{what}: expected comma-separated numbers, got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise OptionError(f"{what}: values must be finite, got {text!r}")
    return values


def _to_int(s: str) -> int:
    """``'20001'`` or an integral float such as ``'1e8'`` → int; ValueError otherwise."""
    try:
        return int(s)
    except ValueError:
        x = float(s)  # ValueError for text
        if not (math.isfinite(x) and x.is_integer()):
            raise ValueError(s) from None
        return int(x)


def integer(text: str) -> int:
    """argparse ``type`` of counts: an integer, also written as ``1e6``."""
    try:
        return _to_int(text.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def parse_ints(text: str, what: str) -> list[int]:
    """Parse ``'a,b,…'`` into integers (``1e6`` allowed; empty text: no values)."""
    try:
        return [_to_int(s.strip()) for s in text.split(",")] if text else []
    except ValueError:
        raise OptionError(f"{what}: expected comma-separated integers, got {text!r}") from None


def check_count(value: int, what: str, minimum: int = 1) -> int:
    """``value`` if it is an integer >= ``minimum``, else :class:`OptionError` naming ``what``."""
    if value < minimum:
        raise OptionError(f"{what} must be >= {minimum}, got {value}")
    return int(value)


def check_positive(value: float, what: str) -> float:
    """``value`` if it is a positive finite number (within :data:`MAGNITUDE_LIMITS` for the
    options listed there), else :class:`OptionError` naming ``what``."""
    if not (math.isfinite(value) and value > 0):
        raise OptionError(f"{what} must be a positive finite number, got {value}")
    _check_magnitude(value, what)
    return float(value)


def check_level(level: float) -> float:
    """A confidence level in (0, 1) given as ``--level``, within
    [:data:`LEVEL_MIN`, :data:`LEVEL_MAX`]."""
    if not 0.0 < level < 1.0:
        raise OptionError(f"--level must be in (0, 1), e.g. 0.95, got {level}")
    if level < LEVEL_MIN:
        raise OptionError(f"--level must be at least 1e-12 (a region of smaller probability "
                          f"has an area that underflows), got {level!r}")
    if level > LEVEL_MAX:
        raise OptionError(f"--level must be at most 1 - 1e-12 (the tail 1 - level is not "
                          f"resolved in double precision beyond), got {level!r}")
    return level


def check_initial_state(args: argparse.Namespace) -> None:
    """``--p0`` / ``--v0`` of ``trajectory`` and ``nmin``, checked before the files are read
    (finite, within :data:`MAGNITUDE_LIMITS`)."""
    for what, text in (("--p0", args.p0), ("--v0", args.v0)):
        if text is not None:
            parse_pair(text, what)


def noise_var_from_args(args: argparse.Namespace):
    """σ² (m/s²)² from ``--noise-var`` or ``--datos``; None means 'estimate from the residuals'."""
    if args.noise_var is not None and args.datos:
        raise OptionError("give either --noise-var or --datos, not both")
    if args.noise_var is not None:
        return parse_variances(args.noise_var)
    if args.datos:
        from calib.files.course import read_datos

        return read_datos(args.datos).noise_var
    return None


def add_sweep_options(p: argparse.ArgumentParser) -> None:
    """``--workers K`` (local processes; default: every core) and ``--scheduler ADDR``
    (a dask.distributed scheduler, e.g. ``tcp://10.0.0.5:8786``) for the long sweeps."""
    add_option(p, "--workers", type=integer, default=None)
    add_option(p, "--scheduler", default=None)


def mapper_from_args(args: argparse.Namespace):
    """The :class:`calib.stats.runs.Mapper` chosen by :func:`add_sweep_options`."""
    from bench.sweep import make_mapper

    workers = getattr(args, "workers", None)
    if workers is not None:
        check_count(workers, "--workers")
    scheduler = getattr(args, "scheduler", None)
    if scheduler is not None and not re.fullmatch(
            r"(tcp|tls|ucx)://(\[[0-9A-Fa-f:.]+\]|[^\s/:\[\]]+):\d{1,5}", scheduler):
        raise OptionError(f"--scheduler must be a scheduler address like "
                          f"tcp://10.0.0.5:8786, got {scheduler!r}")
    return make_mapper(workers, scheduler)
