"""The performance suite (the figures of docs/performance.md), as ``urpc bench``.

    python scripts/bench.py                 # the full suite (about a minute), one table
    python scripts/bench.py --quick         # fewer repeats, 2 s simulations, 4-run campaign
    python scripts/bench.py --json          # one JSON object (the keys of `urpc bench --json`)
    python scripts/bench.py --profile       # also: where one control step's time goes
    python scripts/bench.py --profile-only  # only the control-step profile

Both run :func:`urpc.studies.benchmark.run_benchmarks`; the profile is
:func:`urpc.studies.benchmark.profile_control_step` (parts of one control step timed side by side).
"""

from __future__ import annotations

import argparse
import json
import sys

from urpc.jsonsafe import jsonable
from urpc.studies.benchmark import (
    BENCHMARK_ROBOTS,
    DRIVE_ROBOTS,
    SuiteSettings,
    format_benchmarks,
    format_machine,
    format_profile,
    machine_info,
    profile_control_step,
    run_benchmarks,
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the quick settings")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--profile", action="store_true", help="also profile one control step")
    parser.add_argument("--profile-only", action="store_true", help="only the profile")
    parser.add_argument("--repeats", type=int, default=101, help="timed batches of the profile")
    args = parser.parse_args(argv)

    def progress(message: str) -> None:
        print(f"bench: {message} ...", file=sys.stderr, flush=True)

    document: dict = {}
    if not args.profile_only:
        settings = SuiteSettings.quick() if args.quick else SuiteSettings()
        document = run_benchmarks(settings=settings, progress=progress)
        if not args.json:
            print(
                f"{format_machine(document['machine'])}\n\n{format_benchmarks(document, settings)}"
            )
    if args.profile or args.profile_only:
        progress("control-step profile")
        machine = machine_info()
        profile = profile_control_step(BENCHMARK_ROBOTS + DRIVE_ROBOTS, args.repeats)
        if args.json:
            document = (
                {**document, "profile": profile}
                if document
                else {"machine": machine, "profile": profile}
            )
        else:
            print(f"\ncontrol-step profile, {format_machine(machine)}\n\n{format_profile(profile)}")
    if args.json:
        print(json.dumps(jsonable(document), indent=2, allow_nan=False))
    return 0


if __name__ == "__main__":  # the campaign's worker processes re-import this file
    raise SystemExit(main())
