"""The reconfigurable-arm demo: controllers synthesized on the fly for modular arms.

Two demonstrations of the paper's closing promise (automatic synthesis for modular arms):

* :func:`reconfigure_demo` runs a sequence of arm configurations (default: the shipped assemblies
  ``arm_3dof``, ``arm_4dof``, ``arm_4dof_vacuum``) as if the arm were reassembled between runs.
  Each one is composed from its modules, loaded and given a controller with the same default
  settings (:func:`urpc.control.synthesis.synthesize` with ``epsilon`` only), then simulated sampled at
  1 kHz on a true plant drawn from its box, under an input disturbance the controller does not
  know. Its ``synthesis_time`` [s] is URDF composition + model load + controller construction.
* :func:`tool_change_run` changes the payload during a run: at ``t_change`` the true plant takes a
  heavier payload and the controller switches to the new configuration's box (re-synthesized with
  the same gains) while keeping its internal state, the integral ``s`` of ``f(||e||)`` behind
  ``phi`` and ``kappa``. The run continues from the plant's state, on the same (time-shifted)
  trajectory, without a restart.

Computation is separate from drawing: :func:`run_configuration` and :func:`tool_change_run` return
values, :func:`plot_reconfigure` and :func:`plot_tool_change` return matplotlib figures, and
:func:`reconfigure_demo` and :func:`tool_change_demo` run everything and write the files.
"""

from __future__ import annotations

import dataclasses
import gc
import json
import statistics
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..control.base import Controller, Reference
from ..control.synthesis import synthesize
from ..errors import InputError, SimulationError
from ..model.modular import TCP_LINK, Assembly, assemble, load_assembly, load_module_library
from ..model.robot import Robot
from ..model.uncertainty import ParameterBox
from ..sim.results import SimulationResult
from ..sim.simulation import simulate
from ..sim.trajectories import Trajectory, generic_trajectory, home_configuration
from .scenario import sample_true_parameters

#: The shipped assemblies the reconfiguration demo runs, in order.
DEFAULT_CONFIGURATIONS = ("arm_3dof", "arm_4dof", "arm_4dof_vacuum")
#: The tool-change demo: the gripper arm grasps a heavier object.
TOOL_CHANGE = ("arm_4dof", "arm_4dof_3kg")
#: Required tracking precision ``||q_d - q|| < epsilon`` [rad].
EPSILON = 1e-2
#: Control period [s] (1 kHz, zero-order hold).
SAMPLE_PERIOD = 1e-3
#: Radius [N m] of the ball the input disturbance is drawn from at every sample, unknown to the
#: controller: of the order of unmodelled joint friction of harmonic-drive joints of this size.
DISTURBANCE_BOUND = 2.0
#: Simulated time of one configuration [s].
DURATION = 8.0
#: How many times the synthesis of a configuration is repeated to time it (the median is kept).
TIMING_REPEATS = 5

#: A configuration: a shipped assembly name, an assembly file, a list of module names, or a
#: mapping ``{"name": ..., "modules": [...]}``.
ConfigurationLike = str | Path | Sequence[str] | Mapping[str, Any]


# ============================================================================ synthesis
@dataclass(frozen=True)
class SynthesisTiming:
    """Wall times [s] of building one configuration's controller (medians over ``repeats``).

    Attributes:
        compose: Module chain -> URDF and uncertainty files (:func:`urpc.model.modular.assemble`).
        load: URDF -> Pinocchio model and validated box (:meth:`Assembly.load`).
        controller: Robot and box -> controller (:func:`urpc.control.synthesis.synthesize`).
        total: Median of ``compose + load + controller`` (the ``synthesis_time``).
        total_min: Fastest of the repeats.
        repeats: Number of timed repeats.
    """

    compose: float
    load: float
    controller: float
    total: float
    total_min: float
    repeats: int


@dataclass(frozen=True, eq=False)
class SynthesizedArm:
    """One configuration, composed, loaded and given its controller.

    Attributes:
        name: Configuration name.
        assembly: The composed assembly (its URDF and uncertainty file are on disk).
        robot: The URDF model without payload (the true plant is built from it).
        box: The combined parameter box (disturbance unknown).
        nominal: The controller's nominal model (payload at its nominal point).
        controller: The interval passivity controller, default settings.
        timing: How long it took.
    """

    name: str
    assembly: Assembly
    robot: Robot
    box: ParameterBox
    nominal: Robot
    controller: Controller
    timing: SynthesisTiming

    @property
    def modules(self) -> tuple[str, ...]:
        return self.assembly.modules

    @property
    def dof(self) -> int:
        return self.robot.dof


def synthesize_configuration(
    configuration: ConfigurationLike,
    *,
    epsilon: float = EPSILON,
    out_dir: str | Path | None = None,
    repeats: int = TIMING_REPEATS,
    sample_period: float | None = SAMPLE_PERIOD,
) -> SynthesizedArm:
    """Compose, load and synthesize one configuration with the default settings, timed.

    The whole chain (``assemble`` or ``load_assembly``, ``Assembly.load``, ``synthesize``) runs
    ``repeats`` times, each timed with :func:`time.perf_counter`; the median is reported. The module
    library is read (and cached) before timing: it is read once when the arm software starts, not
    at each reconfiguration.

    Args:
        configuration: A shipped assembly name, an assembly file, a list of module names (base
            first) or a mapping with ``name`` and ``modules``.
        epsilon: Required precision [rad].
        out_dir: Folder for the composed URDF and uncertainty file (default: temporary).
        repeats: Timed repeats, >= 1.
        sample_period: The control period [s] the controller is synthesized for (its
            sampled-data gain limit); ``None`` for continuous time.

    Raises:
        InputError: an invalid configuration (see :func:`urpc.model.modular.assemble`).
    """
    if not (isinstance(repeats, int) and repeats >= 1):
        raise InputError(f"{repeats!r} must be an integer >= 1", field="repeats")
    compose = _composer(configuration, out_dir)
    load_module_library()  # cached: the timing below is that of a reconfiguration
    samples = []
    for _ in range(repeats):
        gc.collect()
        start = time.perf_counter()
        assembly = compose()
        composed = time.perf_counter()
        robot, box = assembly.load()
        loaded = time.perf_counter()
        controller = synthesize(robot, box, epsilon, sample_period=sample_period)
        done = time.perf_counter()
        samples.append((composed - start, loaded - composed, done - loaded, done - start))
    columns = [statistics.median(column) for column in zip(*samples, strict=True)]
    timing = SynthesisTiming(
        compose=columns[0],
        load=columns[1],
        controller=columns[2],
        total=columns[3],
        total_min=min(sample[3] for sample in samples),
        repeats=repeats,
    )
    return SynthesizedArm(
        name=assembly.name,
        assembly=assembly,
        robot=robot,
        box=box,
        nominal=box.nominal_robot(robot),
        controller=controller,
        timing=timing,
    )


def _composer(
    configuration: ConfigurationLike, out_dir: str | Path | None
) -> Callable[[], Assembly]:
    """A function composing the configuration (validated once, here)."""
    if isinstance(configuration, str | Path):
        composer = lambda: load_assembly(configuration, out_dir=out_dir)  # noqa: E731
    elif isinstance(configuration, Mapping):
        unknown = set(configuration) - {"name", "modules"}
        if unknown or "modules" not in configuration:
            raise InputError(
                f"a configuration mapping has 'modules' (required) and 'name', got "
                f"{sorted(map(str, configuration))}",
                field="configurations",
            )
        name = str(configuration.get("name", "assembly"))
        modules = configuration["modules"]
        composer = lambda: assemble(modules, name=name, out_dir=out_dir)  # noqa: E731
    elif isinstance(configuration, Sequence):
        modules = list(configuration)
        composer = lambda: assemble(modules, name="assembly", out_dir=out_dir)  # noqa: E731
    else:
        raise InputError(
            f"{configuration!r} is not a configuration: give an assembly name or file, a list of "
            "module names, or a mapping with 'name' and 'modules'",
            field="configurations",
        )
    composer()  # fail early on a bad configuration, and warm the imports of the first one
    return composer


def configuration_name(configuration: ConfigurationLike) -> str:
    """A name for a configuration before it is composed (for folders and messages)."""
    if isinstance(configuration, Path):
        return configuration.stem
    if isinstance(configuration, str):
        return Path(configuration).stem
    if isinstance(configuration, Mapping):
        return str(configuration.get("name", "assembly"))
    return "assembly"


# ============================================================================ one configuration
@dataclass(frozen=True, eq=False)
class ConfigurationRun:
    """One configuration of the demo: its synthesis and its closed-loop run.

    Attributes:
        arm: The synthesized configuration (assembly, models, controller, timing).
        plant: The true plant (a seeded, physically consistent draw from the box).
        true_point: The drawn parameters (link or payload -> coordinates of its box).
        trajectory: The desired trajectory (:func:`urpc.sim.trajectories.generic_trajectory`).
        result: The simulation, or ``None`` when it diverged.
        failure: Why the simulation stopped, when it diverged.
    """

    arm: SynthesizedArm
    plant: Robot
    true_point: dict[str, np.ndarray]
    trajectory: Trajectory
    result: SimulationResult | None
    failure: str | None = None

    @property
    def name(self) -> str:
        return self.arm.name

    def summary(self) -> dict[str, Any]:
        """JSON-ready: name, modules, dof, synthesis_time [s] and its parts, met, the metrics."""
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
        summary["true_parameters"] = _describe_point(self.true_point)
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
    plant = arm.box.plant(arm.robot, point)
    trajectory = generic_trajectory(arm.nominal)
    try:
        result = simulate(
            plant,
            arm.controller,
            trajectory,
            duration=duration,
            q0=_initial_position(trajectory, initial_offset),
            sample_period=sample_period,
            disturbance_bound=disturbance_bound,
            seed=seed,
            epsilon=epsilon,
            scenario=arm.name,
            plant_description=f"{arm.name}: {_describe_point(point)}",
            progress=progress,
        )
    except SimulationError as exc:
        return ConfigurationRun(arm, plant, point, trajectory, None, str(exc))
    return ConfigurationRun(arm, plant, point, trajectory, result)


# ============================================================================ the demo
def reconfigure_demo(
    out_dir: str | Path | None = None,
    *,
    configurations: Sequence[ConfigurationLike] | None = None,
    progress: bool | Callable[[float], Any] | None = None,
    duration: float = DURATION,
    epsilon: float = EPSILON,
    sample_period: float = SAMPLE_PERIOD,
    disturbance_bound: float = DISTURBANCE_BOUND,
    seed: int = 0,
    initial_offset: float | Sequence[float] | None = None,
    repeats: int = TIMING_REPEATS,
) -> dict[str, Any]:
    """Run a sequence of arm configurations, each synthesized on the fly with the same settings.

    Args:
        out_dir: Where to write ``reconfigure.png`` (the figure), ``reconfigure.json`` (the
            returned summary) and, per configuration, ``<name>/summary.json`` with the composed
            URDF and uncertainty file; ``None`` writes nothing.
        configurations: What to run, in order (see :func:`synthesize_configuration`); default
            :data:`DEFAULT_CONFIGURATIONS`.
        progress: ``True`` for a progress bar on stderr, a callable receiving the fraction done in
            ``[0, 1]``, or ``None``.
        duration: Simulated time per configuration [s].
        epsilon: Required precision [rad].
        sample_period: Control period [s].
        disturbance_bound: Radius of the disturbance ball [N m] (unknown to the controllers).
        seed: Seed of the true plants and of the disturbance draws.
        initial_offset: Initial position error [rad] (a number: the same on every joint);
            ``None`` starts on the reference.
        repeats: Timed repeats of each synthesis (the median is reported).

    Returns:
        ``{"configurations": [{"name", "modules", "dof", "synthesis_time", "met", ...metrics}],
        "settings": {...}, "figure": path or None}``.
    """
    configurations = list(DEFAULT_CONFIGURATIONS if configurations is None else configurations)
    if not configurations:
        raise InputError("give at least one configuration", field="configurations")
    out = None if out_dir is None else Path(out_dir)
    folders = _folders(out, configurations)
    runs = []
    with _ProgressReporter(progress, "reconfigure") as report:
        for i, (configuration, folder) in enumerate(zip(configurations, folders, strict=True)):
            runs.append(
                run_configuration(
                    configuration,
                    epsilon=epsilon,
                    sample_period=sample_period,
                    disturbance_bound=disturbance_bound,
                    duration=duration,
                    seed=seed,
                    initial_offset=initial_offset,
                    out_dir=folder,
                    repeats=repeats,
                    progress=report.part(i, len(configurations)),
                )
            )
    summary: dict[str, Any] = {
        "configurations": [run.summary() for run in runs],
        "settings": {
            "epsilon": epsilon,
            "sample_period": sample_period,
            "disturbance_bound": disturbance_bound,
            "disturbance_known": False,
            "duration": duration,
            "seed": seed,
            "initial_offset": initial_offset,
            "timing_repeats": repeats,
            "controller": "interval, default gains (synthesize(robot, box, epsilon, sample_period))",
        },
        "figure": None,
    }
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        figure_path = out / "reconfigure.png"
        plot_reconfigure(runs, epsilon=epsilon).savefig(figure_path, dpi=110)
        summary["figure"] = str(figure_path)
        for folder, entry in zip(folders, summary["configurations"], strict=True):
            _write_json(folder / "summary.json", entry)
        _write_json(out / "reconfigure.json", summary)
    return summary


def _folders(out: Path | None, configurations: Sequence[ConfigurationLike]) -> list[Path | None]:
    """``out/<name>`` per configuration (``out/<k>_<name>`` when names repeat)."""
    if out is None:
        return [None] * len(configurations)
    names = [configuration_name(c) for c in configurations]
    if len(set(names)) < len(names):
        names = [f"{k + 1}_{name}" for k, name in enumerate(names)]
    return [out / name for name in names]


# ============================================================================ tool change
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
                "end_of_old_controller": float(self.segments[-2].phi[-1]),
                "start_of_new_controller": float(last.phi[0]),
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
    configurations) and draws the rest (the new payload) from the new box. At
    ``t_change + switch_delay`` the controller switches to the new configuration's controller (the
    new nominal model and bound, the same gains) without a restart: each segment starts from the
    previous one's last plant state ``(q, qd)`` and controller state (``controller_state0``: the
    integral behind ``phi`` and ``kappa`` is not reset), on the same trajectory shifted by the
    time already run, so the reference is continuous. The disturbance keeps being drawn (segment
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
    folders = _folders(out, [before, after])
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
    for link, values in point_before.items():  # the arm itself does not change
        if _same_box(first.box, second.box, link):
            point_after[link] = values
    plant_before = first.box.plant(first.robot, point_before)
    plant_after = second.box.plant(second.robot, point_after)
    described = {
        id(plant_before): f"{first.name}: {_describe_point(point_before)}",
        id(plant_after): f"{second.name}: {_describe_point(point_after)}",
    }
    plan = [(plant_before, first.controller, t_change)]
    if switch_delay > 0:
        plan.append((plant_after, first.controller, t_change + switch_delay))
    plan.append((plant_after, second.controller, duration))
    trajectory = generic_trajectory(first.nominal)
    segments: list[SimulationResult] = []
    clock, qd0, state = 0.0, None, None
    q0 = _initial_position(trajectory, initial_offset)
    states = []
    with _ProgressReporter(progress, "tool change") as report:
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
                sample_period=sample_period,
                disturbance_bound=disturbance_bound,
                seed=seed + k,
                epsilon=epsilon,
                scenario=f"{first.name} -> {second.name}",
                plant_description=described[id(plant)],
                progress=report.part(k, len(plan)),
            )
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
    for item in dataclasses.fields(SimulationResult):
        parts = [getattr(segment, item.name) for segment in segments]
        if not isinstance(parts[0], np.ndarray):
            values[item.name] = parts[0]
            continue
        pieces = []
        for k, (segment, part) in enumerate(zip(segments, parts, strict=True)):
            if part.shape[:1] == segment.t.shape:
                part = part if k == last else part[:-1]
                part = part + offsets[k] if item.name == "t" else part
            pieces.append(part)
        values[item.name] = np.concatenate(pieces)
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
    return SimulationResult(**values)


def tool_change_demo(
    out_dir: str | Path | None = None,
    *,
    progress: bool | Callable[[float], Any] | None = None,
    before: ConfigurationLike = TOOL_CHANGE[0],
    after: ConfigurationLike = TOOL_CHANGE[1],
    t_change: float = 4.0,
    switch_delay: float = 0.0,
    duration: float = DURATION,
    seed: int = 0,
    initial_offset: float | Sequence[float] | None = None,
) -> dict[str, Any]:
    """Run :func:`tool_change_run` with the demo's settings; write ``tool_change.png`` and
    ``tool_change.json`` into ``out_dir`` (nothing when ``None``); return the summary."""
    run = tool_change_run(
        before,
        after,
        t_change=t_change,
        switch_delay=switch_delay,
        duration=duration,
        seed=seed,
        initial_offset=initial_offset,
        out_dir=out_dir,
        progress=progress,
    )
    summary = run.summary()
    summary["figure"] = None
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        figure_path = out / "tool_change.png"
        plot_tool_change(run).savefig(figure_path, dpi=110)
        summary["figure"] = str(figure_path)
        _write_json(out / "tool_change.json", summary)
    return summary


def _initial_position(
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


def _same_box(a: ParameterBox, b: ParameterBox, link: str) -> bool:
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


# ============================================================================ figures
_KIND_COLORS = {"link": "0.45", "tool": "tab:orange", "actuator": "0.2", "base": "0.3"}


def plot_reconfigure(runs: Sequence[ConfigurationRun], *, epsilon: float | None = None) -> Figure:
    """For each configuration, a side view of the arm where its run starts (``q_d(0)``; the home
    pose in light grey) above its error norm ``||e||`` [rad] (log scale) with the ``epsilon``
    line."""
    figure = Figure(figsize=(3.6 * len(runs), 6.4), layout="constrained")
    grid = figure.add_gridspec(2, len(runs), height_ratios=(1.15, 1.0))
    for i, run in enumerate(runs):
        drawing = figure.add_subplot(grid[0, i])
        draw_arm(drawing, run.arm, run.trajectory.reference(0.0).q)
        ms = 1e3 * run.arm.timing.total
        drawing.set_title(
            f"{run.name} ({run.arm.dof} DOF)\nsynthesized in {ms:.1f} ms", fontsize=10
        )
        axes = figure.add_subplot(grid[1, i])
        eps = epsilon if run.result is None else run.result.epsilon
        if run.result is None:
            axes.text(0.5, 0.5, "diverged", ha="center", va="center", transform=axes.transAxes)
            axes.set_yscale("log")
            axes.set_ylim(1e-5, 1.0)
        else:
            _error_norm_axes(axes, run.result.t, run.result.error_norm, eps)
            axes.set_title("met" if run.result.metrics["met"] else "not met", fontsize=10)
        if eps is not None:
            axes.axhline(eps, color="tab:red", ls="--", lw=1.0, label=r"$\varepsilon$")
        if i == 0:
            axes.set_ylabel(r"$\|e\|$ [rad]")
            axes.legend(loc="upper right", fontsize="small")
        axes.set_xlabel("time [s]")
    first = next((run.result for run in runs if run.result is not None), None)
    if first is not None and first.sample_period is not None:
        figure.suptitle(
            "Reconfigurable arm: each controller synthesized on the fly with the default "
            f"settings; {1 / first.sample_period:g} Hz, unknown disturbance "
            rf"$\|d\| \leq$ {first.disturbance_bound:g} N m (grey: home pose)",
            fontsize=10,
        )
    return figure


def plot_tool_change(run: ToolChangeRun) -> Figure:
    """The error norm of the whole run (log scale) with ``epsilon`` and the change marked, above
    the gain ``phi``."""
    result = run.result
    figure = Figure(figsize=(7.5, 5.0), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    _error_norm_axes(top, result.t, result.error_norm, result.epsilon)
    top.axhline(result.epsilon, color="tab:red", ls="--", lw=1.0, label=r"$\varepsilon$")
    for axes in (top, bottom):
        axes.axvline(run.t_change, color="k", lw=1.0, ls=":")
        if run.switch_delay > 0:
            axes.axvline(run.t_switch, color="tab:purple", lw=1.0, ls=":")
    reentry = run.reentry_time
    if reentry is None:
        status = "not back below epsilon"
    elif reentry == 0:
        status = "error stayed below epsilon"
    else:
        status = f"back below epsilon after {reentry * 1e3:.0f} ms"
    top.text(
        run.t_change,
        0.04,
        f"  payload change {run.before.name} -> {run.after.name}\n  {status}",
        transform=top.get_xaxis_transform(),
        va="bottom",
        fontsize=9,
    )
    top.set_ylabel(r"$\|e\|$ [rad]")
    top.legend(loc="upper left", fontsize="small")
    bottom.plot(result.t, result.phi, color="tab:blue")
    bottom.set_ylabel(r"$\phi$ [N m s/rad]")
    bottom.set_xlabel("time [s]")
    bottom.grid(True, alpha=0.3)
    figure.suptitle("Payload change during a run: same controller state, new box", fontsize=11)
    return figure


def _error_norm_axes(axes: Axes, t: np.ndarray, error_norm: np.ndarray, epsilon: float) -> None:
    floor = 1e-6  # [rad]; a zero error has no logarithm
    axes.semilogy(t, np.maximum(error_norm, floor), lw=0.8, color="tab:blue", label=r"$\|e\|$")
    axes.set_ylim(bottom=max(floor, 0.5 * float(np.min(np.maximum(error_norm[1:], floor)))))
    axes.set_ylim(top=max(2.0 * epsilon, 1.5 * float(np.max(error_norm))))
    axes.grid(True, which="both", alpha=0.3)


def draw_arm(
    axes: Axes, arm: SynthesizedArm, q: np.ndarray | None = None, *, show_home: bool = True
) -> None:
    """A side view of an assembly at ``q`` [rad] (default: home, the middle of the joint limits),
    with the home pose as a light outline when ``show_home`` and ``q`` differs from it.

    Flange and module-frame positions come from Pinocchio's forward kinematics. The view looks
    along the first horizontal joint axis at ``q`` (the shoulder pitch of an anthropomorphic
    arm). Links and tools are lines from input to output flange, joints circles (large ones for
    large actuators), the TCP a cross and the payload a square at its nominal center of mass.
    """
    robot = arm.robot
    home = home_configuration(robot)
    q = home if q is None else np.asarray(q, dtype=float)
    horizontal, vertical = _side_view(robot, robot.configuration(q))

    def project(point: np.ndarray) -> tuple[float, float]:
        return float(point @ horizontal), float(point @ vertical)

    if show_home and not np.allclose(q, home):
        segments, joints, _ = _skeleton(arm, home, project)
        for _, _, points in segments:
            axes.plot(*zip(*points, strict=True), color="0.85", lw=3.0, solid_capstyle="butt")
        for _, (x, y) in joints:
            axes.plot(x, y, "o", ms=6, mfc="white", mec="0.75", mew=1.0)
    segments, joints, tcp = _skeleton(arm, q, project)
    for kind, _, points in segments:
        width = {"base": 9.0, "actuator": 6.0, "tool": 4.0}.get(kind, 3.0)
        axes.plot(
            *zip(*points, strict=True),
            color=_KIND_COLORS.get(kind, "0.45"),
            lw=width,
            solid_capstyle="butt",
        )
    for module, (x, y) in joints:
        size = 11 if arm.assembly.library[module].joint.effort >= 100 else 8
        axes.plot(x, y, "o", ms=size, mfc="white", mec="k", mew=1.5, zorder=3)
    x, y = project(tcp.translation)
    axes.plot(x, y, "x", ms=7, color="tab:orange", mew=2, zorder=4)
    for payload in arm.box.payloads:
        values = arm.box.link_box(payload.name).nominal
        px, py = project(tcp.act(np.asarray(values[1:4], dtype=float)))
        axes.plot(px, py, "s", ms=6 + 3 * float(values[0]), color="tab:green", zorder=4)
        axes.annotate(
            f"{values[0]:g} kg", (px, py), xytext=(9, 4), textcoords="offset points", fontsize=8
        )
    tool = next((p.module for p in arm.assembly.parts if p.kind == "tool"), None)
    if tool is not None:
        axes.annotate(tool, (x, y), xytext=(9, -12), textcoords="offset points", fontsize=8)
    axes.axhline(0.0, color="0.6", lw=1.0)
    axes.set_aspect("equal", adjustable="datalim")
    axes.margins(0.2)
    axes.set_xlabel("[m]")
    axes.tick_params(labelsize=8)


def _skeleton(
    arm: SynthesizedArm, q: np.ndarray, project: Callable[[np.ndarray], tuple[float, float]]
) -> tuple[list, list, pin.SE3]:
    """Projected ``(kind, module, flange points)`` per module, ``(module, point)`` per joint, and
    the TCP placement, at ``q``."""
    model = arm.robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, arm.robot.configuration(q))
    segments, joints = [], []
    for part in arm.assembly.parts:
        if part.kind == "payload":
            continue
        module = arm.assembly.library[part.module]
        frame = data.oMf[model.getFrameId(part.link)]
        points = [
            (frame * connector.placement).translation
            for connector in (module.proximal, module.distal)
            if connector is not None
        ]
        if part.kind == "base":
            points.insert(0, frame.translation)
        segments.append((part.kind, part.module, [project(p) for p in points]))
        if part.kind == "actuator":
            joints.append((part.module, project(frame.translation)))
    return segments, joints, data.oMf[model.getFrameId(TCP_LINK)].copy()


def _side_view(robot: Robot, configuration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (horizontal, vertical) of the drawing plane: the plane normal to the first
    horizontal joint axis (world frame), or the world x-z plane."""
    model = robot.model
    data = model.createData()
    vertical = np.array([0.0, 0.0, 1.0])
    pin.computeJointJacobians(model, data, configuration)
    for joint in range(1, model.njoints):
        column = model.joints[joint].idx_v
        jacobian = pin.getJointJacobian(model, data, joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        axis = jacobian[3:, column]
        if np.linalg.norm(axis) > 0.5 and abs(axis @ vertical) < 0.5:
            horizontal = np.cross(axis, vertical)
            return horizontal / np.linalg.norm(horizontal), vertical
    return np.array([1.0, 0.0, 0.0]), vertical


# ============================================================================ helpers
def _describe_point(point: Mapping[str, np.ndarray]) -> str:
    return "; ".join(
        f"{name}: " + ", ".join(f"{value:.6g}" for value in np.asarray(values))
        for name, values in point.items()
    )


def _write_json(path: Path, payload: Mapping[str, Any]) -> None:
    from ..cli.common import jsonable

    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(json.dumps(jsonable(dict(payload)), indent=2, allow_nan=False) + "\n")
    partial.replace(path)


class _ProgressReporter:
    """One progress bar over several simulations: :meth:`part` gives the ``i``-th of ``n``
    simulations a callable for ``simulate(progress=...)``."""

    def __init__(self, progress: Any, description: str):
        self._bar = None
        self._callback = None
        self._done = 0.0
        if progress is True:
            from tqdm import tqdm

            self._bar = tqdm(
                total=100,
                file=sys.stderr,
                leave=False,
                desc=description,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}",
            )
        elif callable(progress):
            self._callback = progress
        elif progress not in (None, False):
            raise InputError(
                f"{progress!r} is not a progress reporter; give True, False, None or a callable",
                field="progress",
            )

    def __enter__(self) -> _ProgressReporter:
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._bar is not None:
            self._bar.close()

    def part(self, index: int, count: int) -> Callable[[float], None] | None:
        if self._bar is None and self._callback is None:
            return None
        return lambda fraction: self._update((index + fraction) / count)

    def _update(self, fraction: float) -> None:
        fraction = min(max(fraction, 0.0), 1.0)
        if fraction <= self._done:
            return
        if self._bar is not None:
            self._bar.update(100.0 * (fraction - self._done))
        if self._callback is not None:
            self._callback(fraction)
        self._done = fraction
