"""Cost of one rho evaluation (Slotine-Li regressor included) per robot and bound method.

    python scripts/bench_bounds.py                          # hull, vertex, vertex-plain, rigorous
    python scripts/bench_bounds.py --methods hull vertex    # a subset
    python scripts/bench_bounds.py --write-docs             # also replace the table in docs/bounds.md
    python scripts/bench_bounds.py --before /tmp/old/src    # side by side with an older source tree

``--before SRC`` copies the package found in ``SRC/urpc`` (for example a ``git worktree`` of an older
commit) as ``urpc_before``, and times its ``rho`` next to the current one, at the same state, in
the same interleaved batches (with RNEA), so that a change's cost is measured on one machine load.

Figures are medians over timed batches of the CPU time of the calling thread
(:func:`urpc.studies.benchmark.bench_bounds`), with one nominal ``pinocchio.rnea`` call timed in the same
run for scale. ``urpc bench bounds`` prints the same table (default methods: hull, vertex,
rigorous); ``urpc bench`` and ``scripts/bench.py`` run the whole performance suite.
"""

from __future__ import annotations

import argparse
import importlib
import re
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from urpc.bounds import METHODS
from urpc.studies.benchmark import (
    BENCHMARK_ROBOTS,
    VARIANTS,
    bench_bounds,
    benchmark_box,
    benchmark_robot,
    format_machine,
    format_timings,
    machine_info,
)

DOCS = Path(__file__).resolve().parents[1] / "docs" / "bounds.md"
MARKERS = ("<!-- timing:begin -->", "<!-- timing:end -->")


def load_before(source: Path):
    """The package of ``source/urpc`` imported under the name ``urpc_before`` (its imports are
    relative, so the copy is independent of the current package)."""
    target = Path(tempfile.mkdtemp(prefix="urpc-before-")) / "urpc_before"
    shutil.copytree(Path(source) / "urpc", target, ignore=shutil.ignore_patterns("__pycache__"))
    sys.path.insert(0, str(target.parent))
    return importlib.import_module("urpc_before")


def side_by_side(before, robots: list[str], methods: list[str], repeats: int) -> str:
    """A Markdown table: each method's ``rho`` before and after, at one state per robot."""
    from urpc.studies.benchmark import make_method

    old_benchmark = importlib.import_module("urpc_before.studies.benchmark")

    def calls(robot_name: str) -> dict:
        rng = np.random.default_rng(0)
        robot = benchmark_robot(robot_name)
        old_robot = old_benchmark.benchmark_robot(robot_name)
        box, old_box = benchmark_box(robot), old_benchmark.benchmark_box(old_robot)
        q, qd, qd_a = (rng.uniform(-1.0, 1.0, robot.dof) for _ in range(3))
        qdd_a = 5.0 * rng.uniform(-1.0, 1.0, robot.dof)
        functions = {}
        for name in methods:
            new, old = (
                make_method(name, robot, box),
                old_benchmark.make_method(name, old_robot, old_box),
            )
            functions[f"{name} before"] = lambda m=old: m.rho(q, qd, qd_a, qdd_a)
            functions[f"{name} after"] = lambda m=new: m.rho(q, qd, qd_a, qdd_a)
        return functions

    result = bench_bounds(robots, [], repeats, extra_calls=calls)
    header = "| robot | RNEA [us] | " + " | ".join(
        f"{m} before [us] | {m} after [us] | after / before" for m in methods
    )
    lines = [header + " |", "|---" * (2 + 3 * len(methods)) + "|"]
    for robot in robots:
        extra, rnea = result["extra"][robot], result["rnea"][robot]
        cells = []
        for m in methods:
            old, new = extra[f"{m} before"], extra[f"{m} after"]
            cells += [f"{1e6 * old:.1f} ({old / rnea:.1f})", f"{1e6 * new:.1f} ({new / rnea:.1f})"]
            cells.append(f"{new / old:.3f}")
        lines.append(f"| {robot} | {1e6 * rnea:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


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
    parser.add_argument(
        "--before",
        type=Path,
        help="a source tree (containing urpc/) to time side by side with the current code",
    )
    args = parser.parse_args(argv)
    if args.before is not None:
        load_before(args.before)
        methods = [m for m in args.methods if m != "rigorous"]
        text = side_by_side(args.before, args.robots, methods, args.repeats)
        print(f"{format_machine(machine_info())}\n\n(x RNEA in parentheses)\n\n{text}")
        return 0
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
