"""Latency of :meth:`urpc.robot.loop.ControlLoop.step` (the robot-side hot path: reference,
controller output and advance, one log row) next to one RNEA, per robot: the ``loop step`` rows
of ``urpc bench`` and the table of ``urpc bench loop`` (``docs/robot.md``, "Figures").

Unlike the suite's thread-CPU-time figures, these are wall-clock times (``time.perf_counter``,
as :class:`~urpc.robot.loop.ControlLoop` measures its own steps), because a robot's deadline is
wall-clock: the tail (p99, p99.9, max) includes the scheduler's preemptions and is only worth
quoting from an idle machine. p99.9 needs a few thousand steps to be more than the largest few
samples."""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin

from ...errors import InputError
from ...robot.loop import ControlLoop, percentiles
from .control_step import control_setup

#: Keys of one :func:`loop_latency` row.
LATENCY_KEYS = ("p50", "p99", "p99_9", "max", "rnea", "steps")
#: Steps per robot of ``urpc bench`` (``--loop-steps``) and ``urpc bench loop`` (``--steps``).
DEFAULT_LOOP_STEPS = 3000


def loop_latency(robot_name: str, steps: int = DEFAULT_LOOP_STEPS) -> dict[str, float]:
    """``p50``, ``p99``, ``p99_9`` and ``max`` [s] of ``steps`` consecutive loop steps on the
    robot's 1 kHz scenario (the state 2 epsilon off the reference, as :func:`control_setup`),
    ``rnea``, the median of one nominal ``pin.rnea`` of the same arm timed the same way [s], and
    ``steps``.

    Raises:
        InputError: a robot without a control scenario, or ``steps < 1``.
    """
    if steps < 1:
        raise InputError(f"{steps} must be >= 1", field="steps")
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
    figures["steps"] = steps
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
