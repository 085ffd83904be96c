"""Latency of :meth:`urpc.robot.loop.ControlLoop.step` (the robot-side hot path: reference,
controller output and advance, one log row) next to one RNEA, per robot."""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin

from ...robot.loop import ControlLoop, percentiles
from .control_step import control_setup


def loop_latency(robot_name: str, steps: int = 20_000) -> dict[str, float]:
    """p50, p99, p99.9 and max [s] of ``steps`` consecutive loop steps on the robot's 1 kHz
    scenario (the state 2 epsilon off the reference, as :func:`control_setup`), and the median of
    one RNEA (``rnea``) timed the same way."""
    setup, controller, (_, q_offset, _, _, _) = control_setup(robot_name)
    loop = ControlLoop(controller, setup.trajectory, capacity=steps + 16)
    period = controller.sample_period
    offset = q_offset - setup.trajectory.reference(1.3).q
    for k in range(50):  # warm-up: compiled kernels, caches
        reference = setup.trajectory.reference(k * period)
        loop.step(k * period, reference.q + offset, reference.qd)
    loop.reset()
    references = [setup.trajectory.reference(k * period) for k in range(steps)]
    for k, reference in enumerate(references):
        loop.step(k * period, reference.q + offset, reference.qd)
    figures = loop.step_time_percentiles()
    robot = controller.robot
    data = robot.model.createData()
    config, zeros = robot.configuration(references[0].q), np.zeros(robot.dof)
    clock = time.perf_counter
    samples = np.empty(2000)
    for k in range(len(samples)):
        tic = clock()
        pin.rnea(robot.model, data, config, zeros, zeros)
        samples[k] = clock() - tic
    figures["rnea"] = percentiles(samples)["p50"]
    return figures


def format_latency(table: dict[str, dict[str, float]]) -> str:
    lines = [
        "| robot | step p50 [us] | p99 [us] | p99.9 [us] | max [us] | one RNEA [us] | p50 / RNEA |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name, f in table.items():
        lines.append(
            f"| {name} | {f['p50'] * 1e6:.1f} | {f['p99'] * 1e6:.1f} | {f['p99_9'] * 1e6:.1f} | "
            f"{f['max'] * 1e6:.1f} | {f['rnea'] * 1e6:.2f} | {f['p50'] / f['rnea']:.0f} |"
        )
    return "\n".join(lines)
