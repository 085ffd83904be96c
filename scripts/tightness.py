"""Tightness of the bound methods: width(enclosure) / width(sampled inner hull), per box and method.

    python scripts/tightness.py                 # print the table
    python scripts/tightness.py --write-docs    # also replace the table in docs/bounds.md

The sampled inner hull is the range of ``w`` over uniform draws of the box plus all its vertices
(random vertices when there are more than 1024), each sample a plant built with Pinocchio
(:func:`urpc.studies.benchmark.tightness`). A ratio is >= 1 for a sound method; joints the box cannot move
are left out. Takes a minute or two.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from urpc.bounds import METHODS
from urpc.model.catalog import default_uncertainty
from urpc.model.uncertainty import load_uncertainty, parse_uncertainty
from urpc.studies.benchmark import benchmark_box, benchmark_robot, tightness

DOCS = Path(__file__).resolve().parents[1] / "docs" / "bounds.md"
MARKERS = ("<!-- tightness:begin -->", "<!-- tightness:end -->")

#: A barycentric UR5 box (what identification tools output), 8 uncertain coordinates.
UR5_BARYCENTRIC = {
    "links": {
        "forearm_link": {"barycentric": {"m": "10%", "h_z": "+-0.05", "I_yy": "20%"}},
        "wrist_2_link": {"barycentric": {"m": "10%", "h_x": "+-0.01", "h_y": "+-0.01"}},
        "wrist_3_link": {"barycentric": {"m": "10%", "I_zz": "30%", "h_z": "+-0.002"}},
    }
}


def cases():
    """``(label, robot, box)`` of the table."""
    rr, ur5, panda = (benchmark_robot(name) for name in ("rr_planar", "ur5", "panda"))
    yield "rr_planar, Table I (link 2: m, lc2, I2)", rr, benchmark_box(rr)
    yield (
        "ur5, shipped box (wrist masses, 0-3 kg payload)",
        ur5,
        load_uncertainty(default_uncertainty("ur5"), ur5),
    )
    yield "ur5, all 6 links (benchmark box)", ur5, benchmark_box(ur5)
    yield (
        "panda, shipped box (wrist masses, 0-3 kg payload)",
        panda,
        load_uncertainty(default_uncertainty("panda"), panda),
    )
    yield "ur5, barycentric box (3 links)", ur5, parse_uncertainty(UR5_BARYCENTRIC, ur5)


def table(n_states: int, n_samples: int) -> str:
    methods = ["hull", "vertex", "vertex-plain"] + (["rigorous"] if "rigorous" in METHODS else [])
    lines = [
        "| box | uncertain coordinates | " + " | ".join(methods) + " |",
        "|---|---|" + "---|" * len(methods),
    ]
    for label, robot, box in cases():
        print(f"{label} ...", file=sys.stderr, flush=True)
        result = tightness(robot, box, methods, n_states, n_samples, n_samples)
        cells = [f"{result[m].median:.3f} / {result[m].worst:.3f}" for m in methods]
        lines.append(f"| {label} | {box.n_uncertain} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=20, help="random states per box")
    parser.add_argument("--samples", type=int, default=300, help="uniform draws (and vertices)")
    parser.add_argument("--write-docs", action="store_true", help=f"update {DOCS}")
    args = parser.parse_args(argv)
    text = table(args.states, args.samples)
    caption = (
        f"width(enclosure) / width(sampled hull), median / worst over {args.states} random "
        f"states and the joints, {args.samples} uniform samples plus the vertices "
        "(`python scripts/tightness.py`)"
    )
    print(caption + "\n\n" + text)
    if args.write_docs:
        document = DOCS.read_text()
        pattern = re.compile(re.escape(MARKERS[0]) + ".*?" + re.escape(MARKERS[1]), re.S)
        block = f"{MARKERS[0]}\n{caption}:\n\n{text}\n{MARKERS[1]}"
        DOCS.write_text(pattern.sub(lambda _: block, document))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
