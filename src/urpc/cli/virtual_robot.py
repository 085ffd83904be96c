"""``urpc virtual-robot``: a plant that behaves like a torque-controlled arm, over UDP on
127.0.0.1 (:mod:`urpc.robot.virtual_server`)."""

from __future__ import annotations

from ..names import PLANT_BACKENDS, VELOCITY_MODES
from .common import (
    EXIT_OK,
    add_command,
    add_lock_argument,
    add_robot_positional,
    add_uncertainty_option,
    non_negative_float,
    non_negative_int,
    positive_float,
    vector,
)


def _port(text: str) -> int:
    import argparse

    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a port number") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"'{text}' is not a port; valid: 0-65535 (0: any free)")
    return port


def _sequence_number(text: str) -> int:
    import argparse

    value = non_negative_int(text)
    if not value < 2**32:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a 32-bit sequence number; valid: 0-{2**32 - 1}"
        )
    return value


def _fraction(text: str) -> float:
    import argparse

    value = non_negative_float(text)
    if not value < 1:
        raise argparse.ArgumentTypeError(f"'{text}' must be in [0, 1)")
    return value


#: The shortest robot period [s] the wall-clock virtual robot accepts (10 kHz).
MIN_PERIOD = 1e-4


def register(commands) -> None:
    p = add_command(
        commands,
        "virtual-robot",
        run_virtual_robot,
        help="run a plant as a torque-controlled arm over UDP on 127.0.0.1 (for urpc run)",
        description="Run the true plant of ROBOT (Pinocchio or MuJoCo) in wall-clock time at the "
        "robot's rate, streaming its state to a controller over UDP on 127.0.0.1 and applying the "
        "torques it sends back (packet format: docs/robot.md). Until the first torque the arm is "
        "held (brakes on); afterwards its own watchdog brakes it when no torque arrives for "
        "--watchdog-ms. A torque with a non-finite entry is dropped and counted as malformed; one "
        "beyond the URDF's effort limits is clipped to them. Prints a ready line, then what it did: why it stopped, packets, late "
        "cycles.",
        epilog="Stops when braked (watchdog or the controller's STOP), after --max-duration, or "
        "when no controller registers within --wait. Exit code 0; 2 on bad input.",
    )
    add_robot_positional(p)
    add_uncertainty_option(p)
    p.add_argument(
        "--true-params",
        metavar="FILE",
        help="true parameter point file, 'nominal', or 'sample' (seeded draw from the box); "
        "default: the robot's shipped true_parameters.yaml, else nominal",
    )
    add_lock_argument(p)
    p.add_argument("--port", type=_port, required=True, metavar="P", help="UDP port on 127.0.0.1")
    p.add_argument(
        "--period", type=positive_float, default=1e-3, metavar="S", help="robot period [s] (1e-3)"
    )
    p.add_argument(
        "--delay", type=int, choices=(0, 1), default=0, help="samples of actuation delay (0)"
    )
    p.add_argument(
        "--encoder-resolution",
        type=non_negative_float,
        default=0.0,
        metavar="R",
        help="position quantum [rad] (0: none)",
    )
    p.add_argument(
        "--noise",
        type=non_negative_float,
        default=0.0,
        metavar="S",
        help="position noise std [rad] (0)",
    )
    p.add_argument(
        "--velocity",
        choices=VELOCITY_MODES,
        default="measured",
        help="velocity sent: the plant's (measured), or the backward difference of the sent positions",
    )
    p.add_argument(
        "--loss",
        type=_fraction,
        default=0.0,
        metavar="P",
        help="probability a datagram is lost, each way (0)",
    )
    p.add_argument(
        "--disturbance",
        type=non_negative_float,
        default=0.0,
        metavar="D",
        help="input disturbance ||d|| <= D [N m], drawn per period (0)",
    )
    p.add_argument(
        "--seed",
        type=non_negative_int,
        default=0,
        metavar="N",
        help="seed of noise, loss, disturbance, a sampled plant",
    )
    p.add_argument(
        "--q0", type=vector, metavar="Q", help="initial joint positions [rad] (default: zeros)"
    )
    p.add_argument(
        "--watchdog-ms",
        type=positive_float,
        default=20.0,
        metavar="MS",
        help="brake after this long without torque [ms] (20)",
    )
    p.add_argument(
        "--max-duration",
        type=positive_float,
        default=600.0,
        metavar="S",
        help="stop after this much robot time [s] (600)",
    )
    p.add_argument(
        "--wait",
        type=positive_float,
        default=60.0,
        metavar="S",
        help="stop if no controller registers within S [s] (60)",
    )
    p.add_argument(
        "--first-seq",
        type=_sequence_number,
        default=0,
        metavar="N",
        help="sequence number of the first state (0); e.g. 4294967000 to cross the 32-bit wrap "
        "(2**32 - 1, then 0) within the first second at 1 kHz",
    )
    p.add_argument(
        "--plant",
        choices=PLANT_BACKENDS,
        default="pinocchio",
        help="plant backend (pinocchio)",
    )


def run_virtual_robot(args) -> int:
    import numpy as np

    from ..errors import InputError
    from ..model.catalog import default_uncertainty
    from ..model.robot import load_robot
    from ..model.uncertainty import load_parameter_point, load_uncertainty
    from ..robot.virtual import ArmOptions, VirtualArm
    from ..robot.virtual_server import say, serve
    from ..studies.scenario.setup import sample_true_parameters

    robot = load_robot(args.robot, args.lock)
    uncertainty = args.uncertainty
    if uncertainty is None:
        shipped = default_uncertainty(args.robot)
        if shipped is None:
            raise InputError(
                f"robot '{args.robot}' has no shipped uncertainty box; give -u FILE",
                field="uncertainty",
            )
        uncertainty = str(shipped)
    box = load_uncertainty(uncertainty, robot)
    true = args.true_params
    if true is None:
        try:
            point, what = load_parameter_point(args.robot, robot, box), "shipped true parameters"
        except InputError:
            point, what = {}, "nominal parameters"
    elif true == "nominal":
        point, what = {}, "nominal parameters"
    elif true == "sample":
        point, what = (
            sample_true_parameters(box, args.seed),
            f"parameters drawn from the box (seed {args.seed})",
        )
    else:
        try:
            point, what = load_parameter_point(true, robot, box), f"parameters from {true}"
        except InputError as exc:
            raise InputError(f"{exc}; or 'sample' or 'nominal'", field="true-params") from None
    plant = box.plant(robot, point)
    if args.q0 is not None and len(args.q0) != robot.dof:
        raise InputError(f"{len(args.q0)} values; the robot has {robot.dof} joints", field="q0")
    if args.q0 is not None:
        lower, upper = robot.position_limits
        q0 = np.asarray(args.q0, dtype=float)
        outside = np.flatnonzero((q0 < lower) | (q0 > upper))
        if len(outside):
            j = int(outside[0])
            raise InputError(
                f"joint {robot.joint_names[j]} starts at {q0[j]:g}, outside its limits "
                f"[{lower[j]:g}, {upper[j]:g}] (the URDF's)",
                field="q0",
            )
    if args.period < MIN_PERIOD:
        raise InputError(
            f"{args.period:g} s is faster than a wall-clock robot process can keep; give at "
            f"least {MIN_PERIOD:g} s (10 kHz)",
            field="period",
        )
    if args.watchdog_ms * 1e-3 < 2 * args.period:
        raise InputError(
            f"{args.watchdog_ms:g} ms is less than two periods ({2e3 * args.period:g} ms): the "
            "arm would brake between two torques; give at least two periods",
            field="watchdog-ms",
        )
    options = ArmOptions(
        delay=args.delay,
        encoder_resolution=args.encoder_resolution,
        noise=args.noise,
        velocity=args.velocity,
        loss=args.loss,
        disturbance=args.disturbance,
        seed=args.seed,
        watchdog_timeout=args.watchdog_ms * 1e-3,
    )
    arm = VirtualArm(
        plant, args.period, options, q0=args.q0, backend=args.plant, first_seq=args.first_seq
    )

    def ready(port: int) -> None:
        say(
            f"virtual-robot: ready on udp://127.0.0.1:{port} ({robot.name}, {robot.dof} joints, "
            f"{1 / args.period:g} Hz, delay {args.delay}, watchdog {args.watchdog_ms:g} ms, {what})"
        )

    report = serve(
        arm, args.port, max_duration=args.max_duration, wait_for_client=args.wait, ready=ready
    )
    for line in report.lines():
        say(f"virtual-robot: {line.strip()}")
    return EXIT_OK
