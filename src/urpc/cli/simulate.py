"""Simulation commands: ``urpc simulate`` and ``urpc reproduce-paper``."""

from __future__ import annotations

import sys
from pathlib import Path

from ..control import SAMPLED_LAWS
from ..errors import InputError
from .common import EXIT_OK, json_text, names, positive_float, print_json, warn_uncertified


def register(commands) -> None:
    p = commands.add_parser(
        "simulate",
        help="synthesize a controller and simulate it against a true plant",
        description="Simulate one run, from a scenario file (a path or a shipped name such as "
        "rr_planar/s2_ic1; see docs/scenarios.md) or straight from a robot and an uncertainty "
        "file (--robot). Flags override the scenario file's values. Without a file the run "
        "tracks a generic sinusoid inside the joint limits, the true plant is a seeded, "
        "physically consistent draw from the box (printed), epsilon is 1e-2 rad, the control "
        "period 1e-3 s, no disturbance, 10 s.",
        epilog="Prints whether ||e|| < epsilon was met, the errors, the torque cost and the gains; "
        "--json prints them as one object; --out DIR saves result.npz, result.csv, summary.json, certificate.json, "
        "scenario.yaml and the figures (PNG).",
    )
    add_scenario_arguments(p)
    output = p.add_argument_group("output")
    output.add_argument("--out", type=Path, metavar="DIR", help="save result files and figures")
    output.add_argument("--json", action="store_true", help="print one JSON object")
    output.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(handler=run_simulate)

    p = commands.add_parser(
        "reproduce-paper",
        help="run the paper's six scenarios with both controllers; figures and a results table",
        description="Reproduce Giusti & Althoff Sec. IV: scenarios 1-3 of Table II with the "
        "initial conditions IC1 and IC2, each with the interval controller and r-alpha (12 "
        "runs, in parallel processes). Writes results.md, results.json, the figures of the "
        "paper's Figs. 1-5 and each run's result.npz and summary.json.",
    )
    p.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        default=None,
        help="output directory (default: urpc-results/paper)",
    )
    p.add_argument(
        "--duration",
        type=positive_float,
        metavar="S",
        help="simulated time of each run [s] (default: the scenario files' 10 s)",
    )
    p.add_argument(
        "--workers", type=int, default=2, metavar="N", help="parallel processes (default 2)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object (results.json)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.set_defaults(handler=run_reproduce_paper)


def add_scenario_arguments(p, simulate: bool = True) -> None:
    """The scenario and its overrides, shared by ``simulate`` and ``certify``; ``simulate=False``
    leaves out what only a run needs (true plant, controller, plant backend, seed, torque limit)."""
    p.add_argument(
        "scenario",
        nargs="?",
        help="scenario YAML file or shipped name (rr_planar/s1_ic1 ...); omit with --robot",
    )
    source = p.add_argument_group("robot and knowledge (replace or stand in for a scenario file)")
    source.add_argument("--robot", help="URDF path or robot name (rr_planar, ur5, panda, ...)")
    source.add_argument(
        "--lock", type=names, metavar="JOINTS", help="comma-separated joints to lock (at 0)"
    )
    source.add_argument(
        "--uncertainty",
        "-u",
        metavar="FILE",
        help="uncertainty YAML file (default for a robot known by name: its shipped box)",
    )
    run = p.add_argument_group("run settings")
    run.add_argument(
        "--method", help="bound method of the interval controller: vertex, hull, rigorous"
    )
    run.add_argument(
        "--sampled-law",
        choices=SAMPLED_LAWS,
        help="law of a sampled interval controller: implicit (default, certified by urpc "
        "certify) or paper (the paper's law unchanged; it can diverge on light plants at "
        "0.5-1 kHz)",
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
    if not simulate:
        p.set_defaults(true_params=None, controller=None, plant=None, seed=None, torque_limit=None)
        return
    source.add_argument(
        "--true-params",
        metavar="FILE",
        help="true parameter point file, 'sample' (seeded draw from the box) or 'nominal'",
    )
    run.add_argument("--controller", help="interval (default), r-alpha or computed-torque")
    run.add_argument("--plant", help="plant backend: pinocchio (default) or mujoco (sampled runs)")
    run.add_argument("--seed", type=int, help="seed of the disturbance and of a sampled plant")
    run.add_argument(
        "--torque-limit", metavar="TAU", help="torque bound [N m]: one number or one per joint"
    )


# ============================================================================== simulate
def run_simulate(args) -> int:
    from ..sim.plotting import plot_error, plot_torque, plot_trajectory
    from ..studies.certification import certificate_fields
    from ..studies.scenario import build, build_controller, simulate_setup

    scenario = scenario_from_arguments(args)
    setup = build(scenario)
    controller = build_controller(setup)
    guarantee = certificate_fields(setup, controller)
    warn_uncertified(guarantee)
    result = simulate_setup(setup, controller, progress=_show_progress(args))
    summary = {
        **result.summary(),
        "scenario": scenario.name,
        "plant": result.info["plant"],
        "true_parameters": {
            "description": setup.true_description,
            "values": result.info["true_parameters"],
            "inside_box": setup.inside_box,
            "outside_box": setup.outside_box,
        },
        **guarantee,
    }
    if args.out is not None:
        import yaml

        from ..sim.results import write_files

        writers = result.writers(csv=True)
        guarantee_text = json_text({key: summary[key] for key in guarantee})
        writers["certificate.json"] = lambda path: path.write_text(guarantee_text)
        document = yaml.safe_dump(scenario.to_dict(), sort_keys=False)
        writers["scenario.yaml"] = lambda path: path.write_text(document)
        figures = {
            "trajectory.png": plot_trajectory(result),
            "error.png": plot_error(result),
            "torque.png": plot_torque(result),
        }
        for name, figure in figures.items():
            writers[name] = _savefig(figure)
        try:
            write_files(args.out, writers)
        except OSError as exc:
            raise InputError(f"cannot write the results ({exc})", source=args.out) from None
    if args.json:
        print_json(summary)
        return EXIT_OK
    _print_summary(result, scenario, setup, summary, args.out)
    return EXIT_OK


def scenario_from_arguments(args):
    """The scenario of a ``simulate`` command line: the file (or a robot and its box) with every
    given flag as an override (:meth:`urpc.studies.scenario.Scenario.with_overrides`)."""
    from ..model.catalog import default_uncertainty, resolve_robot
    from ..studies.scenario import load_scenario, parse_scenario

    uncertainty = args.uncertainty
    if args.robot is not None and uncertainty is None:
        resolve_robot(args.robot)  # an unknown name: say so, with the closest one
        shipped = default_uncertainty(args.robot)
        uncertainty = None if shipped is None else str(shipped)
    if args.scenario is not None:
        scenario = load_scenario(args.scenario)
    elif args.robot is None:
        raise InputError(
            "give a scenario file (or a shipped name such as rr_planar/s2_ic1) or --robot",
            field="scenario",
        )
    elif uncertainty is None:
        raise InputError(
            f"robot '{args.robot}' has no shipped uncertainty box; write one with "
            f"'urpc init {args.robot} --out box.yaml' and give --uncertainty box.yaml "
            "(format: docs/uncertainty-format.md)",
            field="uncertainty",
        )
    else:
        scenario = parse_scenario({"robot": args.robot, "uncertainty": uncertainty})
        scenario = scenario.with_overrides(name=Path(args.robot).stem)
    torque_limit = args.torque_limit
    if torque_limit is not None and "," in torque_limit:
        torque_limit = names(torque_limit)
    interval = {"method": args.method, "sampled_law": args.sampled_law}
    interval = {key: value for key, value in interval.items() if value is not None}
    options = {"interval": interval} if interval else None
    return scenario.with_overrides(
        robot=args.robot if args.scenario is not None else None,
        locked_joints=args.lock,
        uncertainty=uncertainty if args.scenario is not None else None,
        true_parameters=args.true_params,
        controller=args.controller,
        controller_options=options,
        plant=args.plant,
        epsilon=args.epsilon,
        sample_period="continuous" if args.continuous else args.sample_period,
        disturbance=args.disturbance,
        duration=args.duration,
        seed=args.seed,
        torque_limit=torque_limit,
    )


def _print_summary(result, scenario, setup, summary: dict, out: Path | None) -> None:
    m = result.metrics
    epsilon = result.epsilon
    if result.sample_period is None:
        timing = "continuous time"
    else:
        timing = f"{1.0 / result.sample_period:g} Hz zero-order hold"
    if result.disturbance_bound > 0:
        known = setup.box.disturbance_bound is not None
        timing += (
            f", disturbance ||d|| <= {result.disturbance_bound:g} N m "
            f"({'bound known' if known else 'unknown'} to the controller)"
        )
    else:
        timing += ", no disturbance"
    print(
        f"scenario     {scenario.name}: {setup.robot.name} ({setup.robot.dof} joints), "
        f"{result.controller} controller, {summary['plant']} plant"
    )
    print(f"run          {result.duration:g} s, {timing}")
    print(f"true plant   {setup.true_description}")
    if summary["certified"]:
        certificate = summary["certificate"]
        floor = certificate["epsilon_floor"]
        covered = "" if setup.inside_box else "; this true plant lies OUTSIDE the box"
        print(
            f"guarantee    certified for the box ({certificate['law']} law; floor "
            f"{floor:.3g} rad){covered}"
        )
    else:
        print(f"guarantee    {summary['not_certified']}")
    if m["met"]:
        print(
            f"result       MET: ||e|| < epsilon = {epsilon:g} rad from t = "
            f"{m['entry_time']:.4g} s to the end"
        )
    elif m["entry_time"] is not None:
        print(
            f"result       NOT MET: ||e|| < epsilon = {epsilon:g} rad only from t = "
            f"{m['entry_time']:.4g} s, less than the final quarter of the run"
        )
    else:
        print(f"result       NOT MET: ||e|| ends above epsilon = {epsilon:g} rad")
    ratio = m["final_error"] / epsilon
    print(
        f"final error  {m['final_error']:.4g} rad (max over the last second) = "
        f"{ratio:.3g} x epsilon"
    )
    if m["max_error_after_entry"] is not None:
        print(f"after entry  max ||e|| = {m['max_error_after_entry']:.4g} rad")
    print(
        f"torque       peak {m['torque_peak']:.4g} N m, RMS {m['torque_rms']:.4g} N m, "
        f"variation {m['torque_variation']:.4g} N m/s"
    )
    if result.saturated_samples:
        print(f"saturation   the torque limit clipped {result.saturated_samples} samples")
    if m["phi"] is not None:
        print(f"gains        phi = {m['phi']:.4g} N m s/rad, kappa = {m['kappa']:.4g} s/rad")
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


def _show_progress(args) -> bool:
    return not args.no_progress and sys.stderr.isatty()


# ============================================================================== reproduce-paper
def run_reproduce_paper(args) -> int:
    from ..studies.paper import DEFAULT_OUT_DIR, reproduce_paper, results_markdown

    out = DEFAULT_OUT_DIR if args.out is None else args.out
    document = reproduce_paper(
        out, progress=_show_progress(args), duration=args.duration, workers=args.workers
    )
    if args.json:
        print_json(document)
        return EXIT_OK
    print(results_markdown(document))
    print(f"Wrote {len(document['files'])} files into {out} ({document['wall_time']:.1f} s).")
    return EXIT_OK
