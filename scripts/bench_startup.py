"""Start-up time of the ``urpc`` command line, as ratios to ``python -c "import numpy"``.

Each command runs in a fresh interpreter, interleaved with the reference (``import numpy``) in
every round, so that the load of a shared machine hits both alike; the figures are the medians
over the rounds. The target (issue 11) is a ratio of at most 3 for ``urpc --help`` and for every
bad-input error.

    python scripts/bench_startup.py            # 15 rounds
    python scripts/bench_startup.py --rounds 30 --json
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

#: The target: at most this many times ``python -c "import numpy"``.
TARGET_RATIO = 3.0

#: (label, urpc arguments, counts against the target).
COMMANDS: tuple[tuple[str, tuple[str, ...], bool], ...] = (
    ("urpc --help", ("--help",), True),
    ("urpc simulate --help", ("simulate", "--help"), True),
    ("urpc init --help", ("init", "--help"), True),
    ("urpc nonsense (unknown command)", ("nonsense",), True),
    ("urpc simulate --bogus (unknown option)", ("simulate", "--bogus"), True),
    ("urpc check (missing argument)", ("check",), True),
    ("urpc campaign X --runs zero (bad value)", ("campaign", "x", "--runs", "zero"), True),
    ("urpc init ur10 (missing --out)", ("init", "ur10"), True),
    (
        "urpc init ur10 --out x --mass 10 (bad value)",
        ("init", "ur10", "--out", "x", "--mass", "10"),
        True,
    ),
    ("urpc robots", ("robots",), False),
)


def urpc_command() -> list[str]:
    """The installed ``urpc`` console script next to this interpreter, else ``python -m urpc``."""
    script = Path(sys.executable).with_name("urpc")
    if script.is_file():
        return [str(script)]
    found = shutil.which("urpc")
    return [found] if found else [sys.executable, "-m", "urpc"]


def wall_time(command: list[str]) -> float:
    """Wall-clock time [s] of one run of ``command`` (output discarded)."""
    start = time.perf_counter()
    subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.perf_counter() - start


def measure(rounds: int) -> dict:
    """Median wall times [s] and ratios to ``import numpy`` over interleaved rounds."""
    reference = [sys.executable, "-c", "import numpy"]
    urpc = urpc_command()
    commands = {
        "python -c 'import urpc'": [sys.executable, "-c", "import urpc"],
        **{label: [*urpc, *arguments] for label, arguments, _ in COMMANDS},
    }
    counted = {label for label, _, counts in COMMANDS if counts}
    for command in (reference, *commands.values()):  # warm the file cache
        wall_time(command)
    times: dict[str, list[float]] = {"import numpy": [], **{label: [] for label in commands}}
    for _ in range(rounds):
        for label, command in commands.items():
            times["import numpy"].append(wall_time(reference))
            times[label].append(wall_time(command))
    numpy_time = statistics.median(times["import numpy"])
    rows = []
    for label, values in times.items():
        median = statistics.median(values)
        rows.append(
            {
                "command": label,
                "median_s": median,
                "ratio": median / numpy_time,
                "counted": label in counted,
            }
        )
    worst = max(row["ratio"] for row in rows if row["counted"])
    return {
        "rounds": rounds,
        "urpc": " ".join(urpc),
        "import_numpy_s": numpy_time,
        "target_ratio": TARGET_RATIO,
        "worst_counted_ratio": worst,
        "met": worst <= TARGET_RATIO,
        "rows": rows,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=15, help="interleaved rounds (default 15)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    report = measure(max(1, args.rounds))
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(
        f"start-up, median of {report['rounds']} interleaved rounds; reference "
        f"python -c 'import numpy' = {1e3 * report['import_numpy_s']:.0f} ms"
    )
    print(f"  {'command':<48} {'median':>9} {'ratio':>7}")
    for row in report["rows"]:
        mark = "" if not row["counted"] else (" ok" if row["ratio"] <= TARGET_RATIO else " OVER")
        print(
            f"  {row['command']:<48} {1e3 * row['median_s']:>6.0f} ms {row['ratio']:>6.2f}x{mark}"
        )
    verdict = "met" if report["met"] else "NOT met"
    print(
        f"target: --help and bad-input errors <= {TARGET_RATIO:g}x import numpy: {verdict} "
        f"(worst {report['worst_counted_ratio']:.2f}x)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
