"""Inspection commands: ``urpc robots``, ``urpc check``, ``urpc bound``."""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from .common import (
    BOUND_METHODS,
    EXIT_OK,
    add_command,
    add_json_argument,
    add_robot_arguments,
    count,
    joint_units,
    print_json,
    robot_argument,
    vector,
)


def register(commands) -> None:
    p = add_command(
        commands, "robots", run_robots, help="list the robots that can be loaded by name"
    )
    add_json_argument(p)

    p = add_command(
        commands,
        "check",
        run_check,
        help="validate a robot and an uncertainty file, print the box",
        description="Load ROBOT, validate the uncertainty file against it, and print the box: "
        "links, parameters, nominal values, bounds and relative widths.",
    )
    add_robot_arguments(p)
    add_json_argument(p)

    p = add_command(
        commands,
        "bound",
        run_bound,
        help="enclose the mismatch torque w at one state",
        description="Enclose the mismatch torque w = Y_SL (pi - pi0) - d over the box at one "
        "state, and print lower, upper and rho = max(|lower|, |upper|) per joint [N m].",
    )
    add_robot_arguments(p)
    for name, what in (
        ("q", "joint positions [rad]"),
        ("qd", "joint velocities [rad/s]"),
        ("qd-a", "reference velocity qd_a [rad/s]"),
        ("qdd-a", "reference acceleration qdd_a [rad/s^2]"),
    ):
        p.add_argument(f"--{name}", type=vector, required=True, help=f"{what}, comma-separated")
    p.add_argument(
        "--method",
        choices=BOUND_METHODS,
        default=None,
        help="bound method (default: by box kind)",
    )
    add_json_argument(p)


def run_robots(args) -> int:
    from ..model.catalog import builtin_robots, example_robot_data_robots, shipped_data

    builtin = builtin_robots()
    erd = example_robot_data_robots()
    known = {**erd, **builtin}
    shipped = {}
    for name in sorted(known):
        data = shipped_data(name)
        if any(data.values()):
            shipped[name] = (known[name], data)
    supported = {n: e for n, e in erd.items() if not e.floating_base}
    floating = {n: e for n, e in erd.items() if e.floating_base}
    needs_lock = _mimic_joints_by_robot({**builtin, **supported})
    if args.json:
        print_json(
            {
                "builtin": {n: str(e.urdf) for n, e in builtin.items()},
                "example_robot_data": {n: str(e.urdf) for n, e in supported.items()},
                "shipped": {
                    name: {
                        "urdf": str(entry.urdf),
                        "origin": entry.origin,
                        "uncertainty": [str(p) for p in data["uncertainty"]],
                        "parameter_points": [f"{name}/{p.stem}" for p in data["parameter_points"]],
                        "scenarios": [f"{name}/{p.stem}" for p in data["scenarios"]],
                    }
                    for name, (entry, data) in shipped.items()
                },
                "not_supported": {
                    n: {"urdf": str(e.urdf), "reason": "floating base"} for n, e in floating.items()
                },
                "needs_lock": needs_lock,
            }
        )
        return EXIT_OK
    print("Robots with a shipped uncertainty box, true plants and scenarios:")
    print(f"  {'name':<11} {'URDF from':<19} {'box':<4} {'true plants':<28} scenarios")
    for name, (entry, data) in shipped.items():
        box = "yes" if data["uncertainty"] else "no"
        points = ", ".join(p.stem for p in data["parameter_points"]) or "-"
        scenarios = ", ".join(f"{name}/{p.stem}" for p in data["scenarios"]) or "-"
        print(f"  {name:<11} {entry.origin:<19} {box:<4} {points:<28} {scenarios}")
    print(
        "  (urpc check NAME; urpc simulate NAME/SCENARIO; the API loads them by name too: "
        "urpc.load_uncertainty(NAME, robot))"
    )
    print(
        "\nFixed-base robots of example-robot-data, without a shipped box ('urpc init NAME --out "
        "box.yaml'\nwrites one; a joint type other than revolute, continuous, prismatic or fixed "
        "is refused):"
    )
    _print_columns([n for n in supported if n not in shipped])
    if needs_lock:
        print(
            "  Mimic joints (urpc does not model them) to lock with --lock, or locked_joints=[...]"
            " in the API:"
        )
        for name, joints in needs_lock.items():
            print(f"    {name:<24} --lock {','.join(joints)}")
    print(
        "\nNot supported: floating-base robots of example-robot-data (legged, humanoid, aerial, "
        "mobile;\nurpc controls fixed-base arms):"
    )
    _print_columns(list(floating))
    return EXIT_OK


def _mimic_joints_by_robot(entries) -> dict[str, list[str]]:
    """For each robot whose URDF has mimic joints, every joint of those pairs (leaders first):
    the ``--lock`` list it needs."""
    from xml.etree.ElementTree import ParseError

    from ..model.urdf import mimic_joints

    out = {}
    for name, entry in entries.items():
        try:
            pairs = mimic_joints(Path(entry.urdf))
        except (OSError, ParseError):  # reported when the robot is loaded
            continue
        if pairs:
            joints = [j for follower, leader in pairs.items() for j in (leader, follower)]
            out[name] = list(dict.fromkeys(joints))
    return out


def _print_columns(names: list[str]) -> None:
    width = max((len(n) for n in names), default=0) + 2
    per_line = max(1, 96 // width)
    for i in range(0, len(names), per_line):
        print("  " + "".join(n.ljust(width) for n in names[i : i + per_line]).rstrip())


def load_robot_and_box(args):
    from ..model.catalog import default_uncertainty
    from ..model.robot import load_robot
    from ..model.uncertainty import ParameterBox, load_uncertainty

    robot = load_robot(robot_argument(args), locked_joints=args.lock)
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
        "drives": _drives(box, dict(zip(robot.joint_names, robot.joint_kinds, strict=True))),
        "urdf_dynamics_joints": [
            name
            for name, column in zip(robot.joint_names, robot.urdf_dynamics.T, strict=True)
            if column.any()
        ],
    }


def _drives(box, kinds: dict[str, str]) -> list[dict]:
    """The joints' drive parameters of a box with a ``joints:`` section (empty: rigid joints);
    ``kinds``: each joint's kind, for the units (a prismatic joint's are kg, N s/m, N)."""
    from ..formats.uncertainty import JOINT_FIELDS  # heavy (pydantic, numba): not at parse time
    from ..model.joint_dynamics import JOINT_UNITS, PRISMATIC_JOINT_UNITS

    def units(joint: str) -> dict[str, str]:
        return PRISMATIC_JOINT_UNITS if kinds.get(joint) == "prismatic" else JOINT_UNITS

    joints = box.joints
    if joints is None:
        return []
    return [
        {
            "joint": joints.joint_names[column],
            "field": JOINT_FIELDS[row],
            "unit": units(joints.joint_names[column])[JOINT_FIELDS[row]],
            "nominal": float(joints.nominal[row, column]),
            "lower": float(joints.lower[row, column]),
            "upper": float(joints.upper[row, column]),
            "uncertain": bool(joints.uncertain[row, column]),
        }
        for column in range(joints.dof)
        for row in range(3)
        if joints.upper[row, column] > 0
    ]


def run_check(args) -> int:
    robot, box, path = load_robot_and_box(args)
    summary = box_summary(robot, box)
    if args.json:
        print_json(summary)
        return EXIT_OK
    print(f"robot        {robot.name} ({count(robot.dof, 'joint')}) from {robot.urdf_path}")
    print(f"joints       {', '.join(robot.joint_names)}")
    print(f"moving links {', '.join(robot.moving_link_names)}")
    if path is None:
        print(
            f"uncertainty  none: there is no shipped box for {args.robot}; write one with "
            f"'urpc init {args.robot} --out box.yaml' and check it with --uncertainty box.yaml"
        )
        return EXIT_OK
    print(f"uncertainty  {path}")
    dist = summary["disturbance"]
    print(
        f"disturbance  {'unknown bound (Theorem 2, adaptive gains)' if dist == 'unknown' else f'||d|| <= {dist} N m (Theorem 1)'}"
    )
    for payload in box.payloads:
        print(f"payload      '{payload.name}' fixed to link '{payload.link}'")
    print(
        f"uncertain    {count(box.n_uncertain, 'parameter')} in "
        f"{count(len(box.uncertain_links), 'link')}\n"
    )
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
    _print_drives(summary)
    return EXIT_OK


def _print_drives(summary: dict) -> None:
    drives = summary["drives"]
    if not drives:
        ignored = summary["urdf_dynamics_joints"]
        note = (
            f"; the URDF's <dynamics> on {', '.join(ignored)} are not used without a joints: "
            "section (docs/joint-dynamics.md)"
            if ignored
            else ""
        )
        print(f"drives       none: rigid joints{note}")
        return
    print("drives (armature, damping, Coulomb friction; docs/joint-dynamics.md)")
    print(f"  {'joint':<22} {'field':<9} {'nominal':>10} {'lower':>10} {'upper':>10}  unit")
    for d in drives:
        exact = "" if d["uncertain"] else "  (exact)"
        print(
            f"  {d['joint']:<22} {d['field']:<9} {d['nominal']:>10.4g} {d['lower']:>10.4g} "
            f"{d['upper']:>10.4g}  {d['unit']}{exact}"
        )


def run_bound(args) -> int:
    import numpy as np

    from ..bounds import default_method, make_bound

    robot, box, _ = load_robot_and_box(args)
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
    if not (np.isfinite(lower).all() and np.isfinite(upper).all()):  # never print NaN or inf
        raise InputError(
            "the enclosure of the mismatch torque overflows double precision at this state; "
            "give a smaller --q, --qd, --qd-a or --qdd-a",
            field="qd",
        )
    if args.json:
        print_json(
            {
                "method": method,
                "joints": list(robot.joint_names),
                "lower": lower,
                "upper": upper,
                "rho": rho,
            }
        )
        return EXIT_OK
    print(f"method {method}; mismatch torque w enclosure (N m per revolute, N per prismatic joint)")
    print(f"  {'joint':<24} {'lower':>14} {'upper':>14} {'rho':>14}  unit")
    rows = zip(robot.joint_names, robot.joint_kinds, lower, upper, rho, strict=True)
    for name, kind, lo, hi, r in rows:
        unit = joint_units([kind])[1]
        print(f"  {name:<24} {lo:>14.6g} {hi:>14.6g} {r:>14.6g}  {unit}")
    return EXIT_OK
