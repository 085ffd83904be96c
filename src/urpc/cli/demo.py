"""Demo commands: ``urpc demo reconfigure`` and ``urpc demo tool-change``."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import (
    EXIT_OK,
    RESULTS_ROOT,
    add_command,
    add_output_arguments,
    add_subcommands,
    finite_float,
    names,
    non_negative_float,
    non_negative_int,
    output_folder,
    positive_float,
    print_json,
    show_progress,
)

#: Default output folders of the demos.
RECONFIGURE_OUT = RESULTS_ROOT / "reconfigure"
TOOL_CHANGE_OUT = RESULTS_ROOT / "tool-change"


def register(commands) -> None:
    demo = add_command(
        commands,
        "demo",
        None,  # each demo has its own handler
        help="run a demonstration (reconfigurable arm, tool change)",
        description="Demonstrations of on-the-fly synthesis for modular arms.",
    )
    demos = add_subcommands(demo, "demo", "DEMO", required=True)

    p = add_command(
        demos,
        "reconfigure",
        run_reconfigure,
        help="synthesize and simulate a sequence of arm configurations",
        description="Run a sequence of modular-arm configurations (default: the shipped "
        "assemblies arm_3dof, arm_4dof, arm_4dof_vacuum). Each one is composed from its modules, "
        "loaded and given a controller with the same default settings, then simulated at 1 kHz "
        "on a true plant drawn from its box under a disturbance the controller does not know. "
        "Reports synthesis_time [s] (composition + model load + controller construction), met "
        "and the metrics; writes DIR/reconfigure.png, DIR/reconfigure.json and DIR/<name>/.",
    )
    p.add_argument(
        "--assemblies",
        type=names,
        default=None,
        metavar="NAMES",
        help="comma-separated shipped assembly names or assembly files, in order "
        "(default: arm_3dof,arm_4dof,arm_4dof_vacuum)",
    )
    _common_arguments(p, RECONFIGURE_OUT)

    p = add_command(
        demos,
        "tool-change",
        run_tool_change,
        help="change the payload during a run; the controller switches boxes without a restart",
        description="Run the 4-DOF gripper arm (arm_4dof, about 1 kg); at --t-change the true "
        "payload becomes about 3 kg (arm_4dof_3kg) and the controller switches to the new box, "
        "keeping its internal state (phi, kappa). Reports the re-entry time into the epsilon "
        "ball; writes DIR/tool_change.png and DIR/tool_change.json.",
    )
    p.add_argument(
        "--before",
        default="arm_4dof",
        metavar="NAME",
        help="configuration before (default: arm_4dof)",
    )
    p.add_argument(
        "--after",
        default="arm_4dof_3kg",
        metavar="NAME",
        help="configuration after (default: arm_4dof_3kg)",
    )
    p.add_argument(
        "--t-change",
        type=positive_float,
        default=4.0,
        metavar="S",
        help="time of the change [s] (default: 4)",
    )
    p.add_argument(
        "--switch-delay",
        type=non_negative_float,
        default=0.0,
        metavar="S",
        help="delay between the change and the controller's switch [s] (default: 0)",
    )
    _common_arguments(p, TOOL_CHANGE_OUT)


def _common_arguments(p: argparse.ArgumentParser, out: Path) -> None:
    p.add_argument(
        "--duration",
        type=positive_float,
        default=8.0,
        metavar="S",
        help="simulated time [s] (default: 8)",
    )
    p.add_argument(
        "--seed",
        type=non_negative_int,
        default=0,
        metavar="N",
        help="seed of plants and disturbances (default: 0)",
    )
    p.add_argument(
        "--initial-offset",
        type=finite_float,
        default=None,
        metavar="RAD",
        help="start this far from the reference on every joint [rad] (default: on it)",
    )
    add_output_arguments(p, str(out), what="figure and results")
    p.add_argument(
        "--replay",
        action="store_true",
        help="also write DIR/replay.html: a 3D replay of the arm (each configuration in turn) "
        "that opens offline in a browser (docs/replay.md)",
    )


def run_reconfigure(args) -> int:
    from ..studies.demo import reconfigure_demo

    return _run_demo(
        args, reconfigure_demo, RECONFIGURE_OUT, _print_reconfigure, configurations=args.assemblies
    )


def _print_reconfigure(summary: dict) -> None:
    settings = summary["settings"]
    print(
        f"epsilon {settings['epsilon']:g} rad, {1 / settings['sample_period']:g} Hz, "
        f"||d|| <= {settings['disturbance_bound']:g} N m (unknown to the controller), "
        f"{settings['duration']:g} s per configuration"
    )
    header = (
        f"  {'configuration':<18} {'dof':>3} {'synthesis [ms]':>14} {'met':>5} "
        f"{'entry [s]':>9} {'final error [rad]':>17} {'wall [s]':>8}"
    )
    print(header)
    for entry in summary["configurations"]:
        entry_time = "-" if entry.get("entry_time") is None else f"{entry['entry_time']:.3f}"
        final = "diverged" if entry["diverged"] else f"{entry['final_error']:.3g}"
        wall = "-" if entry["diverged"] else f"{entry['wall_time']:.1f}"
        print(
            f"  {entry['name']:<18} {entry['dof']:>3} {1e3 * entry['synthesis_time']:>14.1f} "
            f"{'yes' if entry['met'] else 'NO':>5} {entry_time:>9} {final:>17} {wall:>8}"
        )
    _print_drives(summary["configurations"])


def _print_drives(configurations) -> None:
    """One line per configuration with drives: each joint's nominal armature, damping and
    friction (the true plant's are drawn from the intervals in the JSON output)."""
    lines = []
    for entry in configurations:
        drives = entry.get("drives") or {}
        values = []
        for joint, drive in drives.items():
            nominal = [v["nominal"] for k, v in drive.items() if k != "module"]
            values.append(f"{joint} " + "/".join(f"{x:g}" for x in nominal))
        if values:
            lines.append(f"  {entry['name']:<18} {', '.join(values)}")
    if lines:
        print(
            "drives, nominal armature [kg m^2] / damping [N m s/rad] / friction [N m], each "
            "uncertain (true plants drawn from the intervals):"
        )
        print("\n".join(lines))


def run_tool_change(args) -> int:
    from ..studies.demo import tool_change_demo

    return _run_demo(
        args,
        tool_change_demo,
        TOOL_CHANGE_OUT,
        _print_tool_change,
        before=args.before,
        after=args.after,
        t_change=args.t_change,
        switch_delay=args.switch_delay,
    )


def _print_tool_change(summary: dict) -> None:
    reentry = summary["reentry_time"]
    phi = summary["phi_at_switch"]
    print(
        f"{summary['before']['name']} -> {summary['after']['name']} at {summary['t_change']:g} s "
        f"(controller switched {summary['switch_delay']:g} s later; new controller built in "
        f"{1e3 * summary['switch_time']:.1f} ms)"
    )
    print(
        f"phi at the switch: {phi['end_of_old_controller']:.6g} -> "
        f"{phi['start_of_new_controller']:.6g} N m s/rad (state carried over)"
    )
    print(
        "re-entry into the epsilon ball after the change: "
        + ("never" if reentry is None else f"{1e3 * reentry:.0f} ms")
        + f"; max error after the change {summary['max_error_after_change']:.3g} rad; "
        + f"met {'yes' if summary['met'] else 'NO'}"
    )


def _run_demo(args, demo, default_out: Path, print_text, **options) -> int:
    """Run ``demo`` into ``--out`` (default ``default_out``, checked before any work) with the
    options every demo has and its own ``options``; print its summary as one JSON object
    (``--json``) or as ``print_text`` does, then the files it wrote."""
    out = args.out or default_out
    output_folder(out, default_out)  # checked before any work
    summary = demo(
        out,
        progress=show_progress(args),
        duration=args.duration,
        seed=args.seed,
        initial_offset=args.initial_offset,
        replay=args.replay,
        **options,
    )
    if args.json:
        print_json(summary)
        return EXIT_OK
    print_text(summary)
    print(f"figure  {summary['figure']}")
    if summary["replay"]:
        print(f"replay  {summary['replay']}")
    return EXIT_OK
