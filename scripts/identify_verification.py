"""Verification of ``urpc identify`` (docs/identification.md): coverage over random plants and
noise, width ratios, time per identification, and least squares' +-3 sigma intervals side by side.

Each trial draws a rigid payload from the UR5's shipped payload box (rejecting non-rigid draws),
records it along the excitation trajectory of ``urpc identify --excite ur5 --payload tool0`` with
torque noise within the bound, identifies in payload mode, and checks whether the truth lies in
the box (every physical field and the 10 standard parameters). Least squares on the same data:
the estimate with ``+-3 sigma`` from ``sigma^2 (W^T W)^-1``, ``sigma^2`` from the residuals.
Two noises, both within the bound: ``uniform`` and ``biased`` (a constant sensor offset of 80 %
of the bound plus 20 % uniform).

    python scripts/identify_verification.py --trials 200 --samples 500 --json out.json
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import urpc
from urpc.identify import excite, identify, record
from urpc.identify.problem import Problem
from urpc.model.inertia import inertia_problem
from urpc.model.parameter_box import barycentric_from_physical, inertia_from_physical


def draw_payload(box, rng):
    while True:
        values = rng.uniform(box.lower, box.upper)
        if not inertia_problem(np.asarray(inertia_from_physical(values).inertia)):
            return values


def least_squares(robot, prior, samples, noise, payload):
    problem = Problem(robot, prior, samples, np.full(robot.dof, noise), [payload], False)
    W, r = problem.regressor_matrix()
    theta, *_ = np.linalg.lstsq(W, r, rcond=None)
    dof = W.shape[0] - W.shape[1]
    sigma2 = float(np.sum((r - W @ theta) ** 2) / dof)
    covariance = sigma2 * np.linalg.inv(W.T @ W)
    half = 3 * np.sqrt(np.diag(covariance))
    return theta - half, theta + half


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200)
    parser.add_argument("--samples", type=int, default=500)
    parser.add_argument("--noise", type=float, default=0.5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json")
    args = parser.parse_args()
    robot = urpc.load_robot("ur5")
    prior = urpc.load_uncertainty("ur5", robot)
    box = prior.link_box("payload")
    trajectory = excite(robot, payload="tool0").trajectory
    times = np.linspace(0, 10, args.samples, endpoint=False)
    rng = np.random.default_rng(args.seed)
    figures = {}
    for kind in ("uniform", "biased"):
        covered = covered_standard = ls_missed = 0
        ls_missed_fields = np.zeros(10)
        seconds, ratios = [], {}
        for _ in range(args.trials):
            true = draw_payload(box, rng)
            plant = prior.plant(robot, {"payload": true})
            samples = record(plant, trajectory, times, args.noise, rng, kind=kind)
            start = time.perf_counter()
            result = identify(
                robot, prior, samples, args.noise, payload="tool0", standard_parameters=True
            )
            seconds.append(time.perf_counter() - start)
            covered += result.contains({"payload": true})
            standard = barycentric_from_physical(true)
            lo, hi = result.standard["payload"]
            covered_standard += bool(np.all((lo <= standard) & (standard <= hi)))
            for group, ratio in result.mean_width_ratios().items():
                ratios.setdefault(group, []).append(ratio)
            ls_lo, ls_hi = least_squares(robot, prior, samples, args.noise, "payload")
            miss = (standard < ls_lo) | (standard > ls_hi)
            ls_missed += bool(miss.any())
            ls_missed_fields += miss
        figures[kind] = {
            "trials": args.trials,
            "samples": args.samples,
            "noise": args.noise,
            "box_covers_truth": covered,
            "box_covers_standard_parameters": covered_standard,
            "mean_width_ratio": {g: float(np.mean(v)) for g, v in ratios.items()},
            "max_width_ratio": {g: float(np.max(v)) for g, v in ratios.items()},
            "seconds_median": float(np.median(seconds)),
            "seconds_max": float(np.max(seconds)),
            "least_squares_3sigma_missed_trials": ls_missed,
            "least_squares_3sigma_missed_per_parameter": ls_missed_fields.tolist(),
        }
        print(kind, json.dumps(figures[kind], indent=1), flush=True)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as stream:
            json.dump(figures, stream, indent=2)


if __name__ == "__main__":
    main()
