"""Cost of one rho evaluation (Slotine-Li regressor included) per robot and bound method.

    python scripts/bench_bounds.py                          # hull, vertex, vertex-plain, rigorous
    python scripts/bench_bounds.py --methods hull vertex    # a subset
    python scripts/bench_bounds.py --write-docs             # also replace the table in docs/bounds.md

Figures are medians over timed batches of the CPU time of the calling thread
(:func:`urpc.studies.benchmark.bench_bounds`), with one nominal ``pinocchio.rnea`` call timed in the same
run for scale. ``urpc bench bounds`` prints the same table (default methods: hull, vertex,
rigorous); ``urpc bench`` and ``scripts/bench.py`` run the whole performance suite.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from urpc.bounds import METHODS
from urpc.studies.benchmark import (
    BENCHMARK_ROBOTS,
    VARIANTS,
    bench_bounds,
    format_machine,
    format_timings,
    machine_info,
)

DOCS = Path(__file__).resolve().parents[1] / "docs" / "bounds.md"
MARKERS = ("<!-- timing:begin -->", "<!-- timing:end -->")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", nargs="+", default=list(BENCHMARK_ROBOTS))
    parser.add_argument(
        "--methods",
        nargs="+",
        default=[
            m for m in ("hull", "vertex", *VARIANTS, "rigorous") if m in METHODS or m in VARIANTS
        ],
        help="registered methods or variants (default: all)",
    )
    parser.add_argument("--repeats", type=int, default=51, help="timed batches per figure")
    parser.add_argument("--write-docs", action="store_true", help=f"update {DOCS}")
    args = parser.parse_args(argv)
    result = bench_bounds(args.robots, args.methods, args.repeats)
    machine = format_machine(machine_info())
    text = format_timings(result)
    print(f"{machine}\n\n{text}")
    if args.write_docs:
        document = DOCS.read_text()
        pattern = re.compile(re.escape(MARKERS[0]) + ".*?" + re.escape(MARKERS[1]), re.S)
        block = f"{MARKERS[0]}\n{machine}:\n\n{text}\n{MARKERS[1]}"
        DOCS.write_text(pattern.sub(lambda _: block, document))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
