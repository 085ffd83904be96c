"""Simulation commands: ``urpc simulate`` and ``urpc reproduce-paper``."""

from __future__ import annotations

from pathlib import Path

from ..control import SAMPLED_LAWS
from ..errors import InputError
from ..names import DISTURBANCE_MODELS
from ..validation import check_run_length
from .common import (
    BOUND_METHODS,
    CONTROLLERS,
    EXIT_OK,
    LOCK_HELP,
    RESULTS_ROOT,
    ROBOT_HELP,
    add_certificate_arguments,
    add_command,
    add_output_arguments,
    add_scenario_argument,
    add_uncertainty_option,
    certificate_progress,
    count,
    joint_units,
    json_text,
    names,
    non_negative_int,
    output_folder,
    positive_float,
    positive_int,
    print_json,
    scenario_or_robot,
    show_progress,
    warn_uncertified,
    write_error,
)

#: Help of ``--replay`` (simulate and the demos).
REPLAY_HELP = (
    "also write DIR/replay.html: a 3D replay of the run (the arm moving, the desired "
    "end-effector path, play/pause and a time slider) in one file that opens offline in a "
    "browser (docs/replay.md)"
)
#: Default output folder of ``urpc reproduce-paper``.
PAPER_OUT = RESULTS_ROOT / "paper"


def register(commands) -> None:
    p = add_command(
        commands,
        "simulate",
        run_simulate,
        help="synthesize a controller and simulate it against a true plant",
        description="Simulate one run, from a scenario file (a path or a shipped name such as "
        "rr_planar/s2_ic1; see docs/scenarios.md) or straight from a robot and an uncertainty "
        "file (--robot). Flags override the scenario file's values. Without a file the run "
        "tracks a generic sinusoid inside the joint limits, the true plant is a seeded, "
        "physically consistent draw from the box (printed), epsilon is 1e-2 rad, the control "
        "period 1e-3 s, no disturbance, 10 s.",
        epilog="Computes the certificate of the configuration first (urpc certify), once: later "
        "runs of the same configuration read it from the certificate cache. Prints whether "
        "||e|| < epsilon was met, the final error (max ||e|| over the last "
        "second, or the last quarter of a run shorter than 4 s), the torque cost and the gains; "
        "--json prints them as one object; --out DIR (checked before the run) saves result.npz, "
        "result.csv, summary.json, certificate.json, scenario.yaml and the figures "
        "trajectory.png, error.png, torque.png and gains.png; --replay adds replay.html.",
    )
    add_scenario_arguments(p)
    add_certificate_arguments(p.add_argument_group("certificate"))
    output = p.add_argument_group("output")
    add_output_arguments(output, None)
    output.add_argument("--replay", action="store_true", help=REPLAY_HELP)

    p = add_command(
        commands,
        "reproduce-paper",
        run_reproduce_paper,
        help="run the paper's six scenarios with both controllers; figures and a results table",
        description="Reproduce Giusti & Althoff Sec. IV: scenarios 1-3 of Table II with the "
        "initial conditions IC1 and IC2, each with the interval controller and r-alpha (12 "
        "runs, in parallel processes). Writes results.md, results.json, the figures of the "
        "paper's Figs. 1-5 and each run's result.npz and summary.json.",
    )
    p.add_argument(
        "--duration",
        type=positive_float,
        metavar="S",
        help="simulated time of each run [s] (default: the scenario files' 10 s)",
    )
    p.add_argument(
        "--workers",
        type=positive_int,
        default=2,
        metavar="N",
        help="parallel processes (default: 2)",
    )
    add_output_arguments(p, str(PAPER_OUT), what="report, figures and runs")


def add_scenario_arguments(p, simulate: bool = True) -> None:
    """The scenario and its overrides, shared by ``simulate`` and ``certify``; ``simulate=False``
    leaves out what only a run needs (true plant, controller, plant backend, seed, torque limit)."""
    add_scenario_argument(p)
    source = p.add_argument_group("robot and knowledge (replace or stand in for a scenario file)")
    source.add_argument("--robot", metavar="ROBOT", help=ROBOT_HELP)
    source.add_argument("--lock", type=names, metavar="JOINTS", help=LOCK_HELP + " (at 0)")
    add_uncertainty_option(source)
    run = p.add_argument_group("run settings")
    run.add_argument(
        "--method", choices=BOUND_METHODS, help="bound method of the interval controller"
    )
    run.add_argument(
        "--sampled-law",
        choices=SAMPLED_LAWS,
        help="law of a sampled interval controller: implicit (default, certified by urpc "
        "certify) or paper (the paper's law unchanged; it can diverge on light plants at "
        "0.5-1 kHz)",
    )
    run.add_argument(
        "--delay",
        type=int,
        choices=(0, 1),
        help="samples of actuation delay the interval law predicts over (1: it predicts one "
        "period ahead; docs/robot.md); default: the scenario's",
    )
    run.add_argument("--epsilon", metavar="E", help="required precision ||q_d - q|| < E [rad]")
    timing = run.add_mutually_exclusive_group()
    timing.add_argument("--sample-period", metavar="T", help="control period [s] (zero-order hold)")
    timing.add_argument("--continuous", action="store_true", help="continuous-time control")
    run.add_argument(
        "--disturbance",
        metavar="D",
        help="bound on ||d|| [N m], drawn per sample, unknown to the controller",
    )
    run.add_argument("--duration", metavar="S", help="simulated time [s]")
    run.add_argument(
        "--actuation-delay",
        type=non_negative_int,
        metavar="N",
        help="samples between a state and the period its torque acts over on the plant, as on "
        "a real torque interface (1: the torque computed at t_k acts from t_k + T; zero torque "
        "until the first one arrives); sampled runs only; default: the scenario's "
        "actuation_delay, else the law's own delay (--delay, else 0). The certificate covers "
        "the delay the law predicts over (0, or 1 with --delay 1, at short periods: "
        "docs/sampled-data.md section 7); any other delay is not certified",
    )
    if not simulate:  # (the certificate bounds every disturbance: no model to choose)
        p.set_defaults(
            true_params=None, controller=None, plant=None, seed=None, torque_limit=None,
            disturbance_model=None,
        )  # fmt: skip
        return
    run.add_argument(
        "--disturbance-model",
        choices=DISTURBANCE_MODELS,
        help="how the disturbance is drawn: ball (uniform in the ball, seeded; the default), or "
        "at its bound: against (against r), worst (against r in the plant's M^-1 metric, the "
        "certificate's worst case), lightest (along the lightest mode of the law's M_L)",
    )
    source.add_argument(
        "--true-params",
        metavar="FILE",
        help="true parameter point file, 'sample' (seeded draw from the box) or 'nominal'",
    )
    run.add_argument("--controller", choices=CONTROLLERS, help="controller (default: interval)")
    add_plant_argument(run, "default: the scenario's, else pinocchio; mujoco for sampled runs")
    run.add_argument(
        "--seed", type=int, metavar="N", help="seed of the disturbance and of a sampled plant"
    )
    run.add_argument(
        "--torque-limit", metavar="TAU", help="torque bound [N m]: one number or one per joint"
    )


def add_plant_argument(group, default: str) -> None:
    """``--plant {pinocchio,mujoco}``, the same in ``simulate`` and ``campaign``."""
    from ..sim import PLANT_BACKENDS  # not the plants: the argparse set-up stays lean

    group.add_argument("--plant", choices=PLANT_BACKENDS, help=f"true plant backend ({default})")


# ============================================================================== simulate
def run_simulate(args) -> int:
    from ..sim.metrics import describe_final_window
    from ..sim.plotting import plot_error, plot_gains, plot_torque, plot_trajectory
    from ..studies.certification import guarantee_of
    from ..studies.scenario import build, build_controller, simulate_setup

    if args.out is not None:
        output_folder(args.out, args.out)  # checked before any work
    elif args.replay:
        raise InputError("--replay writes DIR/replay.html: give --out DIR")
    out = args.out
    scenario = scenario_from_arguments(args)
    # Before the certificate (minutes of CPU on a real arm): the run must fit in memory.
    check_run_length(scenario.duration, scenario.sample_period, source=scenario.source)
    setup = build(scenario)
    controller = build_controller(setup)
    outcome = guarantee_of(
        setup,
        controller,
        certify=not args.no_certify,
        refresh=args.no_cache,
        progress=certificate_progress(args, setup.robot.dof),
    )
    guarantee = outcome.fields
    warn_uncertified(guarantee)
    result = simulate_setup(setup, controller, progress=show_progress(args))
    summary = {
        **result.summary(),
        "final_error_window": describe_final_window(result.duration),
        "scenario": scenario.name,
        "plant": result.info["plant"],
        "actuation_delay": result.info["actuation_delay"],
        "disturbance_model": result.info.get(
            "disturbance_model", None if result.sample_period is None else "ball"
        ),
        "true_parameters": {
            "description": setup.true_description,
            "values": result.info["true_parameters"],
            "inside_box": setup.inside_box,
            "outside_box": setup.outside_box,
        },
        **guarantee,
    }
    if out is not None:
        import yaml

        from ..atomic import write_files
        from ..sim.results import SUMMARY_NAME

        writers = result.writers(csv=True)
        summary_text = json_text(summary) + "\n"  # what --json prints: certified included
        writers[SUMMARY_NAME] = lambda path: path.write_text(summary_text)
        guarantee_text = json_text(guarantee)
        writers["certificate.json"] = lambda path: path.write_text(guarantee_text)
        document = yaml.safe_dump(scenario.to_dict(), sort_keys=False)
        writers["scenario.yaml"] = lambda path: path.write_text(document)
        figures = {
            "trajectory.png": plot_trajectory(result),
            "error.png": plot_error(result),
            "torque.png": plot_torque(result),
            "gains.png": plot_gains(result),
        }
        for name, figure in figures.items():
            writers[name] = _savefig(figure)
        if args.replay:
            writers["replay.html"] = lambda path: result.replay(
                path, setup.robot, title=f"{scenario.name}: {setup.robot.name}"
            )
        try:
            write_files(out, writers)
        except OSError as exc:
            raise write_error(exc, out) from None
    if args.json:
        print_json(summary)
        return EXIT_OK
    _print_summary(result, scenario, setup, summary, args.out, outcome.source_line)
    return EXIT_OK


def scenario_from_arguments(args):
    """The scenario of a ``simulate`` command line: the file (or a robot and its box) with every
    given flag as an override (:meth:`urpc.studies.scenario.Scenario.with_overrides`)."""
    torque_limit = args.torque_limit
    if torque_limit is not None and "," in torque_limit:
        torque_limit = names(torque_limit)
    interval = {"method": args.method, "sampled_law": args.sampled_law, "delay": args.delay}
    interval = {key: value for key, value in interval.items() if value is not None}
    return scenario_or_robot(
        args,
        "rr_planar/s2_ic1",
        box_help=" (format: docs/uncertainty-format.md)",
        locked_joints=args.lock,
        true_parameters=args.true_params,
        controller=args.controller,
        controller_options={"interval": interval} if interval else None,
        plant=args.plant,
        epsilon=args.epsilon,
        sample_period="continuous" if args.continuous else args.sample_period,
        disturbance=args.disturbance,
        disturbance_model=args.disturbance_model,
        duration=args.duration,
        seed=args.seed,
        torque_limit=torque_limit,
        actuation_delay=args.actuation_delay,
    )


def _print_summary(
    result, scenario, setup, summary: dict, out: Path | None, source: str | None
) -> None:
    m = result.metrics
    epsilon = result.epsilon
    # Units follow the joints: rad and N m (revolute), m and N (prismatic), both for a mix.
    position, force = joint_units(setup.robot.joint_kinds)
    if result.sample_period is None:
        timing = "continuous time"
    else:
        timing = f"{1.0 / result.sample_period:g} Hz zero-order hold"
        delay = result.info["actuation_delay"]
        if delay:
            timing += f", actuation delay {count(delay, 'sample')}"
    if result.disturbance_bound > 0:
        known = setup.box.disturbance_bound is not None
        model = scenario.disturbance_model
        drawn = "drawn in the ball" if model == "ball" else f"at its bound, {model}"
        timing += (
            f", disturbance ||d|| <= {result.disturbance_bound:g} {force} {drawn} "
            f"({'bound known' if known else 'unknown'} to the controller)"
        )
    else:
        timing += ", no disturbance"
    print(
        f"scenario     {scenario.name}: {setup.robot.name} ({count(setup.robot.dof, 'joint')}), "
        f"{result.controller} controller, {summary['plant']} plant"
    )
    print(f"run          {result.duration:g} s, {timing}")
    print(f"true plant   {setup.true_description}")
    if summary["certified"]:
        certificate = summary["certificate"]
        floor = certificate["epsilon_floor"]
        covered = "" if setup.inside_box else "; this true plant lies OUTSIDE the box"
        print(
            f"guarantee    certified for the box: ||e|| ends below epsilon ({certificate['law']} "
            f"law; {floor:.3g} {position} once the gains reach their ceiling){covered}"
        )
    else:
        print(f"guarantee    {summary['not_certified']}")
    if source is not None:
        print(f"certificate  {source}")
    if m["met"]:
        print(
            f"result       MET: ||e|| < epsilon = {epsilon:g} {position} from t = "
            f"{m['entry_time']:.4g} s to the end"
        )
    elif m["entry_time"] is not None:
        print(
            f"result       NOT MET: ||e|| < epsilon = {epsilon:g} {position} only from t = "
            f"{m['entry_time']:.4g} s, less than the final quarter of the run"
        )
    else:
        print(f"result       NOT MET: ||e|| ends above epsilon = {epsilon:g} {position}")
    ratio = m["final_error"] / epsilon
    print(
        f"final error  {m['final_error']:.4g} {position} (max over "
        f"{summary['final_error_window']}) = {ratio:.4g} x epsilon"
    )
    if m["max_error_after_entry"] is not None:
        print(f"after entry  max ||e|| = {m['max_error_after_entry']:.4g} {position}")
    print(
        f"torque       peak {m['torque_peak']:.4g} {force} (largest |u_i|), "
        f"RMS {m['torque_rms']:.4g} {force} (of ||u||), "
        f"variation {m['torque_variation']:.4g} {force}/s"
    )
    if result.saturated_samples:
        print(f"saturation   the torque limit clipped {count(result.saturated_samples, 'sample')}")
    if m.get("phi") is not None:
        print(
            f"gains        phi = {m['phi']:.4g} {force} s/{position}, "
            f"kappa = {m['kappa']:.4g} s/{position}"
        )
    print(
        f"time         {m['wall_time']:.3g} s wall, median control step "
        f"{1e6 * m['step_time_median']:.3g} us"
    )
    if out is not None:
        print(f"saved        {out}")


def _savefig(figure):
    def write(path: Path) -> None:
        figure.savefig(path, dpi=100, format="png")

    return write


# ============================================================================== reproduce-paper
def run_reproduce_paper(args) -> int:
    from ..studies.paper import reproduce_paper, results_markdown

    out = args.out or PAPER_OUT
    output_folder(out, PAPER_OUT)  # checked before any work
    document = reproduce_paper(
        out, progress=show_progress(args), duration=args.duration, workers=args.workers
    )
    if args.json:
        print_json(document)
        return EXIT_OK
    print(results_markdown(document))
    print(f"Wrote {len(document['files'])} files into {out} ({document['wall_time']:.1f} s).")
    return EXIT_OK
