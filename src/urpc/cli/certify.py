"""``urpc certify``: for which epsilon and which sample period the guarantee holds."""

from __future__ import annotations

from .common import EXIT_OK, add_certificate_arguments, print_json, show_progress


def register(commands) -> None:
    from .simulate import add_scenario_arguments

    p = commands.add_parser(
        "certify",
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
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_certificate_arguments(p, skippable=False)
    p.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress line (shown only when stderr is a terminal)",
    )
    p.set_defaults(handler=run_certify)


def run_certify(args) -> int:
    from ..studies.certification import cached_setup
    from ..studies.scenario import build, build_controller
    from .simulate import scenario_from_arguments

    scenario = scenario_from_arguments(args)
    setup = build(scenario)
    outcome = cached_setup(
        setup,
        build_controller(setup, "interval"),
        refresh=args.no_cache,
        progress=show_progress(args),
        announce=False,  # the last line of the output says it
    )
    certificate = outcome.certificate
    if args.json:
        print_json({"scenario": scenario.name, **certificate.to_dict()})
        return EXIT_OK
    print(f"{scenario.name}: {certificate.summary()}")
    width = max(len(c.name) for c in certificate.conditions)
    for c in certificate.conditions:
        mark = "ok  " if c.holds else "FAIL"
        line = f"  {mark} {c.name:<{width}}  value {c.value:.4g}  limit {c.limit:.4g}"
        print(line if c.holds else f"{line}  -> {c.explanation}")
    print(f"certificate: {outcome.describe()}")
    return EXIT_OK
