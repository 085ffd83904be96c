"""One configuration of the reconfiguration demo: synthesized on the fly, then simulated on a true
plant drawn from its box under a disturbance the controller does not know."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError, SimulationError
from ...model.point import ParameterPoint
from ...model.robot import Robot
from ...sim.results import SimulationResult
from ...sim.simulation import simulate
from ...trajectories import Trajectory, generic_trajectory
from ..scenario import sample_true_parameters
from .settings import (
    DISTURBANCE_BOUND,
    DURATION,
    EPSILON,
    SAMPLE_PERIOD,
    TIMING_REPEATS,
    ConfigurationLike,
)
from .synthesis import SynthesizedArm, synthesize_configuration


@dataclass(frozen=True, eq=False)
class ConfigurationRun:
    """One configuration of the demo: its synthesis and its closed-loop run.

    Attributes:
        arm: The synthesized configuration (assembly, models, controller, timing).
        plant: The true plant (a seeded, physically consistent draw from the box).
        true_point: The drawn parameters (link or payload -> coordinates of its box, and the
            drawn ``(3, dof)`` drives).
        trajectory: The desired trajectory (:func:`urpc.trajectories.generic_trajectory`).
        result: The simulation, or ``None`` when it diverged.
        failure: Why the simulation stopped, when it diverged.
    """

    arm: SynthesizedArm
    plant: Robot
    true_point: ParameterPoint
    trajectory: Trajectory
    result: SimulationResult | None
    failure: str | None = None

    @property
    def name(self) -> str:
        return self.arm.name

    def summary(self) -> dict[str, Any]:
        """JSON-ready: name, modules, dof, synthesis_time [s] and its parts, met, the metrics, the
        drives of the joints (nominal and interval) and the drawn true parameters."""
        timing = self.arm.timing
        summary: dict[str, Any] = {
            "name": self.arm.name,
            "modules": list(self.arm.modules),
            "dof": self.arm.dof,
            "synthesis_time": timing.total,
            "synthesis_time_min": timing.total_min,
            "compose_time": timing.compose,
            "load_time": timing.load,
            "controller_time": timing.controller,
            "bound_method": getattr(self.arm.controller, "method", None),
        }
        if self.result is None:
            summary.update(met=False, diverged=True, failure=self.failure)
        else:
            metrics = self.result.metrics
            summary["met"] = metrics["met"]
            summary.update({k: v for k, v in metrics.items() if k != "met"})
            summary["diverged"] = False
        summary["drives"] = self.arm.drives
        summary["true_parameters"] = describe_point(self.true_point, self.arm.robot.joint_names)
        summary["urdf"] = str(self.arm.assembly.urdf_path)
        return summary


def run_configuration(
    configuration: ConfigurationLike,
    *,
    epsilon: float = EPSILON,
    sample_period: float | None = SAMPLE_PERIOD,
    disturbance_bound: float = DISTURBANCE_BOUND,
    duration: float = DURATION,
    seed: int = 0,
    initial_offset: float | Sequence[float] | None = None,
    out_dir: str | Path | None = None,
    repeats: int = TIMING_REPEATS,
    progress: Any = None,
) -> ConfigurationRun:
    """Synthesize one configuration on the fly (default settings) and simulate it.

    The true plant is a seeded uniform draw from the configuration's box, redrawn until every body
    is physical (:func:`urpc.studies.scenario.sample_true_parameters`); the trajectory is the generic
    sinusoid of the nominal model, starting at rest on the reference (or ``initial_offset`` [rad],
    a number or one per joint, away from it); the control is sampled with period
    ``sample_period`` [s] (zero-order hold; ``None``: continuous time, no disturbance) and the
    plant input carries a disturbance drawn per sample in the ball
    ``||d|| <= disturbance_bound`` [N m], unknown to the controller.

    A diverging simulation does not raise: the run has ``result=None`` and ``failure`` says why.
    """
    arm = synthesize_configuration(
        configuration,
        epsilon=epsilon,
        out_dir=out_dir,
        repeats=repeats,
        sample_period=sample_period,
    )
    point = sample_true_parameters(arm.box, seed, str(arm.assembly.uncertainty_path))
    plant = arm.box.plant(point)
    trajectory = generic_trajectory(arm.nominal)
    try:
        result = simulate(
            plant,
            arm.controller,
            trajectory,
            duration=duration,
            q0=initial_position(trajectory, initial_offset),
            disturbance_bound=disturbance_bound,
            seed=seed,
            epsilon=epsilon,
            progress=progress,
        ).labelled(
            scenario=arm.name,
            plant=f"{arm.name}: {describe_point(point, arm.robot.joint_names)}",
        )
    except SimulationError as exc:
        return ConfigurationRun(arm, plant, point, trajectory, None, str(exc))
    return ConfigurationRun(arm, plant, point, trajectory, result)


def initial_position(
    trajectory: Trajectory, offset: float | Sequence[float] | None
) -> np.ndarray | None:
    """``q_d(0) + offset`` [rad], or ``None`` (start on the reference) without an offset."""
    if offset is None:
        return None
    q0 = trajectory.reference(0.0).q
    try:
        return q0 + np.broadcast_to(np.asarray(offset, dtype=float), q0.shape)
    except ValueError:
        raise InputError(
            f"{offset!r}: give one number or {len(q0)} numbers [rad]", field="initial_offset"
        ) from None


def describe_point(
    point: ParameterPoint | Mapping[str, np.ndarray], joint_names: Sequence[str] = ()
) -> str:
    """One line: each body's drawn coordinates, then each joint's drawn drive (armature
    [kg m^2], damping [N m s/rad], friction [N m]) when the point has joint parameters."""
    point = ParameterPoint.coerce(point)
    parts = [
        f"{name}: " + ", ".join(f"{value:.6g}" for value in np.ravel(values))
        for name, values in point.links.items()
    ]
    if point.joints is not None:
        values = point.joints
        names = list(joint_names) or [f"joint {k + 1}" for k in range(values.shape[-1])]
        parts += [
            f"{name} drive: armature {a:.6g} kg m^2, damping {d:.6g} N m s/rad, "
            f"friction {f:.6g} N m"
            for name, (a, d, f) in zip(names, values.reshape(3, -1).T, strict=True)
        ]
    return "; ".join(parts)
