"""Scenario settings: everything one simulation run needs, read from one YAML file.

The format (:class:`urpc.formats.scenario.ScenarioFile`) is documented in ``docs/scenarios.md``;
the paper's six runs are shipped in ``robots/rr_planar/scenarios/``. Loading
(:func:`load_scenario`) only validates and stores the settings in a frozen :class:`Scenario`;
:mod:`urpc.studies.scenario.setup` turns them into objects and :mod:`urpc.studies.scenario.run`
synthesizes and simulates. Relative paths in a file are resolved against the file's folder.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

from ... import names
from ...errors import InputError, did_you_mean
from ...formats import scenario as schema
from ...formats.base import read_yaml, validate
from ...model.catalog import builtin_root
from ...wording import count

#: Controllers a scenario can run.
CONTROLLERS: tuple[str, ...] = names.CONTROLLERS
#: Top-level keys of a scenario file.
SCENARIO_KEYS: tuple[str, ...] = tuple(schema.ScenarioFile.model_fields)
#: Plant backends a scenario can simulate with (``urpc.sim.plants.PLANTS``).
PLANT_BACKENDS = names.PLANT_BACKENDS
#: Where the flags of :meth:`Scenario.with_overrides` come from, in error messages.
OVERRIDE_SOURCE = "command-line override"


# ============================================================================ values
@dataclass(frozen=True)
class TrueParameters:
    """Where the true plant's parameters come from.

    Attributes:
        kind: ``"file"`` (a parameter-point file), ``"sample"`` (a seeded uniform draw from the
            box, physically consistent) or ``"nominal"`` (the true plant is the nominal model).
        file: The parameter-point file (kind ``file``).
        seed: Seed of the draw (kind ``sample``); ``None`` uses the scenario's ``seed``.
    """

    kind: Literal["file", "sample", "nominal"]
    file: Path | None = None
    seed: int | None = None


@dataclass(frozen=True)
class TrajectorySpec:
    """A trajectory kind (``paper``, ``sinusoid``, ``quintic``) and its options (see the docs)."""

    kind: str
    options: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True)
class InitialCondition:
    """The initial state; what is not given follows the reference at ``t = 0``.

    Attributes:
        q0: Joint positions [rad]; ``None``: ``q_d(0) + offset``.
        qd0: Joint velocities [rad/s]; ``None``: ``qd_d(0)``.
        offset: Offset from ``q_d(0)`` [rad] (only without ``q0``); ``None``: zero.
    """

    q0: tuple[float, ...] | None = None
    qd0: tuple[float, ...] | None = None
    offset: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Scenario:
    """One simulation run, as read from a scenario file (units in brackets).

    Attributes:
        name: Scenario name (default: the file stem).
        robot: Built-in or example-robot-data name, or an absolute URDF path.
        uncertainty: The uncertainty file (the controller's knowledge).
        true_parameters: Where the true plant's parameters come from.
        trajectory: The desired trajectory.
        initial_condition: The initial state.
        sample_period: Control period [s] (zero-order hold); ``None`` for continuous time.
        disturbance: Bound on the input disturbance ``||d||`` [N m] (0: none); the controller does
            not know it unless the uncertainty file states it.
        epsilon: Required tracking precision ``||q_d - q|| < epsilon`` [rad].
        controller: The controller that runs (one of :data:`CONTROLLERS`).
        controller_options: Options of each controller (keyword arguments of its synthesis).
        duration: Simulated time [s].
        seed: Seed of the disturbance draws (and of a sampled true plant without its own seed).
        torque_limit: Per-joint torque bound [N m] (a number or one per joint); ``None``: none.
        plant: Backend simulating the true plant (one of :data:`PLANT_BACKENDS`); ``mujoco``
            needs a sampled run.
        actuation_delay: Samples between a state and the period its torque acts over on the
            plant (:func:`urpc.simulate`'s ``actuation_delay``); ``None``: the delay the law
            predicts over (the interval law's ``delay`` option, else 0).
        locked_joints: Joints removed from the model: names (locked at 0) or name -> position.
        description: Free text.
        source: The file the scenario was read from.
    """

    name: str
    robot: str
    uncertainty: Path
    true_parameters: TrueParameters = TrueParameters("sample")
    trajectory: TrajectorySpec = TrajectorySpec("sinusoid")
    initial_condition: InitialCondition = InitialCondition()
    sample_period: float | None = 1e-3
    disturbance: float = 0.0
    epsilon: float = 1e-2
    controller: str = "interval"
    controller_options: Mapping[str, Mapping[str, Any]] = field(
        default_factory=lambda: MappingProxyType(
            {name: MappingProxyType({}) for name in CONTROLLERS}
        )
    )
    duration: float = 10.0
    seed: int = 0
    torque_limit: float | tuple[float, ...] | None = None
    plant: str = "pinocchio"
    actuation_delay: int | None = None
    locked_joints: tuple[str, ...] | Mapping[str, float] = ()
    description: str = ""
    source: Path | None = None

    @property
    def options(self) -> Mapping[str, Any]:
        """The options of the controller that runs."""
        return self.controller_options[self.controller]

    @property
    def continuous(self) -> bool:
        return self.sample_period is None

    def with_overrides(self, **flags: Any) -> Scenario:
        """A copy with some fields replaced; ``None`` values are ignored (flags not given).

        Values are validated like file entries; relative paths are resolved against the current
        directory. ``controller_options`` entries are merged per controller.

        Raises:
            InputError: an unknown field (with the closest name) or an invalid value.
        """
        given = {key: value for key, value in flags.items() if value is not None}
        document = self.to_dict()
        if self.true_parameters.kind == "sample" and self.true_parameters.seed is None:
            document["true_parameters"] = "sample"  # keeps following the scenario's seed
        options = given.pop("controller_options", None)
        if isinstance(options, Mapping):
            merged = document["controller_options"]
            for name, values in options.items():
                merged[name] = {**merged.get(name, {}), **(values or {})}
        elif options is not None:
            document["controller_options"] = options
        document.update(given)
        context = {"base": Path.cwd()}
        spec = validate(schema.ScenarioFile, document, OVERRIDE_SOURCE, context=context)
        return _checked(_scenario(spec, self.source), OVERRIDE_SOURCE)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (YAML/JSON-ready) with the scenario file's keys; paths absolute."""
        true = self.true_parameters
        if true.kind == "file":
            true_doc: Any = str(true.file)
        elif true.kind == "sample":
            true_doc = {"sample": {"seed": self.seed if true.seed is None else true.seed}}
        else:
            true_doc = "nominal"
        ic = self.initial_condition
        return {
            "name": self.name,
            "description": self.description,
            "robot": self.robot,
            "locked_joints": _plain(self.locked_joints),
            "uncertainty": str(self.uncertainty),
            "true_parameters": true_doc,
            "trajectory": {"kind": self.trajectory.kind, **_plain(self.trajectory.options)},
            "initial_condition": {
                k: list(v) for k, v in (("q0", ic.q0), ("qd0", ic.qd0), ("offset", ic.offset)) if v
            }
            or "at_reference",
            "sample_period": "continuous" if self.sample_period is None else self.sample_period,
            "disturbance": self.disturbance,
            "epsilon": self.epsilon,
            "controller": self.controller,
            "controller_options": _plain(self.controller_options),
            "duration": self.duration,
            "seed": self.seed,
            "torque_limit": _plain(self.torque_limit),
            "plant": self.plant,
            "actuation_delay": self.actuation_delay,
        }


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return value


# ============================================================================ loading
def shipped_scenarios() -> dict[str, Path]:
    """Scenarios shipped with the built-in robot data (``robots/<robot>/scenarios/*.yaml``), by
    name ``<robot>/<file stem>`` (``rr_planar/s1_ic1``). They ship inside the package, so they are
    found after a plain ``pip install`` too."""
    root = builtin_root()
    return {
        f"{path.parent.parent.name}/{path.stem}": path
        for path in sorted(root.glob("*/scenarios/*.yaml"))
    }


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file (a path, or a shipped name such as ``rr_planar/s2_ic1``).

    Raises:
        InputError: naming the file and the field: a missing file, bad YAML, an unknown key (with
            the closest valid one), a wrong type, a non-positive ``epsilon``, ``duration`` or
            ``sample_period``, an unknown controller or trajectory kind.
    """
    path = Path(path)
    if not path.is_file():
        shipped = shipped_scenarios()
        name = path.as_posix().removesuffix(".yaml")
        if name not in shipped:
            raise InputError(
                "no such scenario file or shipped scenario; " + did_you_mean(name, shipped),
                source=path,
            )
        path = shipped[name]
    document = read_yaml(path)
    return parse_scenario(document, source=path)


def parse_scenario(document: Any, source: str | Path | None = None) -> Scenario:
    """Validate a scenario document (parsed YAML); relative paths are resolved against the
    folder of ``source`` (the current directory without one)."""
    base = Path(source).resolve().parent if source is not None else Path.cwd()
    spec = validate(schema.ScenarioFile, document, source, context={"base": base})
    path = None if source is None else Path(source)
    return _checked(_scenario(spec, path), None if source is None else str(source))


def _scenario(spec: schema.ScenarioFile, source: Path | None) -> Scenario:
    """The :class:`Scenario` of a validated file."""
    true = spec.true_parameters
    if isinstance(true, Path):
        true_parameters = TrueParameters("file", file=true)
    elif isinstance(true, schema.ParameterFile):
        true_parameters = TrueParameters("file", file=true.file)
    elif isinstance(true, schema.SampledParameters):
        seed = None if true.sample is None else true.sample.seed
        true_parameters = TrueParameters("sample", seed=seed)
    else:
        true_parameters = TrueParameters(true)
    trajectory = spec.trajectory
    if isinstance(trajectory, str):
        trajectory_spec = TrajectorySpec(trajectory)
    else:
        options = trajectory.model_dump(exclude_unset=True, exclude={"kind"})
        if isinstance(options.get("path"), Path):  # plain data, like the other options
            options["path"] = str(options["path"])
        trajectory_spec = TrajectorySpec(trajectory.kind, MappingProxyType(options))
    ic = spec.initial_condition
    initial = InitialCondition() if isinstance(ic, str) else InitialCondition(**dict(ic))
    locked = spec.locked_joints or ()
    return Scenario(
        name=spec.name or (source.stem if source is not None else "scenario"),
        robot=spec.robot,
        uncertainty=spec.uncertainty,
        true_parameters=true_parameters,
        trajectory=trajectory_spec,
        initial_condition=initial,
        sample_period=spec.sample_period,
        disturbance=spec.disturbance,
        epsilon=spec.epsilon,
        controller=spec.controller,
        controller_options=_freeze_options(
            {
                field.alias or key: getattr(spec.controller_options, key).model_dump(
                    exclude_unset=True
                )
                for key, field in schema.ControllerOptions.model_fields.items()
                if getattr(spec.controller_options, key) is not None
            }
        ),
        duration=spec.duration,
        seed=spec.seed,
        torque_limit=spec.torque_limit,
        plant=spec.plant,
        actuation_delay=spec.actuation_delay,
        locked_joints=MappingProxyType(locked) if isinstance(locked, Mapping) else tuple(locked),
        description=spec.description,
        source=source,
    )


def _freeze_options(options: Mapping[str, Mapping[str, Any]]) -> Mapping[str, Mapping[str, Any]]:
    full = {name: MappingProxyType(_frozen(options.get(name, {}))) for name in CONTROLLERS}
    return MappingProxyType(full)


def _frozen(options: Mapping[str, Any]) -> dict[str, Any]:
    return {k: MappingProxyType(v) if isinstance(v, Mapping) else v for k, v in options.items()}


def _checked(scenario: Scenario, source: str | None) -> Scenario:
    """``scenario``, after the checks that combine fields."""

    def error(message: str, fieldname: str) -> InputError:
        return InputError(message, source=source, field=fieldname)

    if scenario.sample_period is not None and scenario.sample_period > scenario.duration:
        raise error(
            f"the sample period {scenario.sample_period:g} s is longer than the duration "
            f"{scenario.duration:g} s",
            "sample_period",
        )
    if scenario.sample_period is None and scenario.plant != "pinocchio":
        raise error(
            f"the {scenario.plant} plant steps under a held torque: give a sample_period [s], or "
            "use plant: pinocchio for continuous time",
            "plant",
        )
    if scenario.sample_period is None and scenario.actuation_delay:
        raise error(
            f"an actuation delay of {count(scenario.actuation_delay, 'sample')} needs samples: "
            "give a sample_period [s], or set actuation_delay to 0 for continuous time",
            "actuation_delay",
        )
    if scenario.sample_period is None and scenario.disturbance > 0:
        raise error(
            "the disturbance is drawn once per control sample: give a sample_period [s] or set "
            "disturbance to 0 for continuous time",
            "disturbance",
        )
    return scenario
