"""Issue 9's Table I check: the 8 vertices of the RR box at 1 kHz with the default (implicit) law.

    python scripts/table1_vertices.py [--workers 2] [--duration 10] [--out table.md]

Runs every vertex of ``robots/rr_planar/uncertainty.yaml`` (``box.vertex(i)``: bit 0 picks the
lower/upper m2, bit 1 lc2, bit 2 I2) from IC1 (``q0 = 0``) and IC2 (``q0 = 2 epsilon (1, -1)``),
``qd0 = 0``, under two disturbances of magnitude 10 N m held over each period: ``ball`` (drawn
uniformly in ``||d|| <= 10``, seed = the vertex index) and ``against`` (``d_k = -10 r_k/||r_k||``,
against the sliding variable), at 1 kHz, ``epsilon = 1e-2``, the default gains
(``urpc.synthesize``), the paper trajectory, 10 s. Then the paper's true plant
(``robots/rr_planar/true_parameters.yaml``, vertex 7) from IC1 at ``epsilon = 1e-3``, 1 kHz, 10 s,
under both disturbances. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

PERIOD = 1e-3
DISTURBANCE = 10.0
_CACHE: dict = {}


def _setup(epsilon: float):
    """Robot, box and controller for ``epsilon`` (built once per worker)."""
    if epsilon not in _CACHE:
        import urpc

        robot = urpc.load_robot("rr_planar")
        box = urpc.load_uncertainty("rr_planar", robot)
        controller = urpc.synthesize(robot, box, epsilon=epsilon, sample_period=PERIOD)
        _CACHE[epsilon] = (urpc, robot, box, controller)
    return _CACHE[epsilon]


def run(job: tuple) -> dict:
    """One run: ``(vertex index or 'true', ic, disturbance, epsilon, duration)``."""
    vertex, ic, disturbance, epsilon, duration = job
    urpc, robot, box, controller = _setup(epsilon)
    if vertex == "true":
        point = urpc.load_parameter_point("rr_planar", robot, box)
        seed = 7
    else:
        point, seed = box.vertex(vertex), vertex
    q0 = np.zeros(2) if ic == "IC1" else 2 * epsilon * np.array([1.0, -1.0])
    values = point["link2"]
    row = dict(
        vertex=str(vertex),
        m2=float(values[0]),
        lc2=float(values[1]),
        I2=float(values[6]),
        ic=ic,
        disturbance=disturbance,
        epsilon=epsilon,
    )
    tic = time.perf_counter()
    try:
        result = urpc.simulate(
            box.plant(robot, point),
            controller,
            urpc.PaperTrajectory(),
            duration=duration,
            q0=q0,
            disturbance_bound=DISTURBANCE,
            disturbance=disturbance,
            seed=seed,
        )
    except urpc.SimulationError as error:  # a diverged run is a result, not a crash
        row.update(met=False, entry_time=None, final_error=float("inf"), note=str(error)[:80])
    else:
        metrics = result.metrics
        row.update(
            met=bool(metrics["met"]),
            entry_time=metrics["entry_time"],
            final_error=float(metrics["final_error"]),
            phi=float(metrics["phi"]),
            note="",
        )
    row["wall_time"] = time.perf_counter() - tic
    return row


def jobs(duration: float) -> list[tuple]:
    """The 32 vertex runs and the 2 true-plant runs."""
    out = [
        (vertex, ic, disturbance, 1e-2, duration)
        for vertex in range(8)
        for ic in ("IC1", "IC2")
        for disturbance in ("ball", "against")
    ]
    out += [("true", "IC1", disturbance, 1e-3, duration) for disturbance in ("ball", "against")]
    return out


def table(rows: list[dict]) -> str:
    lines = [
        "| vertex | m2 [kg] | lc2 [m] | I2 [kg m^2] | IC | disturbance | epsilon [rad] | met "
        "| entry time [s] | final error [rad] | final/epsilon | phi final [N m s/rad] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        entry = "never" if r["entry_time"] is None else f"{r['entry_time']:.3f}"
        final = r["final_error"]
        cells = [
            "true plant (7)" if r["vertex"] == "true" else r["vertex"],
            f"{r['m2']:g}",
            f"{r['lc2']:g}",
            f"{r['I2']:.4g}",
            r["ic"],
            "ball" if r["disturbance"] == "ball" else "against r",
            f"{r['epsilon']:g}",
            "yes" if r["met"] else "**no**",
            entry,
            f"{final:.3e}",
            f"{final / r['epsilon']:.3f}",
            f"{r.get('phi', float('nan')):.3g}" + (f" ({r['note']})" if r["note"] else ""),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    vertex_rows = [r for r in rows if r["vertex"] != "true"]
    met = sum(r["met"] for r in vertex_rows)
    worst = max(r["final_error"] / r["epsilon"] for r in vertex_rows)
    lines.append("")
    lines.append(
        f"Vertices at epsilon = 1e-2: {met}/{len(vertex_rows)} met, worst final/epsilon "
        f"{worst:.3f}."
    )
    for r in rows:
        if r["vertex"] == "true":
            lines.append(
                f"True plant, IC1, epsilon = 1e-3, {r['disturbance']}: "
                f"{'met' if r['met'] else 'not met'}, entry "
                f"{'never' if r['entry_time'] is None else format(r['entry_time'], '.3f') + ' s'}, "
                f"final error {r['final_error']:.3e} rad."
            )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--duration", type=float, default=10.0, help="[s]")
    parser.add_argument("--out", help="also write the table to this file")
    args = parser.parse_args()
    start = time.perf_counter()
    work = jobs(args.duration)
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            rows = list(pool.map(run, work))
    else:
        rows = [run(job) for job in work]
    text = table(rows)
    text += (
        f"\n\n{len(rows)} runs of {args.duration:g} s at 1 kHz, {args.workers} workers, "
        f"{time.perf_counter() - start:.0f} s wall time."
    )
    print(text)
    if args.out:
        with open(args.out, "w") as handle:
            handle.write(text + "\n")


if __name__ == "__main__":
    main()
