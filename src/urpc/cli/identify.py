"""``urpc identify``: guaranteed parameter intervals from recorded data, and exciting
trajectories (``--excite``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import InputError
from .common import (
    EXIT_OK,
    add_command,
    add_json_argument,
    add_lock_argument,
    add_new_file_arguments,
    add_robot_positional,
    non_negative_float,
    non_negative_int,
    path,
    positive_float,
    positive_int,
    print_json,
)


def register(commands) -> None:
    p = add_command(
        commands,
        "identify",
        run_identify,
        help="identify a sound parameter box from recorded data (or --excite: write an "
        "exciting trajectory)",
        description="From recorded samples (CSV or NPZ with t, q1..qn, tau1..taun and "
        "optionally qd1..qdn, qdd1..qddn), compute the box enclosing every parameter vector of "
        "the prior box whose rigid bodies (and drives) explain every sample within the torque "
        "noise bound, and write it as an uncertainty file (docs/identification.md). With "
        "--excite, write an exciting Fourier trajectory inside the joint limits instead and "
        "report the identifiable parameter combinations.",
        epilog="Examples: urpc identify --excite ur5 --payload tool0 --out traj.csv; "
        "urpc identify ur5 --data run1.csv run2.csv --prior ur5 --torque-noise 0.5 "
        "--payload tool0 --out box.yaml",
    )
    add_robot_positional(p)
    p.add_argument("--excite", action="store_true", help="write an exciting trajectory to --out")
    p.add_argument("--data", nargs="+", type=path, metavar="FILE", help="data files (CSV or NPZ)")
    p.add_argument(
        "--prior",
        metavar="BOX",
        help="prior box: an uncertainty file or a shipped box name (default: the robot's "
        "shipped box); 'urpc init ROBOT --out FILE' writes one",
    )
    p.add_argument(
        "--torque-noise",
        type=noise,
        metavar="N",
        help="bound of |measured - true torque| per sample [N m]: one number, or one per joint "
        "(comma-separated)",
    )
    p.add_argument(
        "--payload",
        metavar="LINK",
        help="payload mode: only the payload fixed to LINK is unknown (the prior's payload: "
        "section); with --excite: excite the parameters of a body fixed to LINK",
    )
    add_new_file_arguments(p)
    add_lock_argument(p)
    p.add_argument(
        "--jerk-bound",
        type=non_negative_float,
        metavar="J",
        help="bound of |q'''| [rad/s^3] when qd, qdd are estimated from q (files without qd)",
    )
    p.add_argument(
        "--snap-bound",
        type=non_negative_float,
        metavar="S",
        help="bound of |q''''| [rad/s^4] when qdd is estimated (files without qdd)",
    )
    p.add_argument(
        "--position-error",
        type=non_negative_float,
        default=0.0,
        metavar="E",
        help="bound of the position measurement error [rad] for estimated derivatives (default 0)",
    )
    p.add_argument(
        "--rounds",
        type=positive_int,
        default=2,
        metavar="N",
        help="rounds of envelope tightening (default 2)",
    )
    p.add_argument(
        "--harmonics", type=positive_int, default=4, metavar="N", help="--excite: harmonics (4)"
    )
    p.add_argument(
        "--frequency",
        type=positive_float,
        default=0.1,
        metavar="HZ",
        help="--excite: base frequency [Hz] (default 0.1: a 10 s period)",
    )
    p.add_argument(
        "--rate",
        type=positive_float,
        default=100.0,
        metavar="HZ",
        help="--excite: sample rate of the written trajectory [Hz] (default 100)",
    )
    p.add_argument(
        "--acceleration-limit",
        type=positive_float,
        default=3.0,
        metavar="A",
        help="--excite: bound of |qdd| [rad/s^2] (default 3)",
    )
    p.add_argument(
        "--seed", type=non_negative_int, default=0, metavar="N", help="--excite: seed (default 0)"
    )
    add_json_argument(p)


def noise(text: str):
    """``"0.5"`` or ``"0.5,0.5,0.2"`` (argparse type): torque noise bounds >= 0 [N m]."""
    parts = [p for p in text.replace(",", " ").split() if p]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number or a list of numbers") from None
    if not values or any(not (v >= 0 and v < float("inf")) for v in values):
        raise argparse.ArgumentTypeError(f"'{text}' must be finite numbers >= 0 [N m]")
    return values


def run_identify(args) -> int:
    from ..model.robot import load_robot
    from .init import check_new_file, write_new_file

    out = check_new_file(args.out, args.force)
    robot = load_robot(args.robot, locked_joints=args.lock)
    if args.excite:
        return _excite(args, robot, out, write_new_file)
    if not args.data:
        raise InputError(
            "give --data FILE [FILE ...] (recorded samples), or --excite to write a trajectory",
            field="data",
        )
    if args.torque_noise is None:
        raise InputError(
            "give --torque-noise N: the bound of |measured - true torque| per sample [N m]; "
            "the box is guaranteed only under this bound",
            field="torque_noise",
        )
    from ..identify.core import identify
    from ..identify.data import DerivativeBounds
    from ..model.catalog import uncertainty_schema
    from ..model.uncertainty import load_uncertainty
    from .init import _schema_reference

    prior_name = args.prior if args.prior is not None else args.robot
    prior = load_uncertainty(prior_name, robot)
    bounds = DerivativeBounds(args.jerk_bound, args.snap_bound, args.position_error)
    result = identify(
        robot,
        prior,
        args.data,
        args.torque_noise,
        payload=args.payload,
        derivative_bounds=bounds,
        rounds=args.rounds,
    )
    schema = uncertainty_schema()
    text = result.box_text(
        robot_source=str(args.robot),
        schema=None if schema is None else _schema_reference(schema, out),
    )
    import yaml

    from ..model.uncertainty import parse_uncertainty

    parse_uncertainty(yaml.safe_load(text), robot, source=str(out))  # what check will read
    write_new_file(out, text, overwrite=args.force)
    summary = {"out": str(out), **result.summary()}
    if args.json:
        print_json(summary)
        return EXIT_OK
    print(
        f"wrote {out}: {len(result.fields)} identified fields from {result.samples} samples in "
        f"{result.seconds:.2f} s ({result.linear_programs} linear programs); regressor rank "
        f"{result.rank} of {result.unknowns} unknowns"
    )
    for group, ratio in result.mean_width_ratios().items():
        print(f"  {group}: mean width {100 * ratio:.3g} % of the prior")
    if result.unconstrained:
        print(
            "  not constrained by the data (prior interval kept): "
            + ", ".join(result.unconstrained)
        )
    if result.nominal_assumed:
        print(
            "warning: payload mode took these at their nominal values (the payload box is sound "
            "only if they are): " + ", ".join(result.nominal_assumed),
            file=sys.stderr,
        )
    print(f"next: urpc check {args.robot} --uncertainty {out}")
    return EXIT_OK


#: An exciting trajectory is written with at least this many samples per period of its highest
#: harmonic (a trajectory file is read back as a spline through them).
EXCITE_SAMPLES_PER_PERIOD = 10
#: At most this many samples are written (about 0.4 GB of CSV for a 7-dof arm).
EXCITE_MAX_SAMPLES = 1_000_000


def _excite(args, robot, out: Path, write_new_file) -> int:
    import numpy as np

    from ..errors import InputError
    from ..identify.data import write_csv
    from ..identify.excitation import excite

    if out.suffix.lower() != ".csv":
        raise InputError(
            f"{out.name}: an exciting trajectory is written as CSV, which a scenario's "
            "'trajectory: {kind: file}' reads by its suffix; give a name ending in .csv",
            field="--out",
        )
    highest = args.harmonics * args.frequency  # [Hz]
    if args.rate < EXCITE_SAMPLES_PER_PERIOD * highest:
        raise InputError(
            f"{args.rate:g} Hz gives fewer than {EXCITE_SAMPLES_PER_PERIOD} samples per period of "
            f"the highest harmonic ({args.harmonics} x {args.frequency:g} Hz = {highest:g} Hz): "
            f"give --rate {EXCITE_SAMPLES_PER_PERIOD * highest:g} or more, or a lower --frequency",
            field="--rate",
        )
    samples = round(args.rate / args.frequency)  # one period
    if samples > EXCITE_MAX_SAMPLES:
        raise InputError(
            f"{args.rate:g} Hz over a period of {1 / args.frequency:g} s is {samples:.3g} samples; "
            f"at most {EXCITE_MAX_SAMPLES:.0e} are written: give a lower --rate or a higher "
            "--frequency",
            field="--rate",
        )

    result = excite(
        robot,
        payload=args.payload,
        harmonics=args.harmonics,
        frequency=args.frequency,
        acceleration_limit=args.acceleration_limit,
        seed=args.seed,
    )
    trajectory = result.trajectory
    period = 1.0 / args.frequency
    t = np.arange(int(round(period * args.rate)) + 1) / args.rate
    q, qd, qdd = trajectory.evaluate(t)
    columns = {"t": t}
    for prefix, values in (("q", q), ("qd", qd), ("qdd", qdd)):
        for i in range(robot.dof):
            columns[f"{prefix}{i + 1}"] = values[:, i]
    jerk, snap = float(np.max(result.jerk)), float(np.max(result.snap))
    comments = [
        f"Exciting trajectory for {robot.name} written by urpc identify --excite: a Fourier "
        f"series of {args.harmonics} harmonics, period {period:g} s, joints "
        + ", ".join(robot.joint_names),
        f"inside the position limits, |qd| <= half the velocity limits, |qdd| <= "
        f"{args.acceleration_limit:g} rad/s^2; |q'''| <= {jerk:.6g}, |q''''| <= {snap:.6g}",
        "(--jerk-bound/--snap-bound for derivatives estimated from q). Record tau1..taun "
        "along it and run urpc identify.",
    ]
    write_new_file(out, write_csv(out, columns, comments), overwrite=args.force)
    summary = {
        "out": str(out),
        "robot": robot.name,
        "samples": int(t.size),
        "period": period,
        "condition": result.condition,
        "rank": result.rank,
        "columns": len(result.columns),
        "base": result.base,
        "combinations": result.combinations,
        "jerk_bound": result.jerk.tolist(),
        "snap_bound": result.snap.tolist(),
        "coefficients": {
            "home": trajectory.home.tolist(),
            "a": trajectory.a.tolist(),
            "b": trajectory.b.tolist(),
            "frequency": trajectory.frequency,
        },
    }
    if args.json:
        print_json(summary)
        return EXIT_OK
    print(
        f"wrote {out}: {t.size} samples over {period:g} s; stacked regressor condition number "
        f"{result.condition:.3g} (column-normalized, base columns)"
    )
    print(
        f"  identifiable combinations: rank {result.rank} of {len(result.columns)} parameters"
        + ("" if args.payload is None else f" (payload at {args.payload})")
    )
    for line in result.combinations[:12]:
        print(f"    {line}")
    if len(result.combinations) > 12:
        print(f"    ... {len(result.combinations) - 12} more (--json lists them all)")
    print(f"  derivative bounds: --jerk-bound {jerk:.6g} --snap-bound {snap:.6g}")
    return EXIT_OK
