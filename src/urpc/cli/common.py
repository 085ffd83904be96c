"""What every CLI command shares: the error contract, argument types, JSON output, and the
command-line convention (README, "Command line"):

* the robot is ``ROBOT`` (a URDF path or a name), positional where a command needs nothing else
  (``check``, ``bound``, also accepted as ``--robot``), ``--robot ROBOT`` where a scenario can
  stand in for it (``simulate``, ``certify``);
* files read are ``FILE`` (``--uncertainty/-u FILE``, ``--true-params FILE``), the output folder
  is ``--out DIR``, checked writable before any work and written all at once, defaulting to
  ``urpc-results/<job>`` for commands that always write (``simulate`` writes only with ``--out``);
* options with a fixed set of values list them (``--plant {pinocchio,mujoco}``);
* ``--json`` prints one JSON object on stdout; ``--no-progress`` turns off the progress bar,
  which is shown only when stderr is a terminal;
* a run computes its certificate first, once per configuration (the certificate cache):
  ``--no-certify`` skips it, ``--no-cache`` computes it again.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from ..names import BOUND_METHODS, CONTROLLERS  # noqa: F401  (re-exported for the commands)
from ..wording import count  # noqa: F401  (re-exported for the commands)

if TYPE_CHECKING:  # numpy is imported when a command needs it (start-up time of the CLI)
    import numpy as np

EXIT_OK = 0
EXIT_INPUT = 2

#: Root of the default output folders (``urpc-results/<job>``).
RESULTS_ROOT = Path("urpc-results")


#: What argparse must read as a (negative) value, not as an option: ``-5``, ``-0.1``, ``-1e-2``,
#: ``-5%``, ``-0.1,0.2`` (argparse's own pattern misses exponents, percent signs and lists, and
#: answers "expected one argument" instead of the option's own check). No option of urpc starts
#: with a dash and a digit.
NEGATIVE_VALUE = re.compile(r"^-\.?\d[\d.eE+\-,% ]*$")


def path(text: str) -> Path:
    """A path option's value: an empty one (an unset shell variable, ``--out "$DIR"``) is refused
    instead of meaning the current folder."""
    if not text.strip():
        raise argparse.ArgumentTypeError(
            "an empty path (an unset shell variable?): give a file or folder name"
        )
    return Path(text)


class Parser(argparse.ArgumentParser):
    """argparse with the package's error contract: one ``error:`` line, exit code 2; negative
    numbers are values (:data:`NEGATIVE_VALUE`), answered by the option's own check."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_VALUE

    def error(self, message: str):  # type: ignore[override]
        raise InputError(f"{message} (see '{self.prog} --help')")


def add_command(
    commands,
    name: str,
    handler,
    *,
    help: str,
    description: str | None = None,
    epilog: str | None = None,
) -> Parser:
    """The command ``name`` of ``commands`` (from :func:`add_subcommands`), run by
    ``handler(args)`` (its exit code; ``None`` for a command whose subcommands each have one):
    ``help`` is its line in the parent's ``--help``, ``description`` and ``epilog`` its own."""
    parser = commands.add_parser(name, help=help, description=description, epilog=epilog)
    if handler is not None:
        parser.set_defaults(handler=handler)
    return parser


def add_subcommands(parser: argparse.ArgumentParser, dest: str, metavar: str, required=False):
    """The subcommands of ``parser`` (:func:`add_command` adds each), their name stored in
    ``dest``: :class:`Parser` instances, so that they keep the error contract."""
    commands = parser.add_subparsers(dest=dest, metavar=metavar, parser_class=Parser)
    commands.required = required
    return commands


def vector(text: str) -> np.ndarray:
    """Parse ``"0.1,0.2"`` or ``"0.1 0.2"`` into a float vector (NaN/inf rejected)."""
    import numpy as np

    parts = [p for p in text.replace(",", " ").split() if p]
    try:
        values = np.array([float(p) for p in parts])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a list of numbers, e.g. 0.1,0.2"
        ) from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"'{text}' must be finite numbers, e.g. 0.1,0.2")
    return values


def finite_float(text: str) -> float:
    """A finite number (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' must be a finite number")
    return value


def positive_float(text: str) -> float:
    """A finite number > 0 (argparse type)."""
    value = finite_float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be a finite number > 0")
    return value


def non_negative_float(text: str) -> float:
    """A finite number >= 0 (argparse type)."""
    value = finite_float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be a finite number >= 0")
    return value


def _integer(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not an integer") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"'{text}' must be an integer >= {minimum}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1 (argparse type)."""
    return _integer(text, 1)


def non_negative_int(text: str) -> int:
    """An integer >= 0 (argparse type)."""
    return _integer(text, 0)


def names(text: str) -> list[str]:
    return [p for p in text.replace(",", " ").split() if p]


ROBOT_HELP = "URDF path or robot name (rr_planar, ur5, panda, ...; see 'urpc robots')"
UNCERTAINTY_HELP = (
    "uncertainty YAML file (default for a robot with a shipped box: that box; "
    "'urpc init ROBOT --out FILE' writes one)"
)
LOCK_HELP = "comma-separated joints to lock, e.g. panda_finger_joint1,panda_finger_joint2"


def add_robot_arguments(parser: argparse.ArgumentParser, uncertainty_required: bool = False):
    """``ROBOT`` (positional, or ``--robot ROBOT``), ``--uncertainty/-u FILE``, ``--lock``;
    :func:`robot_argument` reads the robot back."""
    parser.add_argument("robot", nargs="?", metavar="ROBOT", help=ROBOT_HELP)
    parser.add_argument(
        "--robot", dest="robot_option", metavar="ROBOT", help="the same as the positional ROBOT"
    )
    parser.add_argument(
        "--uncertainty",
        "-u",
        type=path,
        metavar="FILE",
        required=uncertainty_required,
        help=UNCERTAINTY_HELP,
    )
    add_lock_argument(parser)


def add_lock_argument(parser) -> None:
    """``--lock JOINTS``: joints locked at 0 (:func:`names`; default: none)."""
    parser.add_argument("--lock", type=names, default=[], metavar="JOINTS", help=LOCK_HELP)


JSON_HELP = "print one JSON object"
PROGRESS_HELP = "no progress bar (shown only when stderr is a terminal)"


def add_json_argument(parser, *, on_stdout: bool = False, **options) -> None:
    """``--json``: the command prints one JSON object instead of text (``on_stdout``: the help
    says where)."""
    text = JSON_HELP + (" on stdout" if on_stdout else "")
    parser.add_argument("--json", action="store_true", help=text, **options)


def add_progress_argument(parser, help: str = PROGRESS_HELP) -> None:
    """``--no-progress`` (:func:`show_progress` reads it)."""
    parser.add_argument("--no-progress", action="store_true", help=help)


def add_robot_positional(parser) -> None:
    """``ROBOT``, required and positional (``init``, ``identify``, ``virtual-robot``)."""
    parser.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)


def add_uncertainty_option(parser) -> None:
    """``--uncertainty/-u FILE``, read as a path or a name by the scenario or the plant."""
    parser.add_argument("--uncertainty", "-u", metavar="FILE", help=UNCERTAINTY_HELP)


def add_new_file_arguments(parser) -> None:
    """``--out/-o FILE`` (required) and ``--force``: the file a command writes, never
    overwritten without ``--force``."""
    parser.add_argument(
        "--out", "-o", type=path, required=True, metavar="FILE", help="file to write"
    )
    parser.add_argument("--force", action="store_true", help="overwrite FILE if it exists")


def robot_argument(args) -> str:
    """The robot of :func:`add_robot_arguments` (positional or ``--robot``), stored back into
    ``args.robot``.

    Raises:
        InputError: neither or two different robots given.
    """
    positional, option = args.robot, getattr(args, "robot_option", None)
    if positional is not None and option is not None and positional != option:
        raise InputError(
            f"two robots given: '{positional}' and --robot '{option}'; give one", field="robot"
        )
    robot = positional if positional is not None else option
    if robot is None:
        raise InputError("give a robot: a URDF path or a name (see 'urpc robots')", field="robot")
    args.robot = robot
    return robot


def add_scenario_argument(parser) -> None:
    """The optional ``SCENARIO`` of the commands where ``--robot`` can stand in for it
    (:func:`scenario_or_robot` reads both)."""
    parser.add_argument(
        "scenario",
        nargs="?",
        metavar="SCENARIO",
        help="scenario YAML file or shipped name (rr_planar/s1_ic1 ...); omit with --robot",
    )


def scenario_or_robot(args, example: str, see: str = "", box_help: str = "", **overrides):
    """The scenario of ``SCENARIO``, with ``--robot``/``--uncertainty`` replacing its own, or of
    ``--robot`` with ``--uncertainty`` (default: the robot's shipped box) standing in for one;
    ``overrides`` applied with them (:meth:`urpc.studies.scenario.Scenario.with_overrides`).

    ``example`` (a shipped name), ``see`` and ``box_help`` complete the errors of a command line
    with neither a scenario nor a robot, and of a robot without a box.
    """
    from ..model.catalog import default_uncertainty, resolve_robot
    from ..model.urdf import robot_display_name
    from ..studies.scenario import load_scenario, parse_scenario

    uncertainty = args.uncertainty
    if args.robot is not None and uncertainty is None:
        resolve_robot(args.robot)  # an unknown name: say so, with the closest one
        shipped = default_uncertainty(args.robot)
        uncertainty = None if shipped is None else str(shipped)
    if args.scenario is not None:
        _refuse_a_robot_name_as_scenario(args.scenario)
        return load_scenario(args.scenario).with_overrides(
            robot=args.robot, uncertainty=uncertainty, **overrides
        )
    if args.robot is None:
        raise InputError(
            f"give a scenario file (or a shipped name such as {example}) or --robot{see}",
            field="scenario",
        )
    if uncertainty is None:
        raise InputError(
            f"robot '{args.robot}' has no shipped uncertainty box; write one with "
            f"'urpc init {args.robot} --out box.yaml' and give --uncertainty box.yaml{box_help}",
            field="uncertainty",
        )
    scenario = parse_scenario({"robot": args.robot, "uncertainty": uncertainty})
    return scenario.with_overrides(name=robot_display_name(args.robot), **overrides)


def _refuse_a_robot_name_as_scenario(text: str) -> None:
    """``urpc certify TwoDofs``: a robot's name where a scenario goes is an error that says to give
    it as ``--robot`` (``urpc check`` takes the robot positionally, these commands do not)."""
    from ..model.catalog import builtin_robots, example_robot_data_robots

    if Path(text).exists() or "/" in text or text.endswith((".yaml", ".yml")):
        return
    if text in {*builtin_robots(), *example_robot_data_robots()}:
        from ..studies.scenario import shipped_scenarios

        own = [name for name in shipped_scenarios() if name.startswith(f"{text}/")]
        if own:
            instead = f", or one of its shipped scenarios: {', '.join(own)}"
        else:
            box = f"'urpc init {text} --out box.yaml' writes one"
            instead = f" and --uncertainty BOX.yaml ({box}), or a scenario file"
        raise InputError(
            f"'{text}' is a robot, not a scenario: give it as --robot {text}{instead}",
            field="scenario",
        )


def add_output_arguments(
    parser, default: str | None, *, what: str = "result files and figures", progress: bool = True
) -> None:
    """``--out DIR`` (``default``: a folder under :data:`RESULTS_ROOT`, or ``None``: nothing is
    written without ``--out``), ``--json`` and ``--no-progress``."""
    where = "nothing is written" if default is None else default
    parser.add_argument(
        "--out", type=path, metavar="DIR", help=f"output folder for the {what} (default: {where})"
    )
    add_json_argument(parser, on_stdout=True)
    if progress:
        add_progress_argument(parser)


#: Help of ``--no-certify`` and ``--no-cache`` (simulate, campaign; certify takes ``--no-cache``).
NO_CERTIFY_HELP = (
    "skip the certificate (computed before the run, seconds to minutes of CPU on a real arm): "
    "the output then records certified: null and not_certified: 'not computed (--no-certify)', "
    "never a verdict"
)
NO_CACHE_HELP = (
    "compute the certificate again even when the certificate cache holds it, and replace the "
    "record (the cache: $URPC_CACHE_DIR, else $XDG_CACHE_HOME/urpc or ~/.cache/urpc; "
    "docs/sampled-data.md)"
)


def add_certificate_arguments(parser, *, skippable: bool = True) -> None:
    """``--no-certify`` (with ``skippable``) and ``--no-cache``: the certificate a run computes
    first (once per configuration: later runs read it from the certificate cache)."""
    if skippable:
        parser.add_argument("--no-certify", action="store_true", help=NO_CERTIFY_HELP)
    parser.add_argument("--no-cache", action="store_true", help=NO_CACHE_HELP)


def show_progress(args) -> bool:
    """The rule of every command: a progress bar on stderr only when stderr is a terminal, and
    not with ``--no-progress``."""
    if getattr(args, "no_progress", False):
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # a replaced or closed stream
        return False


#: From this many joints a certificate can cost minutes of CPU (Baxter's 15: 259 s at 1 kHz).
LARGE_ARM_DOF = 10


def certificate_progress(args, dof: int) -> Any:
    """The ``progress`` of a certificate: :func:`show_progress` on a terminal; off a terminal
    (logs, pipes, CI), for an arm of :data:`LARGE_ARM_DOF` joints or more, one line when the
    certificate starts to be computed (not when the cache answers) and its closing line, so that
    minutes of silence do not read as a hang."""
    if show_progress(args):
        return True
    if dof < LARGE_ARM_DOF:
        return False
    said: list[str] = []

    def notice(line: str) -> None:
        if line.startswith("certificate:"):  # the closing line
            if said:
                print(line, file=sys.stderr)
        elif not said:
            said.append(line)
            print(
                f"certificate: computing it for a {dof}-joint arm first (it can take minutes; later "
                "runs of this configuration read it from the cache; --no-certify skips it)",
                file=sys.stderr,
                flush=True,
            )

    return notice


def output_folder(out: Path | None, default: Path) -> Path:
    """The output folder of a command (``out``, or ``default`` under :data:`RESULTS_ROOT`),
    checked writable before any work starts (:func:`urpc.atomic.check_writable`)."""
    from ..atomic import check_writable

    return check_writable(default if out is None else out)


def write_error(exc: OSError, directory: Path) -> InputError:
    """An ``OSError`` while writing ``directory`` as an input error that names the folder and the
    reason, not the staging file's temporary name."""
    reason = exc.strerror or (str(exc.args[0]) if exc.args else type(exc).__name__)
    return InputError(f"cannot write the results ({reason})", source=directory)


def joint_units(kinds) -> tuple[str, str]:
    """The units of positions and of generalized forces for joints of ``kinds``
    (``Robot.joint_kinds``): ``("rad", "N m")`` for revolute joints, ``("m", "N")`` for prismatic
    ones, both for a mix (the error norm then mixes rad and m)."""
    prismatic = [kind == "prismatic" for kind in kinds]
    if all(prismatic) and prismatic:
        return "m", "N"
    if any(prismatic):
        return "rad|m", "N m|N"
    return "rad", "N m"


def one_line(text: str) -> str:
    return " ".join(text.split())


def json_text(payload: dict) -> str:
    from ..jsonsafe import jsonable  # numpy, so not when the command line is parsed

    return json.dumps(jsonable(payload), indent=2, allow_nan=False)


def print_json(payload: dict) -> None:
    print(json_text(payload))


def warn_uncertified(guarantee: dict) -> None:
    """One ``warning:`` line on stderr when a run's configuration is not certified (nothing when
    its certificate was not computed, ``--no-certify``: the output says so)."""
    if guarantee["certified"] is False:
        print(f"warning: {guarantee['not_certified']}", file=sys.stderr)
