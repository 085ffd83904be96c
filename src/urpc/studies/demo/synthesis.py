"""One configuration composed, loaded and given its controller, timed: the synthesis of the
reconfiguration demo (``synthesis_time`` [s] = URDF composition + model load + controller
construction)."""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...control.base import Controller
from ...control.synthesis import synthesize
from ...errors import InputError
from ...model.modular import Assembly, assemble, load_assembly, load_module_library
from ...model.robot import Robot
from ...model.uncertainty import ParameterBox
from .settings import EPSILON, SAMPLE_PERIOD, TIMING_REPEATS, ConfigurationLike


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

    @property
    def drives(self) -> dict[str, dict[str, Any]]:
        """JSON-ready, per joint with a drive: its module and the drive's armature [kg m^2],
        damping [N m s/rad] and friction [N m], each a nominal and an interval."""
        library = self.assembly.library
        return {
            part.joint: {"module": part.module, **library[part.module].drive.describe()}
            for part in self.assembly.parts
            if part.kind == "actuator" and library[part.module].drive is not None
        }


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
            implicit sampled-data law); ``None`` for continuous time.

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
