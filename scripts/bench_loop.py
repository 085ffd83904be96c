"""Latency of the robot control loop's step (p50 / p99 / p99.9 / max) next to one RNEA, for the
RR arm, the UR5 and the Panda (docs/robot.md, "Figures").

    python scripts/bench_loop.py              # 20000 steps per robot
    python scripts/bench_loop.py --steps 5000 --json
"""

from __future__ import annotations

import argparse
import json

from urpc.studies.benchmark.loop_latency import format_latency, loop_latency
from urpc.studies.benchmark.machine import machine_info


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--robots", default="rr_planar,ur5,panda")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    table = {name: loop_latency(name, args.steps) for name in args.robots.split(",")}
    if args.json:
        print(json.dumps({"machine": machine_info(), "loop_step": table}, indent=2))
    else:
        print(format_latency(table))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
