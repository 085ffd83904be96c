"""Why the joints' terms matter: one arm whose true plant has armature, damping and Coulomb
friction, controlled once with a box that ignores them (the rigid links only, urpc before issue 12)
and once with the full box, side by side (docs/joint-dynamics.md).

    python scripts/joint_friction_comparison.py [--scenario ur5/joint_friction] [--out DIR]

For each controller: the run's figures (met, entry time, final error, peak torque), the
certificate, and how often the true mismatch ``w`` of the plant leaves the controller's
enclosure along the run (the bound is only sound when it never does). Writes
``DIR/comparison.png`` (tracking error of both runs) and ``DIR/comparison.md`` (the table).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import urpc
from urpc.model.joint_dynamics import STICTION_VELOCITY, friction_shape
from urpc.studies.certification import certify_setup
from urpc.studies.scenario import build, build_controller, load_scenario, simulate_setup


def escapes(setup, controller, result) -> tuple[int, int, float]:
    """Samples where the plant's true ``w`` leaves the controller's enclosure, the samples
    checked, and the largest excess [N m]. The true ``w`` uses the plant's joint terms with the
    plant's own (regularized) friction, the mismatch the run really met."""
    plant, nominal = setup.plant, controller.bound.robot
    Kr = controller.Kr
    _, damping, friction = plant.joint_parameters
    _, damping0, friction0 = nominal.joint_parameters
    count = excess_max = 0
    step = max(1, len(result.t) // 400)
    indices = range(0, len(result.t), step)
    for k in indices:
        q, qd = result.q[k], result.qd[k]
        e, ed = result.q_desired[k] - q, result.qd_desired[k] - qd
        reference = setup.trajectory.reference(result.t[k])
        qd_a, qdd_a = reference.qd + Kr * e, reference.qdd + Kr * ed
        lower, upper = controller.bound.enclose(q, qd, qd_a, qdd_a)
        w = (
            (plant.M(q) - nominal.M(q)) @ qdd_a
            + (plant.C(q, qd) - nominal.C(q, qd)) @ qd_a
            + plant.g(q)
            - nominal.g(q)
            + damping * qd
            - damping0 * qd_a
            + friction * friction_shape(qd, STICTION_VELOCITY)
            - friction0 * friction_shape(qd_a, STICTION_VELOCITY)
        )
        excess = float(max(np.max(lower - w), np.max(w - upper), 0.0))
        count += excess > 0
        excess_max = max(excess_max, excess)
    return count, len(indices), excess_max


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="ur5/joint_friction")
    parser.add_argument("--out", type=Path, default=Path("urpc-results/joint-friction"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    scenario = load_scenario(args.scenario)
    full = build(scenario)
    # The same plant, controlled with the links' box only (the joints' box dropped).
    rigid_box = dataclasses.replace(full.box, joints=None)
    urdf = urpc.load_robot(scenario.robot, locked_joints=scenario.locked_joints)
    robot = full.robot.with_joint_parameters(urdf.joint_parameters)  # the URDF's drives only
    rigid = dataclasses.replace(full, box=rigid_box, robot=robot)
    rows, results = [], {}
    for label, setup in (("links only (joints ignored)", rigid), ("links and joints", full)):
        controller = build_controller(setup)
        result = simulate_setup(setup, controller)
        certificate = certify_setup(setup, controller)
        count, checked, excess = escapes(setup, controller, result)
        m = result.metrics
        rows.append(
            f"| {label} | {'yes' if m['met'] else 'no'} | {m['entry_time']:.3g} | "
            f"{m['final_error']:.3g} | {np.abs(result.torque).max():.3g} | "
            f"{'yes' if certificate.certified else 'no'} ({certificate.epsilon_floor:.3g}) | "
            f"{count}/{checked} (max {excess:.3g} N m) |"
        )
        results[label] = result
    table = "\n".join(
        [
            f"{args.scenario}, epsilon = {scenario.epsilon:g} rad, "
            f"{1 / scenario.sample_period:g} Hz, true plant: {full.true_description}",
            "",
            "| box of the controller | met | entry [s] | final error [rad] | peak torque [N m] "
            "| certified (floor [rad]) | w outside the enclosure |",
            "|---|---|---|---|---|---|---|",
            *rows,
        ]
    )
    (args.out / "comparison.md").write_text(table + "\n")
    print(table)
    figure, axis = plt.subplots(figsize=(8, 4), constrained_layout=True)
    for label, result in results.items():
        axis.semilogy(result.t, result.error_norm, label=label)
    axis.axhline(scenario.epsilon, color="k", linestyle="--", label="epsilon")
    axis.set_ylim(bottom=scenario.epsilon / 100)
    axis.set_xlabel("time [s]")
    axis.set_ylabel("||q_d - q|| [rad]")
    axis.set_title(f"{args.scenario}: the same plant, two boxes")
    axis.legend()
    figure.savefig(args.out / "comparison.png", dpi=100)
    print(f"saved {args.out / 'comparison.png'} and {args.out / 'comparison.md'}")


if __name__ == "__main__":
    main()
