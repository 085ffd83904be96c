"""``urpc certify``: for which epsilon and which sample period the guarantee holds."""

from __future__ import annotations

from ..names import KR_CANDIDATES
from .common import (
    EXIT_OK,
    add_certificate_arguments,
    add_command,
    add_json_argument,
    add_progress_argument,
    certificate_progress,
    positive_int,
    print_json,
)


def register(commands) -> None:
    from .simulate import add_scenario_arguments

    p = add_command(
        commands,
        "certify",
        run_certify,
        help="say whether the tracking guarantee holds for a scenario, and down to which epsilon",
        description="Synthesize the interval controller of a scenario (a file, a shipped name "
        "such as rr_planar/s3_ic1, or --robot with its box) and check the conditions of its "
        "guarantee: Theorems 1-2 in continuous time; under a zero-order hold, the discrete-time "
        "argument of the implicit law (docs/sampled-data.md). Reports whether it is certified, "
        "epsilon_floor (the smallest epsilon guaranteed at this period) [rad], "
        "max_sample_period (the largest period at which the requested epsilon is guaranteed) "
        "[s], and every condition with its value and limit.",
        epilog="The certificate is computed once per configuration and read back from the "
        "certificate cache after that (the last line says which; --no-cache computes it again). "
        "Exit code 0 whether or not the configuration is certified (the answer is the "
        "output); 2 on bad input.",
    )
    add_scenario_arguments(p, simulate=False)
    p.add_argument(
        "--search-kr",
        action="store_true",
        help="certified synthesis of Kr: certify the controller for each uniform gain of "
        f"{', '.join(f'{k:g}' for k in KR_CANDIDATES)} 1/s and report the best certificate "
        "(certified with the lowest floor, else the longest certified period); each candidate "
        "costs one certificate",
    )
    p.add_argument(
        "--cells",
        type=positive_int,
        metavar="N",
        help="first cells of time the certificate bounds over (default: the reference moves at "
        "most 0.02 rad per joint within one; 8 to 4000, clipped); more cells tighten the "
        "inertia models over each, which an impractical period's advice asks for on long or "
        "light-wristed arms, at a cost about proportional",
    )
    p.add_argument(
        "--require-efforts",
        action="store_true",
        help="for an arm whose drives clip at the URDF's effort limits (a clipped torque voids "
        "the argument): certified only if the bound of the commanded torque is within every "
        "joint's effort, and the max sample period is one where it is. Default: the bound is "
        "reported against the efforts and the verdict assumes an unclipped torque, as the "
        "paper's theorems do",
    )
    add_json_argument(p)
    add_certificate_arguments(p, skippable=False)
    add_progress_argument(p, "no progress line (shown only when stderr is a terminal)")


def run_certify(args) -> int:
    from ..studies.certification import cached_setup
    from ..studies.scenario import build, build_controller
    from .simulate import scenario_from_arguments

    scenario = scenario_from_arguments(args)
    search = None

    def certified(setup, controller=None):
        return cached_setup(
            setup,
            controller or build_controller(setup, "interval"),
            refresh=args.no_cache,
            cells=args.cells,
            require_efforts=args.require_efforts,
            progress=certificate_progress(args, setup.robot.dof),
            announce=False,  # the last line of the output says it
        )

    if args.search_kr:
        from ..control.gain_search import best_gain
        from ..errors import InputError

        probe = build_controller(build(scenario), "interval")
        if probe.feedback.name == "paper":  # the held paper law
            raise InputError(
                "--search-kr needs the implicit sampled law: the paper's law under a hold is "
                "never certified, whatever Kr; give --sampled-law implicit",
                field="sampled_law",
            )
        outcomes = {}

        def certify_with(Kr: float):
            candidate = build(scenario.with_overrides(controller_options={"interval": {"Kr": Kr}}))
            controller = build_controller(candidate, "interval")
            outcomes[Kr] = certified(candidate, controller)
            return controller, outcomes[Kr].certificate

        def report(trial) -> None:
            if not args.json:
                c = trial.certificate
                state = "certified" if c.certified else "not certified"
                print(
                    f"  Kr = {trial.Kr:<5g} {state:<13} floor {c.epsilon_floor:.3g} rad, "
                    f"max sample period {c.max_sample_period * 1e3:.3g} ms",
                    flush=True,
                )

        if not args.json:
            print(f"{scenario.name}: searching Kr ({len(KR_CANDIDATES)} certificates)")
        search = best_gain(certify_with, KR_CANDIDATES, report)
        outcome = outcomes[search.best.Kr]
    else:
        outcome = certified(build(scenario))
    certificate = outcome.certificate
    if args.json:
        extra = {} if search is None else {"kr_search": search.to_dict()}
        print_json({"scenario": scenario.name, **certificate.to_dict(), **extra})
        return EXIT_OK
    if search is not None:
        print(f"best Kr = {search.best.Kr:g} 1/s (uniform); its certificate:")
    print(f"{scenario.name}: {certificate.summary()}")
    width = max(len(c.name) for c in certificate.conditions)
    for c in certificate.conditions:
        mark = "ok  " if c.holds else "FAIL"
        line = f"  {mark} {c.name:<{width}}  value {c.value:.4g}  limit {c.limit:.4g}"
        print(line if c.holds else f"{line}  -> {c.explanation}")
    advice = certificate.figures.get("advice")
    if advice:
        print(f"  {advice}")
    print(f"certificate: {outcome.describe()}")
    return EXIT_OK
