"""``urpc campaign``: many runs of one scenario over its parameter box, in parallel."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

from ..control import SAMPLED_LAWS
from .common import (
    EXIT_OK,
    RESULTS_ROOT,
    ROBOT_HELP,
    add_certificate_arguments,
    add_command,
    add_output_arguments,
    add_scenario_argument,
    add_uncertainty_option,
    count,
    non_negative_float,
    non_negative_int,
    output_folder,
    positive_float,
    positive_int,
    print_json,
    scenario_or_robot,
    show_progress,
    warn_uncertified,
)

#: Exit code of an interrupted campaign (128 + SIGINT, as a shell reports it).
EXIT_INTERRUPTED = 130


def register(commands) -> None:
    from .simulate import add_plant_argument

    p = add_command(
        commands,
        "campaign",
        run_campaign_command,
        help="verify a scenario at scale: many true plants, disturbances and initial states",
        description="Run SCENARIO many times, each run with its own true parameters (all vertices "
        "of the box when 2^n_uncertain <= RUNS, else RUNS/2 random vertices; the rest uniform "
        "draws; physically consistent points only), disturbance seed and initial offset (uniform "
        "within +-IC_SPREAD epsilon per joint), in parallel on local processes or on a Dask "
        "cluster. Writes DIR/runs.csv (one row per run), DIR/summary.json and "
        "DIR/histogram.png, built from DIR/runs.sqlite, where each run is recorded as it "
        "finishes. The same seed gives the same draws and results, whatever the number of "
        "workers. Ctrl-C stops the workers at once and keeps the finished runs; --resume "
        "continues an interrupted (or killed) campaign with the same settings, with results "
        "identical to an uninterrupted one. One campaign at a time per DIR (a lock).",
    )
    add_scenario_argument(p)
    p.add_argument(
        "--robot",
        metavar="ROBOT",
        help=ROBOT_HELP + "; as in simulate, replaces or stands in for SCENARIO",
    )
    add_uncertainty_option(p)
    p.add_argument(
        "--runs",
        type=positive_int,
        required=True,
        metavar="N",
        help="number of runs (at most 100000)",
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--workers", type=positive_int, metavar="N", help="local worker processes (default: 2)"
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="address of a running Dask scheduler (tcp://host:8786) whose workers have urpc "
        "installed; replaces the local processes",
    )
    p.add_argument(
        "--seed", type=non_negative_int, default=0, metavar="N", help="campaign seed (default: 0)"
    )
    p.add_argument(
        "--duration", type=positive_float, metavar="S", help="override the scenario's duration [s]"
    )
    add_plant_argument(p, "default: the scenario's")
    p.add_argument(
        "--sampled-law",
        choices=SAMPLED_LAWS,
        help="law of a sampled interval controller: implicit (certified by urpc certify) or "
        "paper (the paper's law unchanged); default: the scenario's setting",
    )
    p.add_argument(
        "--ic-spread",
        type=non_negative_float,
        default=2.0,
        metavar="E",
        help="half-width of the random initial offset, in epsilon (default: 2)",
    )
    p.add_argument(
        "--vertex-runs",
        type=non_negative_int,
        metavar="N",
        help="number of vertex runs (default: every vertex if they fit, else RUNS/2)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the campaign recorded in DIR (the same settings), running only the runs "
        "not yet recorded",
    )
    add_certificate_arguments(p)
    add_output_arguments(
        p, str(RESULTS_ROOT / "campaign" / "SCENARIO"), what="records, runs, summary and histogram"
    )


def run_campaign_command(args) -> int:
    from ..studies.campaign import CampaignInterrupted, run_campaign

    law = args.sampled_law
    scenario = scenario_or_robot(  # as in simulate; --robot/--uncertainty override SCENARIO's
        args,
        "rr_planar/s3_ic1",
        see=" (see 'urpc campaign --help')",
        duration=args.duration,
        plant=args.plant,
        controller_options=None if law is None else {"interval": {"sampled_law": law}},
    )
    out = output_folder(args.out, default_out(scenario.name))  # before any work
    try:
        result = run_campaign(
            scenario,
            args.runs,
            workers=2 if args.workers is None else args.workers,
            scheduler=args.scheduler,
            seed=args.seed,
            progress=show_progress(args),
            ic_spread=args.ic_spread,
            vertex_runs=args.vertex_runs,
            out=out,
            resume=args.resume,
            certify=not args.no_certify,
            refresh_certificate=args.no_cache,
        )
    except CampaignInterrupted as stop:
        print(
            f"error: interrupted; {stop.done} of {stop.total} runs are recorded in "
            f"{out / 'runs.sqlite'}; continue with: {resume_command(args, out)}",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    warn_uncertified(result.certificate)
    summary = result.summary()
    if args.json:
        print_json({**summary, "out": str(out)})
        return EXIT_OK
    print("\n".join(describe_summary(summary, out, result.certificate_source)))
    return EXIT_OK


def resume_command(args, out: Path) -> str:
    """The command line that continues this campaign: its settings, ``--out`` and ``--resume``."""
    argv = ["urpc", "campaign"]
    if args.scenario is not None:
        argv.append(args.scenario)
    options = {
        "--robot": args.robot,
        "--uncertainty": args.uncertainty,
        "--runs": args.runs,
        "--workers": args.workers,
        "--scheduler": args.scheduler,
        "--seed": args.seed,
        "--duration": args.duration,
        "--plant": args.plant,
        "--sampled-law": args.sampled_law,
        "--ic-spread": args.ic_spread,
        "--vertex-runs": args.vertex_runs,
        "--out": out,
    }
    for option, value in options.items():
        if value is not None:
            argv += [option, repr(value) if isinstance(value, float) else str(value)]
    flags = {"--no-certify": args.no_certify, "--no-cache": args.no_cache}
    argv += [flag for flag, given in flags.items() if given]
    return shlex.join([*argv, "--resume"])


def default_out(scenario_name: str) -> Path:
    """``urpc-results/campaign/<scenario name>``."""
    return RESULTS_ROOT / "campaign" / scenario_name


def describe_summary(summary: dict, out: Path, certificate_source: str | None = None) -> list[str]:
    """The text report of a campaign summary, one line per item (``certificate_source``: how
    the certificate was obtained, :attr:`CampaignResult.certificate_source`)."""
    lines = [
        f"campaign {summary['scenario']}: {count(summary['runs'], 'run')} "
        f"({summary['vertex_runs']} of {count(summary['vertex_total'], 'vertex', 'vertices')}, "
        f"{summary['uniform_runs']} uniform; "
        f"{count(summary['rejected_draws'], 'inconsistent draw')} rejected), "
        f"seed {summary['seed']}",
        f"  met epsilon = {summary['epsilon']:g} rad  {summary['met']}/{summary['runs']} "
        f"(met_fraction {summary['met_fraction']:.4g})",
        "  guarantee            "
        + ("certified" if summary["certified"] else summary["not_certified"]),
    ]
    if certificate_source is not None:
        lines.append(f"  certificate          {certificate_source}")
    if summary["diverged"] or summary["never_entered"]:
        lines.append(
            f"  diverged             {summary['diverged']}, never entered "
            f"{summary['never_entered']}"
        )
    worst = summary["worst_final_error_over_epsilon"]
    if worst is not None:
        run = summary["worst_final_error_run"]
        lines.append(f"  worst final error    {worst:.4g} epsilon (run {run})")
    if summary["worst_entry_time"] is not None:
        lines.append(f"  worst entry time     {summary['worst_entry_time']:.4g} s")
    if summary["torque_peak_max"] is not None:
        lines.append(f"  torque peak max      {summary['torque_peak_max']:.4g} N m")
    where = summary["scheduler"] or f"{summary['workers']} local worker(s)"
    lines += [
        f"  wall time            {summary['wall_time']:.1f} s on {where} "
        f"({summary['runs_per_minute']:.1f} runs/min)",
        f"  outputs              {out}/{{runs.csv, summary.json, histogram.png}} (records: "
        "runs.sqlite)",
    ]
    return lines
