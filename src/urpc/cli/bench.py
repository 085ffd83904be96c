"""Benchmark commands: ``urpc bench`` (the performance suite) and ``urpc bench bounds``."""

from __future__ import annotations

import argparse
import dataclasses
import sys

from ..errors import InputError
from .common import (
    EXIT_OK,
    add_command,
    add_json_argument,
    add_progress_argument,
    add_subcommands,
    names,
    positive_int,
    print_json,
    show_progress,
)

#: urpc.studies.benchmark.DEFAULT_LOOP_STEPS, not imported so that the CLI starts without
#: Pinocchio (tests/test_benchmark.py checks that the two agree).
DEFAULT_LOOP_STEPS = 3000


def register(commands) -> None:
    p = add_command(
        commands,
        "bench",
        run_bench,
        help="measure the performance suite: rho, control step, loop latency, simulation, "
        "synthesis, campaign",
        description="Measure the figures of docs/performance.md on this machine: one rho "
        "evaluation per bound method and robot and its ratio to one nominal pin.rnea call, one "
        "control step, the latency of the robot control loop's step (p50 / p99 / p99.9 / max "
        "next to one RNEA, docs/robot.md), the simulation speed of the paper's scenarios 2 and "
        "3, the synthesis time, and the throughput of a small campaign on 2 workers. The full "
        "suite takes under a minute on 2 cores, --quick a few seconds. 'urpc bench bounds' times "
        "rho alone, 'urpc bench loop' the loop's latency alone.",
        epilog="Timings of single calls are medians of interleaved batches of thread CPU time, "
        "next to one pin.rnea call timed in the same batches: on a shared machine the ratios "
        "are the stable figures.",
    )
    p.add_argument("--quick", action="store_true", help="fewer repeats, shorter simulations")
    p.add_argument(
        "--loop-steps",
        type=positive_int,
        metavar="N",
        help=f"control-loop steps timed per robot (default {DEFAULT_LOOP_STEPS}, --quick 1000; "
        "tens of thousands for tails worth quoting)",
    )
    add_json_argument(p)
    add_progress_argument(p, "no progress lines on stderr")
    parts = add_subcommands(p, "bench_part", "[bounds|loop|certificate]")

    b = add_command(
        parts,
        "bounds",
        run_bench_bounds,
        help="time one rho evaluation per bound method and robot, with its ratio to pin.rnea",
        description="Time one evaluation of rho (the Slotine-Li regressor included) per bound "
        "method on the benchmark box of each robot (the RR arm's Table I box; +-10 % mass, "
        "+-1 cm CoM and +-10 % inertia on every link of the UR5 and the Panda), next to one "
        "nominal pin.rnea call timed in the same batches.",
    )
    _add_json(b)
    b.add_argument("--quick", action="store_true", default=argparse.SUPPRESS, help="fewer repeats")
    _add_robots(b)
    b.add_argument(
        "--methods",
        type=names,
        metavar="NAMES",
        help="comma-separated bound methods (default: hull,vertex,rigorous)",
    )
    b.add_argument(
        "--repeats", type=positive_int, metavar="N", help="timed batches per figure (default 51)"
    )

    lp = add_command(
        parts,
        "loop",
        run_bench_loop,
        help="the robot control loop's step latency (p50 / p99 / p99.9 / max) next to one RNEA",
        description="Time consecutive ControlLoop.step calls (reference, controller output and "
        "advance, one log row) on each robot's 1 kHz scenario, in wall-clock time as the loop "
        "measures itself, next to one nominal pin.rnea of the same arm timed the same way; "
        "prints p50, p99, p99.9 and max. The tail is the operating system's on a loaded machine.",
    )
    _add_json(lp)
    lp.add_argument(
        "--steps",
        type=positive_int,
        default=DEFAULT_LOOP_STEPS,
        metavar="N",
        help=f"steps timed per robot (default {DEFAULT_LOOP_STEPS})",
    )
    _add_robots(lp)

    cp = add_command(
        parts,
        "certificate",
        run_bench_certificate,
        help="the certificate's CPU time next to 1000 control steps (UR5, Panda, 30-link chain)",
        description="Time urpc.certify (implicit law, 1 kHz, epsilon 1e-2, a 2 s generic "
        "reference, the arm's box, d = 2 N m) and 1000 control steps of the same controller, "
        "in CPU seconds in one process, with their ratio, the cells and the outcome. An arm is "
        "a shipped robot with its shipped box (ur5, panda, ...) or chainN, a serial chain of N "
        "revolute joints with +-10 %% masses. The 30-link chain takes minutes; docs/"
        "performance.md has the figures.",
        epilog="Run with OPENBLAS_NUM_THREADS=1: the products are small, and BLAS threads cost "
        "CPU for nothing.",
    )
    _add_json(cp)
    cp.add_argument(
        "--arms",
        type=names,
        metavar="NAMES",
        help="comma-separated arms (default: ur5,panda,chain30; chainN for an N-link chain)",
    )


def run_bench(args) -> int:
    from ..studies.benchmark import (
        SuiteSettings,
        format_benchmarks,
        format_machine,
        run_benchmarks,
    )

    settings = SuiteSettings.quick() if args.quick else SuiteSettings()
    if args.loop_steps is not None:
        settings = dataclasses.replace(settings, loop_steps=args.loop_steps)
    result = run_benchmarks(settings=settings, progress=_progress(args))
    if args.json:
        print_json(result)
        return EXIT_OK
    print(f"urpc bench{' --quick' if args.quick else ''}: {format_machine(result['machine'])}\n")
    print(format_benchmarks(result, settings))
    return EXIT_OK


def run_bench_bounds(args) -> int:
    from ..studies.benchmark import SUITE_METHODS, bench_bounds, format_timings

    robots = _robots(args)
    methods = args.methods or list(SUITE_METHODS)
    repeats = args.repeats or (11 if getattr(args, "quick", False) else 51)
    return _report(args, lambda: bench_bounds(robots, methods, repeats), format_timings)


def run_bench_loop(args) -> int:
    from ..studies.benchmark import format_latency, loop_latency

    robots = _robots(args)
    return _report(
        args,
        lambda: {"loop_step": {name: loop_latency(name, args.steps) for name in robots}},
        lambda result: format_latency(result["loop_step"]),
    )


def run_bench_certificate(args) -> int:
    from ..model.catalog import builtin_root
    from ..studies.benchmark.certificate_cost import (
        CERTIFICATE_ARMS,
        certificate_costs,
        format_certificate_costs,
    )

    arms = args.arms or list(CERTIFICATE_ARMS)
    known = {p.name for p in builtin_root().iterdir() if (p / "uncertainty.yaml").is_file()}
    unknown = [
        a for a in arms if a not in known and not (a.startswith("chain") and a[5:].isdigit())
    ]
    if unknown:
        raise InputError(
            f"unknown arm {', '.join(unknown)}; valid: chainN (N joints) or a shipped robot "
            f"({', '.join(sorted(known))})",
            field="arms",
        )
    return _report(
        args,
        lambda: {"certificate": certificate_costs(arms, _progress(args))},
        lambda result: format_certificate_costs(result["certificate"]),
    )


def _add_json(part) -> None:
    # SUPPRESS: `urpc bench --json bounds` and `urpc bench bounds --json` both work.
    add_json_argument(part, default=argparse.SUPPRESS)


def _add_robots(part) -> None:
    """``--robots`` of a ``bench`` part (read back by :func:`_robots`)."""
    part.add_argument(
        "--robots",
        type=names,
        metavar="NAMES",
        help="comma-separated robots (default: rr_planar,ur5,panda)",
    )


def _robots(args) -> list[str]:
    """``--robots`` of a ``bench`` part (default: every benchmark robot), checked."""
    from ..studies.benchmark import BENCHMARK_ROBOTS

    robots = args.robots or list(BENCHMARK_ROBOTS)
    unknown = [name for name in robots if name not in BENCHMARK_ROBOTS]
    if unknown:
        raise InputError(
            f"unknown benchmark robot {', '.join(unknown)}; valid: {', '.join(BENCHMARK_ROBOTS)}",
            field="robots",
        )
    return robots


def _report(args, measure, text) -> int:
    """A ``bench`` part's figures (``measure()``) with the machine they were measured on: one
    JSON object with ``--json``, else the machine's line and ``text(figures)``."""
    from ..studies.benchmark import format_machine, machine_info

    machine = machine_info()
    result = measure()
    if getattr(args, "json", False):
        print_json({"machine": machine, **result})
        return EXIT_OK
    print(f"{format_machine(machine)}\n")
    print(text(result))
    return EXIT_OK


def _progress(args):
    if not show_progress(args):  # the CLI's rule: only on a terminal
        return None
    return lambda message: print(f"bench: {message} ...", file=sys.stderr, flush=True)
