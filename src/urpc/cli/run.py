"""``urpc run``: a scenario's controller on a robot over UDP (the virtual robot, or any robot
speaking the packet format of docs/robot.md), behind the safety layer and the watchdog."""

from __future__ import annotations

import sys

from ..names import SAFE_MODES, SAMPLED_LAWS
from .common import (
    EXIT_OK,
    add_command,
    add_json_argument,
    json_text,
    non_negative_int,
    path,
    positive_float,
)

#: Exit code of a run stopped by a fault or the watchdog.
EXIT_STOPPED = 1


def register(commands) -> None:
    p = add_command(
        commands,
        "run",
        run_robot,
        help="run a scenario's controller on a robot over UDP (e.g. urpc virtual-robot)",
        description="Synthesize the scenario's interval controller (or load --controller FILE), "
        "connect to the robot at --robot-address and track the scenario's trajectory in real "
        "time, behind the safety layer (torque limits from the URDF's efforts unless the "
        "scenario sets torque_limit, optional torque-rate limit, position and velocity limits "
        "with a margin) and the watchdog (late cycles, a silent robot). When the arm starts "
        "away from the trajectory, a rest-to-rest approach is put in front. The scenario's true "
        "plant and disturbance are the robot's business, not the run's.",
        epilog="Prints whether epsilon was met, the final error, deadline misses, lost samples, "
        "safety interventions and step-time percentiles; --json prints one object. Exit code 0 "
        "when the run completed, 1 when a fault or the watchdog stopped it (one error: line), "
        "2 on bad input.",
    )
    p.add_argument(
        "scenario",
        metavar="SCENARIO",
        help="scenario YAML file or shipped name (rr_planar/s3_ic1 ...)",
    )
    p.add_argument(
        "--robot-address", required=True, metavar="URL", help="udp://127.0.0.1:PORT (loopback only)"
    )
    p.add_argument(
        "--duration",
        type=positive_float,
        metavar="S",
        help="run time after the approach [s] (default: the scenario's)",
    )
    p.add_argument(
        "--controller",
        metavar="FILE",
        type=path,
        help="a controller saved with controller.save() (default: synthesize)",
    )
    p.add_argument(
        "--save-controller",
        metavar="FILE",
        type=path,
        help="also save the controller to FILE, once the robot answers (not overwritten "
        "without --force)",
    )
    p.add_argument(
        "--force", action="store_true", help="overwrite the --save-controller FILE if it exists"
    )
    p.add_argument(
        "--delay",
        type=int,
        choices=(0, 1),
        help="samples of actuation delay the law predicts over (default: the scenario's)",
    )
    p.add_argument(
        "--sampled-law",
        choices=SAMPLED_LAWS,
        help="law of the interval controller (default: the scenario's)",
    )
    p.add_argument(
        "--velocity-filter",
        type=positive_float,
        metavar="HZ",
        help="first-order low-pass on the measured velocity before the law, cutoff [Hz] "
        "(default: none; its lag is outside the certificate, docs/robot.md)",
    )
    p.add_argument(
        "--safe-mode",
        choices=SAFE_MODES,
        default="damping",
        help="safe command on a fault (damping)",
    )
    p.add_argument(
        "--torque-rate",
        type=positive_float,
        metavar="R",
        help="torque-rate limit [N m/s] (default: none)",
    )
    p.add_argument(
        "--late-budget",
        type=non_negative_int,
        default=5,
        metavar="N",
        help="consecutive late cycles tolerated (5); does not lengthen --silence-ms",
    )
    p.add_argument(
        "--silence-ms",
        type=positive_float,
        metavar="MS",
        help="stop when no fresh state (one with a newer sequence number) arrives for MS [ms] "
        "(50, at least 5 periods; at least 2 periods when given). The run also stops when it "
        "takes longer than its duration plus max(1 s, a quarter of it)",
    )
    p.add_argument(
        "--deadline-ms",
        type=positive_float,
        metavar="MS",
        help="state-to-torque deadline [ms] (half a period)",
    )
    p.add_argument(
        "--out",
        type=path,
        metavar="DIR",
        help="save result.npz, result.csv, summary.json, run.json",
    )
    add_json_argument(p, on_stdout=True)


def _shown(value) -> str:
    """A number or a list of numbers as it reads in a scenario file (``[30, 20]``, ``1e+06``)."""
    import numpy as np

    if isinstance(value, str):
        return value
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return f"{float(array):g}"
    rows = [", ".join(f"{v:g}" for v in row) for row in np.atleast_2d(array)]
    return "[" + ", ".join(rows) + "]" if array.ndim == 1 else "[[" + "], [".join(rows) + "]]"


def _check_saved_against_scenario(controller, scenario, box, path, *, law_given: bool) -> None:
    """Refuse a saved controller whose epsilon, sample period, gains or box are not the
    scenario's.

    The loop judges ``met`` against the scenario's epsilon and runs at the controller's period,
    and the controller's guarantee is for its own box and gains: a scenario edited after the
    controller was saved would otherwise be run and judged with numbers that are not the ones it
    states. Gains and law are compared where the scenario states them (its
    ``controller_options.interval``); ``law_given``: ``--sampled-law`` was checked already.
    """
    import dataclasses

    import numpy as np

    from ..control.certificate_key import canonical
    from ..control.synthesis import gain_diagonal
    from ..errors import InputError

    where = scenario.source or scenario.name
    redo = "synthesize the controller again (drop --controller, add --save-controller)"
    for name, saved, wanted in (
        ("epsilon", controller.epsilon, scenario.epsilon),
        ("sample_period", controller.sample_period, scenario.sample_period),
    ):
        if float(saved) != float(wanted):
            raise InputError(
                f"the saved controller was synthesized for {name} = {saved:g}, but {where} "
                f"asks for {name} = {wanted:g}; set {name}: {saved:g} in the scenario, or {redo}",
                path,
                name,
            )
    # What the scenario states (its own entries, not the synthesis defaults filled in).
    stated = scenario.controller_options.by_controller()["interval"]
    saved_values = {
        "kappa_P": controller.kappa_P,
        "kappa_I": controller.kappa_I,
        "phi_P": controller.phi_P,
        "phi_I": controller.phi_I,
        "Kr": np.asarray(controller.Kr, dtype=float),
        "method": controller.bound.name,
        "sampled_law": getattr(controller, "sampled_law", None),
    }
    for name, saved in saved_values.items():
        wanted = stated.get(name)
        if wanted is None or (name == "sampled_law" and law_given):
            continue
        if name == "Kr":  # a scalar, a vector or a diagonal matrix, as synthesize reads it
            try:
                same = np.array_equal(gain_diagonal(wanted, controller.epsilon, saved.size), saved)
            except InputError:  # not a gain synthesize takes: not the saved one either
                same = False
        else:
            same = saved == wanted
        if not same:
            raise InputError(
                f"the saved controller has {name} = {_shown(saved)}, but {where} states {name}: "
                f"{_shown(wanted)} (controller_options.interval); make the two agree, or {redo}",
                path,
                name,
            )
    saved_box = controller.bound.box

    def form(b):
        return canonical(dataclasses.replace(b, source=None))

    if form(saved_box) == form(box):
        return
    saved_links = {link.link: canonical(link) for link in saved_box.links}
    wanted_links = {link.link: canonical(link) for link in box.links}
    differ = sorted(
        name
        for name in set(saved_links) | set(wanted_links)
        if saved_links.get(name) != wanted_links.get(name)
    )
    parts = []
    if differ:
        parts.append("the intervals of " + ", ".join(differ))
    if canonical(saved_box.payloads) != canonical(box.payloads):
        parts.append("the payloads")
    if canonical(saved_box.joints) != canonical(box.joints):
        parts.append("the joint drives")
    if canonical(saved_box.disturbance_bound) != canonical(box.disturbance_bound):
        parts.append(
            f"the disturbance bound ({saved_box.disturbance_bound} saved, "
            f"{box.disturbance_bound} in the scenario)"
        )
    raise InputError(
        "the saved controller's box is not the scenario's uncertainty box ("
        + ("; ".join(parts) or "its values")
        + f" differ); its guarantee holds for the box it was synthesized for, so run {where} "
        "with that box, or synthesize the controller again (drop --controller)",
        path,
        "box",
    )


def run_robot(args) -> int:
    import numpy as np

    from ..atomic import check_writable, write_files
    from ..control.controller_file import check_controller_path, load_controller, save_controller
    from ..control.synthesis import synthesize
    from ..errors import InputError
    from ..robot.loop import ControlLoop
    from ..robot.runner import run
    from ..robot.safety import SafetyLayer
    from ..robot.udp import UdpRobot, parse_address
    from ..robot.watchdog import Watchdog
    from ..studies.scenario import build, load_scenario
    from ..studies.scenario.run import interval_synthesis_options
    from ..trajectory_moves import Approach, segment_durations

    address = parse_address(args.robot_address)
    out = None if args.out is None else check_writable(args.out)
    save_label = (
        None if args.save_controller is None else f"--save-controller {args.save_controller}"
    )
    if args.save_controller is not None:
        check_controller_path(args.save_controller, overwrite=args.force, label=save_label)
    scenario = load_scenario(args.scenario)
    if args.duration is not None:
        scenario = scenario.with_overrides(duration=args.duration)
    if scenario.sample_period is None:
        raise InputError(
            "a robot runs sampled; the scenario is continuous-time",
            scenario.source,
            "sample_period",
        )
    setup = build(scenario)
    if args.controller is not None:
        controller = load_controller(args.controller)
        if controller.robot.dof != setup.robot.dof or tuple(controller.robot.joint_names) != tuple(
            setup.robot.joint_names
        ):
            raise InputError(
                f"the controller is for {_arm(controller.robot)}, but the scenario runs "
                f"{_arm(setup.robot)}; save a controller for the scenario's robot and locked "
                "joints",
                args.controller,
                "robot",
            )
        # a saved law's delay is fixed: a different one asked for (--delay, or the scenario's
        # controller_options.interval.delay) would otherwise be dropped without a word
        wanted = (
            interval_synthesis_options(scenario).get("delay") if args.delay is None else args.delay
        )
        if wanted is not None and wanted != controller.delay:
            raise InputError(
                f"the saved controller predicts over {controller.delay} sample(s) of delay, not "
                f"the {wanted} asked for (--delay or controller_options.interval.delay); "
                f"synthesize it again with delay {wanted}, or ask for {controller.delay}",
                args.controller,
                "delay",
            )
        law = getattr(controller, "sampled_law", None)
        if args.sampled_law is not None and args.sampled_law != law:
            raise InputError(
                f"the saved controller runs the {law} law, not the {args.sampled_law} one asked "
                f"for (--sampled-law); synthesize it again with that law, or drop --sampled-law",
                args.controller,
                "sampled_law",
            )
        _check_saved_against_scenario(
            controller, scenario, setup.box, args.controller, law_given=args.sampled_law is not None
        )
    else:
        options = interval_synthesis_options(scenario)
        if args.delay is not None:
            options["delay"] = args.delay
        if args.sampled_law is not None:
            options["sampled_law"] = args.sampled_law
        controller = synthesize(setup.robot, setup.box, scenario.epsilon, **options)
    declared = scenario.actuation_delay  # the robot's own delay, as the scenario states it
    if declared is not None and declared != controller.delay:
        print(
            f"run: warning: {scenario.source or 'the scenario'} says the robot applies each "
            f"torque {declared} sample(s) late (actuation_delay), but the law predicts over "
            f"{controller.delay}; give --delay {declared} (or controller_options.interval.delay)",
            file=sys.stderr,
            flush=True,
        )
    period = controller.sample_period
    safety = SafetyLayer.for_robot(
        setup.robot,
        period,
        torque_limit=setup.torque_limit,
        torque_rate_limit=args.torque_rate,
        safe_mode=args.safe_mode,
    )
    if args.silence_ms is not None and args.silence_ms * 1e-3 < 2 * period:
        raise InputError(
            f"{args.silence_ms:g} ms is less than two of the controller's periods "
            f"({2e3 * period:g} ms): the watchdog would trip between two states; give at least "
            f"{2e3 * period:g}",
            field="silence-ms",
        )
    watchdog = Watchdog(
        period,
        late_budget=args.late_budget,
        deadline=None if args.deadline_ms is None else args.deadline_ms * 1e-3,
        silence=None if args.silence_ms is None else args.silence_ms * 1e-3,
    )
    robot = UdpRobot(f"udp://{address[0]}:{address[1]}", setup.robot.dof, period)
    first = robot.read_state(5.0)
    if first is None:
        robot.stop()
        if robot.last_refusal is not None:  # it answers, with datagrams this loop cannot use
            raise InputError(
                _refusal(robot.last_refusal, args.robot_address, setup.robot, scenario),
                field="robot-address",
            )
        raise InputError(
            f"no state from the robot at {args.robot_address} within 5 s; start it first "
            "(urpc virtual-robot ROBOT --port P)",
            field="robot-address",
        )
    try:  # the robot answers: anything refused from here on stops it before the error line
        if args.save_controller is not None:  # every input checked: save
            save_controller(
                controller, args.save_controller, overwrite=args.force, label=save_label
            )
        trajectory, approach = setup.trajectory, 0.0
        start = trajectory.reference(0.0).q
        distance = float(np.linalg.norm(first.q - start))
        if distance > scenario.epsilon:
            limit = safety.velocity_limit
            velocity = np.where(np.isfinite(limit), 0.25 * limit, 1.0)
            approach = float(segment_durations(np.stack([first.q, start]), velocity, 2.0, 1.0)[0])
            trajectory = Approach(first.q, trajectory, approach)
        loop = ControlLoop(
            controller, trajectory, epsilon=scenario.epsilon,
            velocity_filter_hz=args.velocity_filter,
        )  # fmt: skip
        for _ in range(3):  # first calls load compiled kernels and fill caches: not in the run
            loop.step(0.0, first.q, first.qd)
        loop.reset()
    except BaseException:
        robot.stop()
        raise
    print(
        f"run: connected to {args.robot_address}; running {scenario.duration + approach:g} s",
        file=sys.stderr,
        flush=True,
    )
    report = run(robot, loop, safety, watchdog, scenario.duration + approach, first=first)
    summary = {
        "scenario": scenario.name,
        "robot_address": args.robot_address,
        "ending": report.ending,
        "message": report.message,
        "approach_s": approach,
        "delay": int(controller.delay),
        "actuation_delay": declared,
        "velocity_filter_hz": args.velocity_filter,
        "cycles": report.cycles,
        "deadline_misses": report.watchdog["late_cycles"],
        "deadline_miss_rate": report.watchdog["late_fraction"],
        "lost_samples": report.watchdog["lost_samples"],
        "stale_states": report.watchdog["stale_states"],
        "worst_response_ms": report.watchdog["worst_response_s"] * 1e3,
        "safety_interventions": report.safety["total"],
        "interventions": report.safety["counts"],
        "torque_limit": report.safety["torque_limit"],
        "step_time": loop.step_time_percentiles() if loop.samples else {},
        "packets": robot.counters(),
    }
    result = None
    if loop.samples > 1:
        result = loop.result(
            scenario=scenario.name,
            plant=f"robot at {args.robot_address}",
            torque_limit=safety.torque_limit,
            wall_time=report.wall_time,
            info={"run": report.to_dict(), "approach_s": approach},
        )
        metrics = result.metrics
        # A run cut short is not judged: "met" needs the whole run.
        summary.update(
            met=bool(metrics["met"]) and report.ok,
            final_error=metrics["final_error"],
            epsilon=scenario.epsilon,
        )
    if out is not None and result is not None:
        writers = result.writers()
        writers["run.json"] = lambda path: path.write_text(
            json_text({**summary, "events": report.events}) + "\n"
        )
        write_files(out, writers)
    if args.json:
        print(json_text(summary))
    else:
        _print_summary(summary)
    if not report.ok:
        print(f"error: run stopped: {report.message}", file=sys.stderr)
        return EXIT_STOPPED
    return EXIT_OK


def _refusal(refusal, address: str, robot, scenario) -> str:
    """Why the robot's first answer is refused, and what to change: the joints (the scenario's
    locked_joints, or the robot's own lock), the protocol version, or the address."""
    arm = f"{robot.dof} joint{'s' if robot.dof != 1 else ''} ({', '.join(robot.joint_names)})"
    where = scenario.source or f"the scenario {scenario.name}"
    if refusal.kind == "joints":
        return (
            f"the robot at {address} sends states for {refusal.joints} joints; the scenario's "
            f"robot has {arm}: lock joints in {where} (locked_joints, docs/scenarios.md) or on "
            "the robot (urpc virtual-robot ... --lock) so that the loop and the robot drive the "
            "same arm"
        )
    if refusal.kind == "version":
        from ..robot.packet import VERSION

        return (
            f"the robot at {address} speaks packet version {refusal.version}; this urpc speaks "
            f"version {VERSION} (docs/robot.md, Packets): run the robot and urpc run from the "
            "same urpc release, or update the robot's adapter"
        )
    return (
        f"the robot at {address} answers with datagrams that are not urpc state packets for "
        f"{arm} ({refusal}): check that --robot-address is the port of a urpc robot (urpc "
        "virtual-robot, or an adapter sending the state packets of docs/robot.md)"
    )


def _arm(robot) -> str:
    """``rr_planar with 1 joint (joint2; locked: joint1)``: a robot and its locked joints."""
    dof = robot.dof
    locked = ", ".join(robot.locked_joints) or "none"
    joints = ", ".join(robot.joint_names)
    return f"{robot.name} with {dof} joint{'s' if dof != 1 else ''} ({joints}; locked: {locked})"


def _print_summary(s: dict) -> None:
    lines = [f"{s['scenario']} on {s['robot_address']}: {s['ending']}"]
    if "met" in s:
        verdict = (
            ("yes" if s["met"] else "NO")
            if s["ending"] == "completed"
            else "not judged (the run stopped early)"
        )
        lines.append(
            f"  met          {verdict}: final error {s['final_error']:.4g} rad "
            f"(epsilon {s['epsilon']:g})"
        )
    if s["approach_s"]:
        lines.append(
            f"  approach     {s['approach_s']:.2f} s from the arm's start to the trajectory's"
        )
    lines.append(
        f"  deadlines    {s['deadline_misses']} missed of {s['cycles']} cycles "
        f"({100 * s['deadline_miss_rate']:.3g} %), worst response {s['worst_response_ms']:.3g} ms, "
        f"{s['lost_samples']} samples lost"
    )
    counts = ", ".join(f"{k} {v}" for k, v in s["interventions"].items() if v) or "none"
    lines.append(f"  safety       {s['safety_interventions']} interventions ({counts})")
    if s["step_time"]:
        st = s["step_time"]
        lines.append(
            f"  step time    p50 {st['p50'] * 1e6:.0f} us, p99 {st['p99'] * 1e6:.0f} us, "
            f"p99.9 {st['p99_9'] * 1e6:.0f} us, max {st['max'] * 1e6:.0f} us"
        )
    print("\n".join(lines))
