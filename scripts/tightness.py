"""Tightness of the bound methods: width(enclosure) / width(sampled inner hull), per box and method.

    python scripts/tightness.py                 # print the table
    python scripts/tightness.py --write-docs    # also replace the table in docs/bounds.md
    python scripts/tightness.py --arms          # the table over example-robot-data arms
    python scripts/tightness.py --arms --write-docs

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
ARM_MARKERS = ("<!-- tightness-arms:begin -->", "<!-- tightness-arms:end -->")

#: example-robot-data arms of the per-arm table, with the joints they need locked.
ARMS = {
    "ur3": (),
    "ur5": (),
    "ur10": (),
    "panda": ("panda_finger_joint1", "panda_finger_joint2"),
    "kinova": (),
    "xarm7": (),
    "z1": (),
    "so100": (),
    "so101": (),
}


def arm_box(robot, rng):
    """A physical box on every link with mass: mass +-10-50 %, CoM +-1-5 cm per axis, inertia
    about the CoM +-20 % (diagonal), drawn per link; and a 0-2 kg payload on the last link with its
    CoM 0-10 cm along its z axis."""
    links = [n for n in robot.moving_link_names if robot.link(n).inertia.mass > 0]
    entries = {}
    for name in links:
        com = rng.uniform(0.01, 0.05)
        entries[name] = {
            "mass": f"{rng.uniform(10, 50):.0f}%",
            **{f"com_{a}": f"+-{com:.3f}" for a in "xyz"},
            **{f"i{a}{a}": "20%" for a in "xyz"},
        }
    payload = {"link": links[-1], "mass": [0, 2], "com_z": [0, 0.1]}
    return parse_uncertainty({"links": entries, "payload": payload}, robot)


def arm_table(n_states: int, n_samples: int, methods: list[str]) -> str:
    """Median / worst width ratio per arm and method (:func:`arm_box` boxes, seed 0 per arm)."""
    import numpy as np

    from urpc.model.robot import load_robot

    lines = [
        "| arm | dof | uncertain coordinates | " + " | ".join(methods) + " |",
        "|---|---|---|" + "---|" * len(methods),
    ]
    worst = dict.fromkeys(methods, 0.0)
    for name, locked in ARMS.items():
        print(f"{name} ...", file=sys.stderr, flush=True)
        robot = load_robot(name, locked_joints=list(locked))
        box = arm_box(robot, np.random.default_rng(sum(map(ord, name))))
        result = tightness(robot, box, methods, n_states, n_samples, n_samples)
        cells = [f"{result[m].median:.3f} / {result[m].worst:.3f}" for m in methods]
        for m in methods:
            worst[m] = max(worst[m], result[m].worst)
        lines.append(f"| {name} | {robot.dof} | {box.n_uncertain} | " + " | ".join(cells) + " |")
    lines.append(
        "| **worst over the arms** | | | " + " | ".join(f"{worst[m]:.3f}" for m in methods) + " |"
    )
    return "\n".join(lines)


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
    parser.add_argument("--arms", action="store_true", help="the per-arm table (ARMS)")
    parser.add_argument("--methods", nargs="+", default=["hull", "vertex", "vertex-plain"])
    args = parser.parse_args(argv)
    if args.arms:
        text = arm_table(args.states, args.samples, args.methods)
        caption = (
            f"width(enclosure) / width(sampled hull), median / worst over {args.states} random "
            f"states and the joints, {args.samples} uniform samples, {args.samples} random vertices "
            "and the assembled extremes per joint (`python scripts/tightness.py --arms`)"
        )
        print(caption + "\n\n" + text)
        if args.write_docs:
            _replace(ARM_MARKERS, f"{caption}:\n\n{text}")
        return 0
    text = table(args.states, args.samples)
    caption = (
        f"width(enclosure) / width(sampled hull), median / worst over {args.states} random "
        f"states and the joints, {args.samples} uniform samples plus the vertices "
        "(`python scripts/tightness.py`)"
    )
    print(caption + "\n\n" + text)
    if args.write_docs:
        _replace(MARKERS, f"{caption}:\n\n{text}")
    return 0


def _replace(markers: tuple[str, str], body: str) -> None:
    """Replace the text between ``markers`` in :data:`DOCS`."""
    document = DOCS.read_text()
    pattern = re.compile(re.escape(markers[0]) + ".*?" + re.escape(markers[1]), re.S)
    if not pattern.search(document):
        raise SystemExit(f"{DOCS} has no {markers[0]} ... {markers[1]} block")
    block = f"{markers[0]}\n{body}\n{markers[1]}"
    DOCS.write_text(pattern.sub(lambda _: block, document))


if __name__ == "__main__":
    raise SystemExit(main())
