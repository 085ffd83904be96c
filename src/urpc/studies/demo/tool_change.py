"""A payload change during a run: the true plant takes a heavier payload and the controller switches
to the new configuration's box (re-synthesized with the same gains) while keeping its internal
state, the integral ``s`` of ``f(||e||)`` behind ``phi`` and ``kappa``. The run continues from the
plant's state, on the same (time-shifted) trajectory, without a restart."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...control.base import Reference
from ...errors import InputError
from ...model.parameter_box import JOINTS
from ...model.uncertainty import ParameterBox
from ...sim.results import SimulationResult
from ...sim.simulation import simulate
from ...trajectories import Trajectory, generic_trajectory
from ..scenario import sample_true_parameters
from .configuration_run import describe_point, initial_position
from .progress import ProgressReporter
from .settings import (
    DISTURBANCE_BOUND,
    DURATION,
    EPSILON,
    SAMPLE_PERIOD,
    TOOL_CHANGE,
    ConfigurationLike,
    configuration_folders,
)
from .synthesis import SynthesizedArm, synthesize_configuration


class _Shifted(Trajectory):
    """``trajectory`` seen from a clock started at ``offset`` [s]: ``reference(t) =
    trajectory.reference(t + offset)``, so a continued run tracks the same motion."""

    def __init__(self, trajectory: Trajectory, offset: float):
        self.trajectory, self.offset = trajectory, float(offset)
        self.dof = trajectory.dof
        self.kind = getattr(trajectory, "kind", "shifted")

    def evaluate(self, t):
        return self.trajectory.evaluate(np.asarray(t, dtype=float) + self.offset)

    def reference(self, t: float) -> Reference:
        return self.trajectory.reference(t + self.offset)


@dataclass(frozen=True, eq=False)
class ToolChangeRun:
    """A run during which the payload changes and the controller switches boxes.

    Attributes:
        before, after: The configurations before and after the change.
        t_change: Time of the physical change [s].
        switch_delay: How long after the change the controller switches to the new box [s].
        segments: The simulations, each on its own clock starting at 0: before the change, then
            (with a delay) the new plant under the old controller, then the new controller.
        result: All segments as one run (at each switch the later segment's sample is kept).
        state_before, state_after: The controller state at the end of the old controller's last
            segment and the one the new controller starts from (equal: it is carried over).
        switch_time: Wall time [s] of composing, loading and synthesizing the new configuration
            (its ``synthesis_time``).
    """

    before: SynthesizedArm
    after: SynthesizedArm
    t_change: float
    switch_delay: float
    segments: tuple[SimulationResult, ...]
    result: SimulationResult
    state_before: np.ndarray
    state_after: np.ndarray
    switch_time: float

    @property
    def t_switch(self) -> float:
        """Time [s] at which the controller switches to the new box."""
        return self.t_change + self.switch_delay

    @property
    def reentry_time(self) -> float | None:
        """Time [s] after the change from which ``||e|| < epsilon`` holds to the end (0 when the
        error never left the ball), ``None`` when the run ends outside it."""
        t, error = self.result.t, self.result.error_norm
        after = t >= self.t_change - 1e-12
        outside = np.flatnonzero(after & ~(error < self.result.epsilon))
        if outside.size == 0:
            return 0.0
        if outside[-1] == len(t) - 1:
            return None
        return float(t[outside[-1] + 1] - self.t_change)

    def summary(self) -> dict[str, Any]:
        """JSON-ready: both configurations, the change, the re-entry and the metrics."""
        first, last = self.segments[0], self.segments[-1]
        t, error = self.result.t, self.result.error_norm
        reentry = self.reentry_time
        span_after = float(t[-1]) - self.t_change
        return {
            "before": {"name": self.before.name, "modules": list(self.before.modules)},
            "after": {"name": self.after.name, "modules": list(self.after.modules)},
            "drives": self.before.drives,
            "dof": self.before.dof,
            "t_change": self.t_change,
            "switch_delay": self.switch_delay,
            "switch_time": self.switch_time,
            "met_before": first.metrics["met"],
            "reentry_time": reentry,
            "met_after": reentry is not None and reentry <= 0.75 * span_after,
            "met": bool(
                first.metrics["met"] and reentry is not None and reentry <= 0.75 * span_after
            ),
            "max_error_after_change": float(error[t >= self.t_change - 1e-12].max()),
            "phi_at_switch": {
                "end_of_old_controller": float(self.segments[-2].diagnostics["phi"][-1]),
                "start_of_new_controller": float(last.diagnostics["phi"][0]),
            },
            "controller_state_at_switch": {
                "end_of_old_controller": self.state_before.tolist(),
                "start_of_new_controller": self.state_after.tolist(),
            },
            "before_metrics": first.metrics,
            "after_metrics": last.metrics,
            "metrics": self.result.metrics,
            "true_parameters": {"before": first.plant, "after": last.plant},
        }


def tool_change_run(
    before: ConfigurationLike = TOOL_CHANGE[0],
    after: ConfigurationLike = TOOL_CHANGE[1],
    *,
    t_change: float = 4.0,
    switch_delay: float = 0.0,
    duration: float = DURATION,
    epsilon: float = EPSILON,
    sample_period: float | None = SAMPLE_PERIOD,
    disturbance_bound: float = DISTURBANCE_BOUND,
    seed: int = 0,
    initial_offset: float | Sequence[float] | None = None,
    out_dir: str | Path | None = None,
    progress: Any = None,
) -> ToolChangeRun:
    """Simulate ``before`` until ``t_change`` [s], then change the payload and the controller's box.

    Both configurations are synthesized with the same default settings. The true plant after the
    change keeps the arm's drawn parameters (every body whose box is the same in both
    configurations, the joints' drives included) and draws the rest (the new payload) from the
    new box. At ``t_change + switch_delay`` the controller switches to the new configuration's
    controller (the new nominal model and bound, the same gains) without a restart: each segment
    starts from the previous one's last plant state ``(q, qd)`` and controller state
    (``controller_state0``: the integral behind ``phi`` and ``kappa`` is not reset), on the same
    trajectory shifted by the time already run, so the reference is continuous. The disturbance keeps being drawn (segment
    ``k`` seeds its generator with ``seed + k``).

    Args:
        before, after: Configurations (see :func:`synthesize_configuration`) with the same joints.
        t_change: Time of the payload change [s], inside ``(0, duration)``.
        switch_delay: Time [s] between the physical change and the controller's switch (0: the
            task program announces the new payload as it grasps it).
        duration: Simulated time of the whole run [s].
        epsilon, sample_period, disturbance_bound, seed, initial_offset: As
            :func:`run_configuration`.
        out_dir: Folder for both configurations' URDF and uncertainty files (default: temporary).
        progress: ``True``, a callable of the fraction done, or ``None``.

    Raises:
        InputError: an invalid configuration, configurations with different joints, or a change
            or switch time outside ``(0, duration)``.
        SimulationError: a segment diverged.
    """
    if not 0 < t_change < duration:
        raise InputError(
            f"t_change = {t_change!r} s must lie inside (0, duration = {duration!r} s)",
            field="t_change",
        )
    if not (switch_delay >= 0 and t_change + switch_delay < duration):
        raise InputError(
            f"switch_delay = {switch_delay!r} s must be >= 0 and end before the duration "
            f"{duration!r} s",
            field="switch_delay",
        )
    out = None if out_dir is None else Path(out_dir)
    folders = configuration_folders(out, [before, after])
    first = synthesize_configuration(
        before, epsilon=epsilon, out_dir=folders[0], sample_period=sample_period
    )
    second = synthesize_configuration(
        after, epsilon=epsilon, out_dir=folders[1], sample_period=sample_period
    )
    if second.robot.joint_names != first.robot.joint_names:
        raise InputError(
            f"a change during a run keeps the joints: '{first.name}' has "
            f"{', '.join(first.robot.joint_names)}, '{second.name}' has "
            f"{', '.join(second.robot.joint_names)}",
            field="after",
        )
    point_before = sample_true_parameters(first.box, seed)
    point_after = sample_true_parameters(second.box, seed + 1)
    # The arm and its drives do not change.
    kept = {k: v for k, v in point_before.links.items() if _same_box(first.box, second.box, k)}
    joints = point_before.joints
    if joints is None or not _same_box(first.box, second.box, JOINTS):
        joints = point_after.joints
    point_after = dataclasses.replace(
        point_after, links={**point_after.links, **kept}, joints=joints
    )
    plant_before = first.box.plant(point_before)
    plant_after = second.box.plant(point_after)
    joint_names = first.robot.joint_names
    described = {
        id(plant_before): f"{first.name}: {describe_point(point_before, joint_names)}",
        id(plant_after): f"{second.name}: {describe_point(point_after, joint_names)}",
    }
    plan = [(plant_before, first.controller, t_change)]
    if switch_delay > 0:
        plan.append((plant_after, first.controller, t_change + switch_delay))
    plan.append((plant_after, second.controller, duration))
    trajectory = generic_trajectory(first.nominal)
    segments: list[SimulationResult] = []
    clock, qd0, state = 0.0, None, None
    q0 = initial_position(trajectory, initial_offset)
    states = []
    with ProgressReporter(progress, "tool change", len(plan)) as report:
        for k, (plant, controller, stop) in enumerate(plan):
            if segments and controller is not plan[k - 1][1]:
                states.append(state)
            segment = simulate(
                plant,
                controller,
                _Shifted(trajectory, clock),
                duration=stop - clock,
                q0=q0,
                qd0=qd0,
                controller_state0=state,
                disturbance_bound=disturbance_bound,
                seed=seed + k,
                epsilon=epsilon,
                progress=report.part(k, len(plan)),
            ).labelled(scenario=f"{first.name} -> {second.name}", plant=described[id(plant)])
            segments.append(segment)
            clock += float(segment.t[-1])
            q0, qd0 = segment.q[-1], segment.qd[-1]
            state = np.asarray(segment.info["controller_state_final"], dtype=float)
    offsets = np.cumsum([0.0] + [float(segment.t[-1]) for segment in segments[:-1]])
    return ToolChangeRun(
        before=first,
        after=second,
        t_change=float(offsets[1]),
        switch_delay=float(offsets[-1] - offsets[1]),
        segments=tuple(segments),
        result=concatenate(segments, offsets),
        state_before=states[0],
        state_after=states[0].copy(),
        switch_time=second.timing.total,
    )


def concatenate(segments: Sequence[SimulationResult], offsets: Sequence[float]) -> SimulationResult:
    """Consecutive runs as one, segment ``k``'s clock shifted by ``offsets[k]`` [s]. At each
    switch the earlier segment's last sample (recorded, never applied) is dropped in favour of the
    later segment's first."""
    values: dict[str, Any] = {}
    last = len(segments) - 1

    def joined(name: str, parts: list[np.ndarray]) -> np.ndarray:
        pieces = []
        for k, (segment, part) in enumerate(zip(segments, parts, strict=True)):
            if part.shape[:1] == segment.t.shape:
                part = part if k == last else part[:-1]
                part = part + offsets[k] if name == "t" else part
            pieces.append(part)
        return np.concatenate(pieces)

    for item in dataclasses.fields(SimulationResult):
        parts = [getattr(segment, item.name) for segment in segments]
        if item.name == "diagnostics":
            values[item.name] = {
                name: joined(name, [part[name] for part in parts]) for name in parts[0]
            }
        elif isinstance(parts[0], np.ndarray):
            values[item.name] = joined(item.name, parts)
        else:
            values[item.name] = parts[0]
    values["duration"] = float(values["t"][-1] - values["t"][0])
    values["plant"] = " | ".join(
        f"from {offset:g} s: {segment.plant}"
        for offset, segment in zip(offsets, segments, strict=True)
    )
    values["wall_time"] = float(sum(segment.wall_time for segment in segments))
    values["step_time_median"] = float(np.median([s.step_time_median for s in segments]))
    values["info"] = {
        "segments": [segment.info for segment in segments],
        "offsets": [float(offset) for offset in offsets],
    }
    if "diagnostic_units" in segments[0].info:
        values["info"]["diagnostic_units"] = segments[0].info["diagnostic_units"]
    return SimulationResult(**values)


def _same_box(a: ParameterBox, b: ParameterBox, link: str) -> bool:
    """Whether a body (or, for :data:`JOINTS`, the joints' drives) has the same box in both."""
    if link == JOINTS:
        x, y = a.joints, b.joints
        return (
            x is not None
            and y is not None
            and x.joint_names == y.joint_names
            and all(
                np.array_equal(getattr(x, k), getattr(y, k)) for k in ("nominal", "lower", "upper")
            )
        )
    try:
        x, y = a.link_box(link), b.link_box(link)
    except KeyError:
        return False
    return (
        x.kind == y.kind
        and np.array_equal(x.lower, y.lower)
        and np.array_equal(x.upper, y.upper)
        and np.array_equal(x.nominal, y.nominal)
    )
