"""Scenario files: everything one simulation run needs, in one YAML file.

The format is documented in ``docs/scenarios.md``; the paper's six runs are shipped in
``robots/rr_planar/scenarios/``. Loading (:func:`load_scenario`) only validates and stores the settings in a
frozen :class:`Scenario`; :func:`build` turns them into objects (robot, box, true plant,
trajectory, initial state), :func:`build_controller` synthesizes the controller, and
:func:`run_scenario` simulates. Relative paths in a file are resolved against the file's folder.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from ..control.base import Controller
from ..errors import InputError, did_you_mean
from ..expressions import evaluate
from ..model.catalog import builtin_root
from ..model.robot import Robot, inertia_problem, load_robot
from ..model.uncertainty import (
    UNITS,
    ParameterBox,
    load_parameter_point,
    load_uncertainty,
    read_yaml,
)
from ..sim.plants import PLANTS
from ..sim.trajectories import (
    TRAJECTORY_KINDS,
    PaperTrajectory,
    QuinticTrajectory,
    SinusoidTrajectory,
    Trajectory,
    generic_trajectory,
)

#: Controllers a scenario can run.
CONTROLLERS = ("interval", "r-alpha", "computed-torque")
#: Top-level keys of a scenario file.
SCENARIO_KEYS = (
    "name", "description", "robot", "locked_joints", "uncertainty", "true_parameters",
    "trajectory", "initial_condition", "sample_period", "disturbance", "epsilon", "controller",
    "controller_options", "duration", "seed", "torque_limit", "plant",
)  # fmt: skip
#: Plant backends a scenario can simulate with (``urpc.sim.plants.PLANTS``).
PLANT_BACKENDS = tuple(PLANTS)
#: Folder of the scenarios shipped with the source tree.

_TRAJECTORY_OPTIONS = {
    "paper": ("amplitude",),
    "sinusoid": ("home", "amplitude", "frequency", "phase", "amplitude_fraction",
                 "velocity_fraction"),
    "quintic": ("points", "times", "home", "segment_duration", "amplitude_fraction",
                "velocity_fraction"),
}  # fmt: skip
_R_ALPHA_OPTIONS = (
    "r", "alpha", "Lambda", "Q", "eta", "betas", "n_samples", "seed", "disturbance_bound",
    "q_range",
)  # fmt: skip
_COMPUTED_TORQUE_OPTIONS = ("natural_frequency", "damping")


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
        context = _Context("command-line override", Path.cwd())
        changes: dict[str, Any] = {}
        for key, value in flags.items():
            if value is None:
                continue
            if key not in SCENARIO_KEYS:
                raise InputError(
                    f"unknown scenario field '{key}'; " + did_you_mean(key, SCENARIO_KEYS),
                    source=context.source,
                    field=key,
                )
            if key == "controller_options":
                merged = {k: dict(v) for k, v in self.controller_options.items()}
                for name, options in _parse_controller_options(value, context).items():
                    merged[name].update(options)
                changes[key] = _freeze_options(merged)
            else:
                changes[key] = _PARSERS[key](value, context)
        updated = dataclasses.replace(self, **changes)
        _check_consistency(updated, context)
        return updated

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
    context = _Context(None if source is None else str(source), base)
    if not isinstance(document, Mapping):
        raise InputError(
            f"a scenario is a mapping of keys ({', '.join(SCENARIO_KEYS)}), got "
            f"{type(document).__name__}",
            source=context.source,
        )
    for key in document:
        if str(key) not in SCENARIO_KEYS:
            raise InputError(
                f"unknown key '{key}'; " + did_you_mean(str(key), SCENARIO_KEYS),
                source=context.source,
                field=str(key),
            )
    for key in ("robot", "uncertainty"):
        if document.get(key) is None:
            raise InputError(f"'{key}' is required", source=context.source, field=key)
    values: dict[str, Any] = {}
    for key, raw in document.items():
        key = str(key)
        if key == "controller_options":
            values[key] = _freeze_options(_parse_controller_options(raw, context))
        elif raw is not None or key == "torque_limit":
            values[key] = _PARSERS[key](raw, context)
    if "name" not in values:
        values["name"] = Path(source).stem if source is not None else "scenario"
    scenario = Scenario(**values, source=None if source is None else Path(source))
    _check_consistency(scenario, context)
    return scenario


@dataclass(frozen=True)
class _Context:
    source: str | None
    base: Path

    def error(self, message: str, fieldname: str) -> InputError:
        return InputError(message, source=self.source, field=fieldname)


def _check_consistency(scenario: Scenario, context: _Context) -> None:
    if scenario.controller not in CONTROLLERS:
        raise context.error(
            f"unknown controller '{scenario.controller}'; "
            + did_you_mean(scenario.controller, CONTROLLERS),
            "controller",
        )
    if scenario.sample_period is not None and scenario.sample_period > scenario.duration:
        raise context.error(
            f"the sample period {scenario.sample_period:g} s is longer than the duration "
            f"{scenario.duration:g} s",
            "sample_period",
        )
    if scenario.sample_period is None and scenario.plant != "pinocchio":
        raise context.error(
            f"the {scenario.plant} plant steps under a held torque: give a sample_period [s], or "
            "use plant: pinocchio for continuous time",
            "plant",
        )
    if scenario.sample_period is None and scenario.disturbance > 0:
        raise context.error(
            "the disturbance is drawn once per control sample: give a sample_period [s] or set "
            "disturbance to 0 for continuous time",
            "disturbance",
        )


# ---------------------------------------------------------------------------- field parsers
def _number(value: Any, context: _Context, fieldname: str, expected: str = "a number") -> float:
    number = None
    if isinstance(value, int | float) and not isinstance(value, bool):
        number = float(value)
    elif isinstance(value, str):
        try:
            number = evaluate(value)
        except ValueError:
            number = None
    if number is None or not math.isfinite(number):
        raise context.error(f"{value!r} is not a finite number; expected {expected}", fieldname)
    return number


def _positive(value: Any, context: _Context, fieldname: str, unit: str) -> float:
    number = _number(value, context, fieldname, f"a number > 0 [{unit}]")
    if number <= 0:
        raise context.error(f"{value!r} must be > 0 [{unit}]", fieldname)
    return number


def _non_negative(value: Any, context: _Context, fieldname: str, unit: str) -> float:
    number = _number(value, context, fieldname, f"a number >= 0 [{unit}]")
    if number < 0:
        raise context.error(f"{value!r} must be >= 0 [{unit}]", fieldname)
    return number


def _integer(value: Any, context: _Context, fieldname: str, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        if isinstance(value, float) and value.is_integer() and value >= minimum:
            return int(value)
        raise context.error(f"{value!r} is not an integer >= {minimum}", fieldname)
    return int(value)


def _vector(value: Any, context: _Context, fieldname: str, unit: str = "") -> tuple[float, ...]:
    if not isinstance(value, list | tuple) or not value:
        raise context.error(
            f"{value!r} is not a list of numbers; expected e.g. [0.1, -0.2]{unit}", fieldname
        )
    return tuple(_number(v, context, f"{fieldname}[{i}]") for i, v in enumerate(value))


def _scalar_or_vector(value: Any, context: _Context, fieldname: str) -> float | tuple[float, ...]:
    if isinstance(value, list | tuple):
        return _vector(value, context, fieldname)
    return _number(value, context, fieldname, "a number or a list of numbers")


def _gain(value: Any, context: _Context, fieldname: str) -> Any:
    """A scalar, a diagonal (list) or a matrix (list of lists)."""
    if isinstance(value, list | tuple) and value and isinstance(value[0], list | tuple):
        return tuple(_vector(row, context, f"{fieldname}[{i}]") for i, row in enumerate(value))
    return _scalar_or_vector(value, context, fieldname)


def _mapping(value: Any, context: _Context, fieldname: str) -> Mapping:
    if not isinstance(value, Mapping):
        raise context.error(
            f"expected a mapping (key: value lines), got {type(value).__name__} {value!r}",
            fieldname,
        )
    return value


def _check_keys(doc: Mapping, valid: tuple[str, ...], context: _Context, prefix: str) -> None:
    for key in doc:
        if str(key) not in valid:
            raise context.error(
                f"unknown key '{key}'; " + did_you_mean(str(key), valid), f"{prefix}{key}"
            )


def _text(value: Any, context: _Context, fieldname: str) -> str:
    if not isinstance(value, str | int | float) or isinstance(value, bool):
        raise context.error(f"{value!r} is not a text", fieldname)
    return str(value)


def _path(value: Any, context: _Context, fieldname: str) -> Path:
    if not isinstance(value, str) or not value.strip():
        raise context.error(f"{value!r} is not a file path", fieldname)
    path = Path(value).expanduser()
    return path if path.is_absolute() else (context.base / path).resolve()


def _parse_robot(value: Any, context: _Context) -> str:
    text = _text(value, context, "robot")
    if Path(text).suffix.lower() in (".urdf", ".xml") or "/" in text:
        path = _path(text, context, "robot")
        if not path.is_file():
            raise context.error(f"robot file '{path}' does not exist", "robot")
        return str(path)
    return text


def _parse_uncertainty(value: Any, context: _Context) -> Path:
    path = _path(value, context, "uncertainty")
    if not path.is_file():
        raise context.error(f"uncertainty file '{path}' does not exist", "uncertainty")
    return path


def _parse_locked(value: Any, context: _Context) -> tuple[str, ...] | Mapping[str, float]:
    if value is None:
        return ()
    if isinstance(value, Mapping):
        return MappingProxyType(
            {str(k): _number(v, context, f"locked_joints.{k}") for k, v in value.items()}
        )
    if isinstance(value, list | tuple):
        return tuple(_text(v, context, "locked_joints") for v in value)
    raise context.error(
        f"{value!r}: expected a list of joint names or a mapping name: position [rad]",
        "locked_joints",
    )


def _parse_true_parameters(value: Any, context: _Context) -> TrueParameters:
    fieldname = "true_parameters"
    if value == "sample":
        return TrueParameters("sample")
    if value == "nominal":
        return TrueParameters("nominal")
    if isinstance(value, str):
        path = _path(value, context, fieldname)
        if not path.is_file():
            raise context.error(
                f"parameter file '{path}' does not exist; give a file, 'sample' or 'nominal'",
                fieldname,
            )
        return TrueParameters("file", file=path)
    doc = _mapping(value, context, fieldname)
    _check_keys(doc, ("sample", "file"), context, f"{fieldname}.")
    if len(doc) != 1:
        raise context.error("give exactly one of 'file' or 'sample'", fieldname)
    if "file" in doc:
        return _parse_true_parameters(str(doc["file"]), context)
    sample = doc["sample"]
    if sample is None:
        return TrueParameters("sample")
    sample = _mapping(sample, context, f"{fieldname}.sample")
    _check_keys(sample, ("seed",), context, f"{fieldname}.sample.")
    return TrueParameters(
        "sample", seed=_integer(sample.get("seed", 0), context, f"{fieldname}.sample.seed")
    )


def _parse_trajectory(value: Any, context: _Context) -> TrajectorySpec:
    if isinstance(value, str):
        doc: Mapping = {"kind": value}
    else:
        doc = _mapping(value, context, "trajectory")
    kind = doc.get("kind")
    if kind not in TRAJECTORY_KINDS:
        raise context.error(
            f"unknown trajectory kind {kind!r}; " + did_you_mean(str(kind), TRAJECTORY_KINDS),
            "trajectory.kind",
        )
    options = {k: v for k, v in doc.items() if k != "kind"}
    _check_keys(options, _TRAJECTORY_OPTIONS[kind], context, "trajectory.")
    parsed: dict[str, Any] = {}
    for key, raw in options.items():
        fieldname = f"trajectory.{key}"
        if key in ("amplitude_fraction", "velocity_fraction", "segment_duration"):
            parsed[key] = _positive(raw, context, fieldname, "1" if "fraction" in key else "s")
        elif key == "points":
            if not isinstance(raw, list | tuple) or len(raw) < 2:
                raise context.error("expected a list of at least 2 configurations", fieldname)
            parsed[key] = tuple(_vector(p, context, f"{fieldname}[{i}]") for i, p in enumerate(raw))
        elif key == "times":
            parsed[key] = _vector(raw, context, fieldname)
        elif key == "amplitude" and kind == "paper":
            parsed[key] = _vector(raw, context, fieldname)
        else:
            parsed[key] = _scalar_or_vector(raw, context, fieldname)
    if "frequency" in parsed and np.any(np.asarray(parsed["frequency"]) < 0):
        raise context.error("frequencies must be >= 0 [Hz]", "trajectory.frequency")
    return TrajectorySpec(kind, MappingProxyType(parsed))


def _parse_initial_condition(value: Any, context: _Context) -> InitialCondition:
    if value == "at_reference":
        return InitialCondition()
    doc = _mapping(value, context, "initial_condition")
    _check_keys(doc, ("q0", "qd0", "offset"), context, "initial_condition.")
    if "q0" in doc and "offset" in doc:
        raise context.error("give either q0 or offset, not both", "initial_condition.offset")
    return InitialCondition(
        **{k: _vector(v, context, f"initial_condition.{k}") for k, v in doc.items()}
    )


def _parse_sample_period(value: Any, context: _Context) -> float | None:
    if value == "continuous":
        return None
    return _positive(value, context, "sample_period", "s; or 'continuous'")


def _parse_controller(value: Any, context: _Context) -> str:
    text = _text(value, context, "controller")
    if text not in CONTROLLERS:
        raise context.error(
            f"unknown controller '{text}'; " + did_you_mean(text, CONTROLLERS), "controller"
        )
    return text


def _parse_plant(value: Any, context: _Context) -> str:
    text = _text(value, context, "plant")
    if text not in PLANT_BACKENDS:
        raise context.error(
            f"unknown plant '{text}'; " + did_you_mean(text, PLANT_BACKENDS), "plant"
        )
    return text


def _parse_torque_limit(value: Any, context: _Context) -> float | tuple[float, ...] | None:
    if value is None or value == "none":
        return None
    if isinstance(value, list | tuple):
        limits = _vector(value, context, "torque_limit")
        if min(limits) <= 0:
            raise context.error(f"{list(value)} must all be > 0 [N m]", "torque_limit")
        return limits
    return _positive(value, context, "torque_limit", "N m; or a list, one per joint")


def _interval_option_names() -> tuple[str, ...]:
    from ..control.synthesis import synthesize

    # The sample period is the scenario's own; `sampled_gain_limit` says whether synthesis uses it.
    parameters = inspect.signature(synthesize).parameters.values()
    names = [p.name for p in parameters if p.kind is inspect.Parameter.KEYWORD_ONLY]
    return (*(n for n in names if n != "sample_period"), "sampled_gain_limit")


def _parse_controller_options(value: Any, context: _Context) -> dict[str, dict[str, Any]]:
    doc = _mapping(value if value is not None else {}, context, "controller_options")
    _check_keys(doc, CONTROLLERS, context, "controller_options.")
    parsed: dict[str, dict[str, Any]] = {name: {} for name in CONTROLLERS}
    for name, options in doc.items():
        prefix = f"controller_options.{name}"
        options = _mapping(options if options is not None else {}, context, prefix)
        valid = {
            "interval": _interval_option_names(),
            "r-alpha": _R_ALPHA_OPTIONS,
            "computed-torque": _COMPUTED_TORQUE_OPTIONS,
        }[name]
        _check_keys(options, valid, context, f"{prefix}.")
        for key, raw in options.items():
            parsed[name][key] = _parse_option(name, key, raw, context, f"{prefix}.{key}")
    return parsed


def _parse_option(controller: str, key: str, raw: Any, context: _Context, fieldname: str) -> Any:
    if key == "sampled_gain_limit":
        if not isinstance(raw, bool):
            raise context.error(f"{raw!r} is not true or false", fieldname)
        return raw
    if controller == "interval" and key == "method":
        from ..bounds import METHODS

        if raw is None:
            return None
        if raw not in METHODS:
            raise context.error(
                f"unknown bound method {raw!r}; " + did_you_mean(str(raw), METHODS), fieldname
            )
        return raw
    if key in ("Lambda", "Q", "Kr"):
        return _gain(raw, context, fieldname)
    if key == "betas":
        if raw in ("estimate", "paper"):
            return raw
        doc = _mapping(raw, context, fieldname)
        names = ("beta0", "beta1", "beta2", "beta3")
        _check_keys(doc, names, context, f"{fieldname}.")
        missing = [n for n in names if n not in doc]
        if missing:
            raise context.error(
                f"missing {', '.join(missing)}; give all of beta0..beta3, 'estimate' or 'paper'",
                fieldname,
            )
        return MappingProxyType(
            {n: _non_negative(doc[n], context, f"{fieldname}.{n}", "SI") for n in names}
        )
    if key in ("n_samples",):
        return _integer(raw, context, fieldname, minimum=1)
    if key == "seed":
        return _integer(raw, context, fieldname)
    if key == "q_range":
        bounds = _vector(raw, context, fieldname)
        if len(bounds) != 2 or bounds[0] > bounds[1]:
            raise context.error(f"{raw!r}: expected [low, high] [rad] with low <= high", fieldname)
        return bounds
    if key == "disturbance_bound":
        return _non_negative(raw, context, fieldname, "N m")
    return _positive(raw, context, fieldname, "SI")


def _freeze_options(options: Mapping[str, Mapping[str, Any]]) -> Mapping[str, Mapping[str, Any]]:
    full = {name: MappingProxyType(dict(options.get(name, {}))) for name in CONTROLLERS}
    return MappingProxyType(full)


_PARSERS = {
    "name": lambda v, c: _text(v, c, "name"),
    "description": lambda v, c: _text(v, c, "description"),
    "robot": _parse_robot,
    "locked_joints": _parse_locked,
    "uncertainty": _parse_uncertainty,
    "true_parameters": _parse_true_parameters,
    "trajectory": _parse_trajectory,
    "initial_condition": _parse_initial_condition,
    "sample_period": _parse_sample_period,
    "disturbance": lambda v, c: _non_negative(v, c, "disturbance", "N m"),
    "epsilon": lambda v, c: _positive(v, c, "epsilon", "rad"),
    "controller": _parse_controller,
    "duration": lambda v, c: _positive(v, c, "duration", "s"),
    "seed": lambda v, c: _integer(v, c, "seed"),
    "torque_limit": _parse_torque_limit,
    "plant": _parse_plant,
}


# ============================================================================ building
@dataclass(frozen=True, eq=False)
class ScenarioSetup:
    """The objects a scenario describes, ready for synthesis and simulation.

    Attributes:
        scenario: The settings.
        robot: The controller's nominal model (payloads of the box attached at their nominal).
        box: The parameter box (the controller's knowledge).
        plant: The true plant.
        true_point: The true parameters (link -> coordinates of its box's kind; empty: nominal).
        true_description: How the true parameters were chosen, for reports.
        trajectory: The desired trajectory.
        q0, qd0: The initial state [rad], [rad/s].
        torque_limit: Per-joint torque bound [N m], or ``None``.
    """

    scenario: Scenario
    robot: Robot
    box: ParameterBox
    plant: Robot
    true_point: dict[str, np.ndarray]
    true_description: str
    trajectory: Trajectory
    q0: np.ndarray
    qd0: np.ndarray
    torque_limit: np.ndarray | None


def build(scenario: Scenario) -> ScenarioSetup:
    """Load the robot and the box, make the true plant, the trajectory and the initial state.

    Raises:
        InputError: a setting that does not fit the robot (vector lengths, joint limits, an
            unknown robot or link), naming the scenario file and the field.
    """
    context = _Context(None if scenario.source is None else str(scenario.source), Path.cwd())
    try:
        robot = load_robot(scenario.robot, scenario.locked_joints)
    except InputError as exc:
        if exc.source is not None:
            raise
        raise context.error(exc.detail, exc.field or "robot") from None
    box = load_uncertainty(scenario.uncertainty, robot)
    nominal = box.nominal_robot(robot)
    point, description = _true_point(scenario, robot, box, context)
    plant = box.plant(robot, point)
    trajectory = _trajectory(scenario.trajectory, nominal, context)
    reference = trajectory.reference(0.0)
    ic = scenario.initial_condition
    q0 = reference.q + _fit(ic.offset, nominal.dof, context, "initial_condition.offset")
    if ic.q0 is not None:
        q0 = _fit(ic.q0, nominal.dof, context, "initial_condition.q0")
    qd0 = reference.qd.copy()
    if ic.qd0 is not None:
        qd0 = _fit(ic.qd0, nominal.dof, context, "initial_condition.qd0")
    limit = None
    if scenario.torque_limit is not None:
        limit = np.broadcast_to(
            _fit(scenario.torque_limit, nominal.dof, context, "torque_limit"), (nominal.dof,)
        ).copy()
    return ScenarioSetup(
        scenario, nominal, box, plant, point, description, trajectory, q0, qd0, limit
    )


def _fit(value: Any, dof: int, context: _Context, fieldname: str) -> np.ndarray:
    """A per-joint vector from ``None`` (zeros), a scalar or ``dof`` numbers."""
    if value is None:
        return np.zeros(dof)
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return np.full(dof, float(array))
    if array.shape != (dof,):
        raise context.error(
            f"{array.tolist()} has {array.size} entries; the robot has {dof} joints", fieldname
        )
    return array.copy()


def _true_point(
    scenario: Scenario, robot: Robot, box: ParameterBox, context: _Context
) -> tuple[dict[str, np.ndarray], str]:
    true = scenario.true_parameters
    if true.kind == "file":
        return load_parameter_point(true.file, robot, box), f"true parameters from {true.file}"
    if true.kind == "nominal":
        return {}, "true parameters = nominal parameters (no model error)"
    seed = scenario.seed if true.seed is None else true.seed
    point = sample_true_parameters(box, seed, context.source)
    return point, (
        f"true parameters drawn uniformly from the box (seed {seed}): " + describe_point(box, point)
    )


def describe_point(box: ParameterBox, point: Mapping[str, np.ndarray]) -> str:
    """``link2: mass = 8.18 kg, com_x = 0.507 m, iyy = 1.17 kg m^2`` (uncertain fields only)."""
    parts = []
    for name, coordinates in point.items():
        link_box = box.link_box(name)
        fields = [
            f"{field_name} = {coordinates[k]:.6g} {UNITS.get(field_name, 'kg m^2')}"
            for k, field_name in enumerate(link_box.fields)
            if link_box.uncertain[k]
        ]
        parts.append(f"{name}: {', '.join(fields) if fields else 'nominal'}")
    return "; ".join(parts) if parts else "nominal"


def sample_true_parameters(
    box: ParameterBox, seed: int, source: str | None = None, tries: int = 1000
) -> dict[str, np.ndarray]:
    """A seeded uniform draw from ``box`` whose every link inertia is physically consistent.

    Raises:
        InputError: no consistent point found in ``tries`` draws.
    """
    rng = np.random.default_rng(seed)
    for _ in range(tries):
        point = box.sample(rng)
        if all(
            inertia_problem(np.asarray(box.link_box(name).inertia(values).inertia)) is None
            and values[0] > 0
            for name, values in point.items()
        ):
            return point
    raise InputError(
        f"no physically consistent point found in {tries} draws from the box; give a "
        "true_parameters file",
        source=source,
        field="true_parameters",
    )


def _trajectory(spec: TrajectorySpec, robot: Robot, context: _Context) -> Trajectory:
    options = dict(spec.options)
    dof = robot.dof
    try:
        if spec.kind == "paper":
            amplitude = options.get("amplitude", (math.pi / 4, -math.pi / 8))
            if len(amplitude) != dof:
                raise context.error(
                    f"the paper trajectory needs one amplitude per joint ({dof}), got "
                    f"{len(amplitude)}",
                    "trajectory.amplitude",
                )
            trajectory = PaperTrajectory(amplitude)
            reach = np.abs(trajectory.amplitude)
            return _within_limits(trajectory, (-reach, reach), robot, context)
        knobs = {
            k: options.pop(k)
            for k in ("home", "amplitude_fraction", "velocity_fraction", "segment_duration")
            if k in options
        }
        if "home" in knobs:
            knobs["home"] = _fit(knobs["home"], dof, context, "trajectory.home")
        generic = generic_trajectory(robot, spec.kind, **knobs)
        if spec.kind == "sinusoid":
            assert isinstance(generic, SinusoidTrajectory)
            values = {
                key: _fit(
                    options.get(key, getattr(generic, key)), dof, context, f"trajectory.{key}"
                )
                for key in ("amplitude", "frequency", "phase")
            }
            trajectory = SinusoidTrajectory(generic.home, **values)
            reach = np.abs(trajectory.amplitude)
            q_range = (trajectory.home - reach, trajectory.home + reach)
        else:
            if "points" not in options:
                return generic
            points = np.array(options["points"], dtype=float)
            if points.ndim != 2 or points.shape[1] != dof:
                raise context.error(f"each point needs {dof} joint values", "trajectory.points")
            times = options.get("times")
            if times is None:
                step = knobs.get("segment_duration", 2.0)
                times = step * np.arange(len(points))
            trajectory = QuinticTrajectory(points, times)
            q_range = (points.min(axis=0), points.max(axis=0))
    except InputError as exc:
        if exc.source is not None or (exc.field or "").startswith("trajectory"):
            raise
        raise context.error(
            exc.detail, f"trajectory.{exc.field}" if exc.field else "trajectory"
        ) from None
    return _within_limits(trajectory, q_range, robot, context)


def _within_limits(
    trajectory: Trajectory, q_range: tuple, robot: Robot, context: _Context
) -> Trajectory:
    lower, upper = robot.position_limits
    outside = np.flatnonzero((q_range[0] < lower) | (q_range[1] > upper))
    if outside.size:
        names = ", ".join(robot.joint_names[j] for j in outside)
        raise context.error(f"the trajectory leaves the joint limits of {names}", "trajectory")
    return trajectory


def interval_synthesis_options(scenario: Scenario) -> dict[str, Any]:
    """The keyword arguments of :func:`urpc.control.synthesis.synthesize` for the scenario's ``interval``
    options: sampled runs pass their ``sample_period`` (each inertia mode's gain capped at its
    dead-beat value) unless the scenario asks for the paper's law unchanged
    (``sampled_gain_limit: false``)."""
    options = dict(scenario.controller_options["interval"])
    if options.pop("sampled_gain_limit", True) and scenario.sample_period is not None:
        options["sample_period"] = scenario.sample_period
    return options


def build_controller(setup: ScenarioSetup, controller: str | None = None) -> Controller:
    """Synthesize the scenario's controller (or ``controller``, one of :data:`CONTROLLERS`) with
    its options from the scenario.

    ``interval`` options: the keyword arguments of :func:`urpc.control.synthesis.synthesize`, and
    ``sampled_gain_limit`` (default true): in a sampled scenario, synthesize with the scenario's
    sample period, which caps each inertia mode's gain at its dead-beat value (see
    :mod:`urpc.control.interval`); ``false`` runs the paper's law unchanged.

    ``r-alpha`` options: ``betas: estimate`` (default,
    :func:`~urpc.control.r_alpha.estimate_betas`), ``paper`` (the paper's values) or explicit
    ``beta0..beta3``; its ``disturbance_bound`` (the bound the r-alpha designer assumes) defaults
    to the box's known bound, else the scenario's ``disturbance``.
    """
    scenario = setup.scenario
    name = scenario.controller if controller is None else controller
    context = _Context(None if scenario.source is None else str(scenario.source), Path.cwd())
    if name not in CONTROLLERS:
        raise context.error(
            f"unknown controller '{name}'; " + did_you_mean(name, CONTROLLERS), "controller"
        )
    options = dict(scenario.controller_options[name])
    try:
        if name == "interval":
            from ..control.synthesis import synthesize

            options = interval_synthesis_options(scenario)
            return synthesize(setup.robot, setup.box, scenario.epsilon, **options)
        if name == "computed-torque":
            from ..control.computed_torque import synthesize_computed_torque

            return synthesize_computed_torque(setup.robot, setup.box, **options)
        from ..control.r_alpha import PAPER_BETAS, Betas, synthesize_r_alpha

        betas = options.pop("betas", "estimate")
        if betas == "paper":
            options["betas"] = PAPER_BETAS
        elif isinstance(betas, Mapping):
            options["betas"] = Betas(**betas)
        if "disturbance_bound" not in options:
            known = setup.box.disturbance_bound
            options["disturbance_bound"] = scenario.disturbance if known is None else known
        return synthesize_r_alpha(setup.robot, setup.box, **options)
    except InputError as exc:
        if exc.source is not None:
            raise
        prefix = f"controller_options.{name}"
        raise context.error(exc.detail, f"{prefix}.{exc.field}" if exc.field else prefix) from None


def run_scenario(
    scenario: Scenario, controller: str | None = None, progress: Any = None
):  # -> urpc.sim.results.SimulationResult
    """Build, synthesize and simulate one scenario; returns the simulation result.

    ``progress`` is passed to :func:`urpc.sim.simulation.simulate`. The result's ``info`` records the
    plant backend (``plant``) and how the true parameters were chosen (``true_parameters``).
    """
    setup = build(scenario)
    law = build_controller(setup, controller)
    return simulate_setup(setup, law, progress=progress)


def simulate_setup(
    setup: ScenarioSetup, controller: Controller, progress: Any = None
):  # -> urpc.sim.results.SimulationResult
    """Simulate a built scenario with a synthesized controller (the last step of
    :func:`run_scenario`, for callers that want to inspect the setup or the controller)."""
    from ..sim.simulation import simulate

    scenario = setup.scenario
    result = simulate(
        setup.plant,
        controller,
        setup.trajectory,
        duration=scenario.duration,
        q0=setup.q0,
        qd0=setup.qd0,
        sample_period=scenario.sample_period,
        disturbance_bound=scenario.disturbance,
        seed=scenario.seed,
        torque_limit=setup.torque_limit,
        epsilon=scenario.epsilon,
        scenario=scenario.name,
        plant_description=setup.true_description,
        progress=progress,
        plant_backend=scenario.plant,
    )
    info = {**result.info, "true_parameters": true_parameter_values(setup)}
    return dataclasses.replace(result, info=info)


def true_parameter_values(setup: ScenarioSetup) -> dict[str, dict[str, float]]:
    """The true values of the uncertain parameters, link -> field -> value (units of the
    uncertainty format: kg, m, kg m^2); empty when the true plant is the nominal model."""
    values: dict[str, dict[str, float]] = {}
    for name, coordinates in setup.true_point.items():
        try:
            link_box = setup.box.link_box(name)
        except KeyError:
            continue
        values[name] = {
            field_name: float(coordinates[k])
            for k, field_name in enumerate(link_box.fields)
            if link_box.uncertain[k]
        }
    return values
