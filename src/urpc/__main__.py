"""Command-line interface: ``urpc COMMAND ...`` (``urpc --help`` lists the commands).

Contract for every command: exit code 0 on success, 2 for bad user input with a single line on
stderr starting with ``error:`` (no traceback); ``--json`` prints one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .errors import InputError, UrpcError

EXIT_OK = 0
EXIT_INPUT = 2


class _Parser(argparse.ArgumentParser):
    """argparse with the package's error contract: one ``error:`` line, exit code 2."""

    def error(self, message: str):  # type: ignore[override]
        raise InputError(f"{message} (see '{self.prog} --help')")


def _vector(text: str) -> np.ndarray:
    """Parse ``"0.1,0.2"`` or ``"0.1 0.2"`` into a float vector (NaN/inf rejected)."""
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


def _names(text: str) -> list[str]:
    return [p for p in text.replace(",", " ").split() if p]


def _add_robot_arguments(parser: argparse.ArgumentParser, uncertainty_required: bool = False):
    parser.add_argument(
        "robot", help="URDF path, built-in name (rr_planar) or example-robot-data name (ur5, panda)"
    )
    parser.add_argument(
        "--uncertainty",
        "-u",
        type=Path,
        required=uncertainty_required,
        help="uncertainty YAML file (default for built-in robots: the robot's uncertainty.yaml)",
    )
    parser.add_argument(
        "--lock",
        type=_names,
        default=[],
        metavar="JOINTS",
        help="comma-separated joints to lock, e.g. panda_finger_joint1,panda_finger_joint2",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="urpc",
        description=(
            "Ultimate robust performance control: synthesize a passivity-based tracking controller "
            "whose gains adapt until the joint error stays below epsilon, from a URDF and a file "
            "of parameter intervals; bound the model-mismatch torque with interval methods; "
            "simulate and compare with the r-alpha baseline."
        ),
        epilog="Exit codes: 0 success, 2 bad input. Docs: docs/ in the source tree.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    commands.required = True

    p = commands.add_parser("robots", help="list the robots that can be loaded by name")
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = commands.add_parser(
        "check",
        help="validate a robot and an uncertainty file, print the box",
        description="Load ROBOT, validate the uncertainty file against it, and print the box: "
        "links, parameters, nominal values, bounds and relative widths.",
    )
    _add_robot_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = commands.add_parser(
        "bound",
        help="enclose the mismatch torque w at one state",
        description="Enclose the mismatch torque w = Y_SL (pi - pi0) - d over the box at one "
        "state, and print lower, upper and rho = max(|lower|, |upper|) per joint [N m].",
    )
    _add_robot_arguments(p)
    for name, what in (
        ("q", "joint positions [rad]"),
        ("qd", "joint velocities [rad/s]"),
        ("qd-a", "reference velocity qd_a [rad/s]"),
        ("qdd-a", "reference acceleration qdd_a [rad/s^2]"),
    ):
        p.add_argument(f"--{name}", type=_vector, required=True, help=f"{what}, comma-separated")
    p.add_argument("--method", default=None, help="vertex, hull or rigorous (default: by box kind)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (also used by the ``urpc`` console script)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        handler = globals()[f"_cmd_{args.command.replace('-', '_')}"]
        return handler(args)
    except UrpcError as exc:
        print(f"error: {_one_line(str(exc))}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:  # e.g. `urpc robots | head`
        sys.stderr.close()
        return EXIT_OK
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _print_json(payload: dict) -> None:
    print(json.dumps(_jsonable(payload), indent=2, allow_nan=False))


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return _jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Path):
        return str(value)
    return value


# ============================================================================ commands
def _cmd_robots(args) -> int:
    from .catalog import builtin_robots, example_robot_data_robots

    builtin = builtin_robots()
    erd = example_robot_data_robots()
    if args.json:
        _print_json(
            {
                "builtin": {n: str(e.urdf) for n, e in builtin.items()},
                "example_robot_data": {n: str(e.urdf) for n, e in erd.items()},
            }
        )
        return EXIT_OK
    print("Built-in robots (with their uncertainty and parameter files):")
    for name, entry in builtin.items():
        extras = ", ".join(p.name for p in entry.files)
        print(f"  {name:<24} {extras}")
    print("\nexample-robot-data URDFs (loaded as fixed-base trees; a URDF with a joint type other")
    print("than revolute, continuous, prismatic or fixed is refused with a message naming it):")
    names = list(erd)
    width = max((len(n) for n in names), default=0) + 2
    per_line = max(1, 96 // width)
    for i in range(0, len(names), per_line):
        print("  " + "".join(n.ljust(width) for n in names[i : i + per_line]))
    return EXIT_OK


def _load_robot_and_box(args):
    from .catalog import default_uncertainty
    from .robot import load_robot
    from .uncertainty import ParameterBox, load_uncertainty

    robot = load_robot(args.robot, locked_joints=args.lock)
    path = args.uncertainty or default_uncertainty(args.robot)
    if path is None:
        return robot, ParameterBox(links=()), None
    return robot, load_uncertainty(path, robot), path


def box_summary(robot, box) -> dict:
    """A JSON-friendly description of a parameter box (used by ``urpc check``)."""
    links = []
    for link_box in box.links:
        fields = []
        for k, name in enumerate(link_box.fields):
            lo, hi, nominal = link_box.lower[k], link_box.upper[k], link_box.nominal[k]
            fields.append(
                {
                    "field": name,
                    "nominal": nominal,
                    "lower": lo,
                    "upper": hi,
                    "uncertain": bool(hi > lo),
                    "relative_width": (hi - lo) / abs(nominal) if nominal != 0 else None,
                }
            )
        links.append({"link": link_box.link, "kind": link_box.kind, "fields": fields})
    return {
        "robot": robot.name,
        "urdf": str(robot.urdf_path),
        "dof": robot.dof,
        "joints": list(robot.joint_names),
        "moving_links": list(robot.moving_link_names),
        "uncertainty": box.source,
        "disturbance": "unknown" if box.disturbance_bound is None else box.disturbance_bound,
        "payloads": [{"name": p.name, "link": p.link} for p in box.payloads],
        "uncertain_parameters": box.n_uncertain,
        "links": links,
    }


def _cmd_check(args) -> int:
    robot, box, path = _load_robot_and_box(args)
    summary = box_summary(robot, box)
    if args.json:
        _print_json(summary)
        return EXIT_OK
    print(f"robot       {robot.name} ({robot.dof} dof) from {robot.urdf_path}")
    print(f"joints      {', '.join(robot.joint_names)}")
    print(f"uncertainty {path if path else '(none: every parameter exact)'}")
    dist = summary["disturbance"]
    print(
        f"disturbance {'unknown bound (Theorem 2, adaptive gains)' if dist == 'unknown' else f'||d|| <= {dist} N m (Theorem 1)'}"
    )
    for payload in box.payloads:
        print(f"payload     '{payload.name}' fixed to link '{payload.link}'")
    print(f"uncertain   {box.n_uncertain} parameters in {len(box.uncertain_links)} links\n")
    header = f"  {'field':<8} {'nominal':>12} {'lower':>12} {'upper':>12} {'rel. width':>11}"
    for entry in summary["links"]:
        print(f"link '{entry['link']}' ({entry['kind']} box)")
        print(header)
        for f in entry["fields"]:
            if not f["uncertain"]:
                continue
            rel = "-" if f["relative_width"] is None else f"{100 * f['relative_width']:.1f} %"
            print(
                f"  {f['field']:<8} {f['nominal']:>12.6g} {f['lower']:>12.6g} {f['upper']:>12.6g} "
                f"{rel:>11}"
            )
        exact = [f["field"] for f in entry["fields"] if not f["uncertain"]]
        if exact:
            print(f"  exact: {', '.join(exact)}")
        print()
    return EXIT_OK


def _cmd_bound(args) -> int:
    from .bounds import default_method, make_bound

    robot, box, _ = _load_robot_and_box(args)
    vectors = {"q": args.q, "qd": args.qd, "qd-a": args.qd_a, "qdd-a": args.qdd_a}
    for name, value in vectors.items():
        if value.shape != (robot.dof,):
            raise InputError(
                f"--{name} has {value.size} values but {robot.name} has {robot.dof} joints "
                f"({', '.join(robot.joint_names)})",
                field=name,
            )
    method = args.method or default_method(box)
    bound = make_bound(method, robot, box)
    lower, upper = bound.enclose(args.q, args.qd, args.qd_a, args.qdd_a)
    rho = np.maximum(np.abs(lower), np.abs(upper))
    if args.json:
        _print_json(
            {
                "method": method,
                "joints": list(robot.joint_names),
                "lower": lower,
                "upper": upper,
                "rho": rho,
            }
        )
        return EXIT_OK
    print(f"method {method}; mismatch torque w enclosure [N m]")
    print(f"  {'joint':<24} {'lower':>14} {'upper':>14} {'rho':>14}")
    for name, lo, hi, r in zip(robot.joint_names, lower, upper, rho, strict=True):
        print(f"  {name:<24} {lo:>14.6g} {hi:>14.6g} {r:>14.6g}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
