"""The scenario file: everything one simulation run needs.

Documented in ``docs/scenarios.md``; read by :func:`urpc.studies.scenario.load_scenario`. Paths are
resolved against ``context["base"]`` (the scenario's folder) and must exist. The names of the
controllers, bound methods, plants and trajectories are declared here; tests check them against
the registries of :mod:`urpc.bounds`, :mod:`urpc.sim.plants` and :mod:`urpc.trajectories`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args

from pydantic import (
    AfterValidator,
    BeforeValidator,
    Discriminator,
    Field,
    Tag,
    ValidationInfo,
    WithJsonSchema,
    model_validator,
)

from .. import names
from ..errors import did_you_mean, no_file
from .base import FieldError, FileFormat
from .values import Count, NonNegative, Number, Positive, PositiveCount, Text, Vector

# The fixed sets, from the one place that names them (urpc.names).
ControllerName = Literal[names.CONTROLLERS]
BoundMethodName = Literal[names.BOUND_METHODS]
PlantBackend = Literal[names.PLANT_BACKENDS]
TrajectoryKind = Literal[names.TRAJECTORY_KINDS]
#: How a sampled interval controller runs: ``implicit`` (the sampled-data law) or ``paper`` (the
#: paper's law unchanged).
SampledLaw = Literal[names.SAMPLED_LAWS]


def _form(value: Any) -> str:
    if isinstance(value, list | tuple):
        return "list"
    return "mapping" if isinstance(value, Mapping) else "scalar"


def _either(expected: str, scalar: Any = None, mapping: Any = None, array: Any = None) -> Any:
    """The forms of one value told apart by its YAML type (a text or number, a mapping, a list),
    so that a wrong value gets the one message of the form it has."""
    forms = {"scalar": scalar, "mapping": mapping, "list": array}
    members = tuple(Annotated[kind, Tag(tag)] for tag, kind in forms.items() if kind is not None)
    return Annotated[
        Union[members],  # noqa: UP007 - built from a tuple
        Discriminator(_form, custom_error_type="form", custom_error_message=f"expected {expected}"),
    ]


def resolve_file(value: Any, info: ValidationInfo, what: str, alternatives: str = "") -> Path:
    """An existing file, relative paths resolved against ``info.context["base"]`` (default: the
    current directory)."""
    if not isinstance(value, str | Path) or not str(value).strip():
        raise ValueError(f"{value!r} is not a file path")
    path = Path(value).expanduser()
    base = Path((info.context or {}).get("base", Path.cwd()))
    path = path if path.is_absolute() else (base / path).resolve()
    if not path.is_file():
        raise ValueError(no_file(path, f"{what} file '{path}'") + alternatives)
    return path


def _file(what: str, alternatives: str = "", schema: dict | None = None) -> Any:
    return Annotated[
        Path,
        BeforeValidator(lambda value, info: resolve_file(value, info, what, alternatives)),
        WithJsonSchema(schema or {"type": "string", "description": "a path"}),
    ]


def _robot(text: str, info: ValidationInfo) -> str:
    if Path(text).suffix.lower() in (".urdf", ".xml") or "/" in text:
        return str(resolve_file(text, info, "robot"))
    return text


def _all_positive(values: tuple[float, ...]) -> tuple[float, ...]:
    if min(values) <= 0:
        raise ValueError(f"{list(values)} must all be > 0 [N m]")
    return values


_VECTOR = "a number or a list of numbers, one per joint"
ScalarOrVector = _either(_VECTOR, scalar=Number, array=Vector)
#: A gain: a number, a diagonal (one per joint) or a matrix (list of rows).
Gain = _either(
    "a number, a list (diagonal) or a list of rows (matrix)",
    scalar=Positive("SI"),
    array=Annotated[
        Annotated[Vector, Tag("diagonal")] | Annotated[tuple[Vector, ...], Tag("rows")],
        Discriminator(lambda v: "rows" if v and isinstance(v[0], list | tuple) else "diagonal"),
    ],
)


# ---------------------------------------------------------------------------- controllers
class IntervalOptions(FileFormat):
    """Keyword arguments of :func:`urpc.control.synthesis.synthesize` (the sample period is the
    scenario's own)."""

    method: BoundMethodName | None = Field(
        None, title="bound method", description="default: by box kind (urpc.bounds.METHODS)"
    )
    kappa_P: Positive("s/rad") | None = Field(None, description="[s/rad], >= 1 (2)")
    kappa_I: Positive("1/rad^2") | None = Field(None, description="[1/rad^2] (1)")
    phi_P: Positive("N m s/rad") | None = Field(None, description="[N m s/rad], >= 1 (1)")
    phi_I: Positive("N m/rad^2") | None = Field(None, description="[N m/rad^2] (1e6)")
    Kr: Gain | None = Field(None, description="[1/s]; default 3/sqrt(epsilon)")
    sampled_law: SampledLaw = Field(
        "implicit",
        description="sampled runs: implicit (the sampled-data law) or paper (the paper's law "
        "unchanged)",
    )
    delay: Literal[0, 1] = Field(
        0,
        description="samples between a state and the period its torque acts over: 0, or 1 (the "
        "law predicts one period ahead; urpc.control.delay)",
    )


def _betas_word(value: Any) -> Any:
    if value not in ("estimate", "paper"):
        raise ValueError(f"{value!r} is not 'estimate' or 'paper', nor a mapping of beta0..beta3")
    return value


class Betas(FileFormat):
    """The r-alpha bounds ``beta0..beta3`` [SI]."""

    beta0: NonNegative("SI")
    beta1: NonNegative("SI")
    beta2: NonNegative("SI")
    beta3: NonNegative("SI")


class RAlphaOptions(FileFormat):
    """Keyword arguments of :func:`urpc.control.r_alpha.synthesize_r_alpha`."""

    r: Positive("rad/s") | None = Field(None, description="[rad/s] (1e-2)")
    alpha: Positive("1/s") | None = Field(None, description="[1/s] (1)")
    Lambda: Gain | None = Field(None, description="[1/s]")
    Q: Gain | None = Field(None, description="[N m s/rad]")
    eta: Positive("N m rad/s") | None = Field(None, description="[N m rad/s]")
    betas: (
        _either(
            "'estimate', 'paper' or a mapping of beta0..beta3",
            scalar=Annotated[Literal["estimate", "paper"], BeforeValidator(_betas_word)],
            mapping=Betas,
        )
        | None
    ) = Field(None, description="estimate (default), paper, or beta0..beta3")
    n_samples: PositiveCount | None = Field(None, description="samples of the estimate (1e5)")
    seed: Count | None = Field(None, description="seed of the estimate (0)")
    disturbance_bound: NonNegative("N m") | None = Field(
        None, description="the bound the designer assumes [N m]"
    )
    q_range: Vector | None = Field(None, description="[low, high] of q in the estimate [rad]")

    @model_validator(mode="after")
    def _range(self) -> RAlphaOptions:
        if self.q_range is not None and (
            len(self.q_range) != 2 or self.q_range[0] > self.q_range[1]
        ):
            raise FieldError(
                "q_range", f"{list(self.q_range)}: expected [low, high] [rad] with low <= high"
            )
        return self


class ComputedTorqueOptions(FileFormat):
    """Keyword arguments of :func:`urpc.control.computed_torque.synthesize_computed_torque`."""

    natural_frequency: Positive("rad/s") | None = Field(None, description="[rad/s] (10)")
    damping: Positive("1") | None = Field(None, description="damping ratio (1)")


class ControllerOptions(FileFormat):
    """The options of each controller; only those of the controller that runs are used."""

    interval: IntervalOptions | None = None
    r_alpha: RAlphaOptions | None = Field(None, alias="r-alpha")
    computed_torque: ComputedTorqueOptions | None = Field(None, alias="computed-torque")


# ---------------------------------------------------------------------------- trajectories
def _kind(value: Any) -> Any:
    if value not in get_args(TrajectoryKind):
        raise FieldError(
            "kind", f"unknown kind {value!r}; " + did_you_mean(str(value), get_args(TrajectoryKind))
        )
    return value


def _at_least_two(value: Any) -> Any:
    if not isinstance(value, list | tuple) or len(value) < 2:
        raise ValueError("expected a list of at least 2 configurations")
    return value


class _Generic(FileFormat):
    home: ScalarOrVector | None = Field(None, description="[rad]; default: middle of the limits")
    amplitude_fraction: Positive("1") | None = Field(None, description="of the distance (0.25)")
    velocity_fraction: Positive("1") | None = Field(None, description="of the limit (0.5)")


class PaperTrajectory(FileFormat):
    """``q_d(t) = amplitude sin(pi t/2) sin(pi t)``."""

    kind: Literal["paper"]
    amplitude: Vector | None = Field(None, description="[rad], one per joint ([pi/4, -pi/8])")


class SinusoidTrajectory(_Generic):
    """``q_d(t) = home + amplitude sin(2 pi frequency t + phase)`` per joint."""

    kind: Literal["sinusoid"]
    amplitude: ScalarOrVector | None = Field(None, description="[rad]")
    frequency: ScalarOrVector | None = Field(None, description="[Hz], >= 0")
    phase: ScalarOrVector | None = Field(None, description="[rad]")

    @model_validator(mode="after")
    def _frequencies(self) -> SinusoidTrajectory:
        frequency = self.frequency
        if (
            frequency is not None
            and min(frequency if isinstance(frequency, tuple) else [frequency]) < 0
        ):
            raise FieldError("frequency", "frequencies must be >= 0 [Hz]")
        return self


class QuinticTrajectory(_Generic):
    """Rest-to-rest quintic segments through via points."""

    kind: Literal["quintic"]
    points: Annotated[tuple[Vector, ...], BeforeValidator(_at_least_two)] | None = Field(
        None, description="configurations [rad]"
    )
    times: Vector | None = Field(None, description="[s], one per point")
    segment_duration: Positive("s") | None = Field(None, description="[s] (2)")


class FileTrajectory(FileFormat):
    """Samples from a file (CSV or NPZ: ``t``, ``q`` per joint, optional ``qd``, ``qdd``),
    interpolated C2 (:mod:`urpc.trajectory_sources`)."""

    kind: Literal["file"]
    path: _file("trajectory") = Field(description="a .csv or .npz file of samples")
    acceleration_limit: ScalarOrVector | None = Field(
        None, description="[rad/s^2], a number or one per joint; checked with the URDF's limits"
    )


class WaypointsTrajectory(FileFormat):
    """Rest-to-rest quintic segments through waypoints, timed by the limits unless ``times``."""

    kind: Literal["waypoints"]
    points: Annotated[tuple[Vector, ...], BeforeValidator(_at_least_two)] = Field(
        description="configurations [rad]"
    )
    times: Vector | None = Field(None, description="[s], one per point; default: from the limits")
    velocity_fraction: Positive("1") | None = Field(None, description="of the URDF limit (0.5)")
    acceleration_limit: ScalarOrVector | None = Field(None, description="[rad/s^2] (5)")


Trajectory = _either(
    "a kind (paper, sinusoid, quintic) or a mapping with kind and options (also file, waypoints)",
    scalar=Annotated[TrajectoryKind, BeforeValidator(_kind)],
    mapping=Annotated[
        Union[  # noqa: UP007
            PaperTrajectory,
            SinusoidTrajectory,
            QuinticTrajectory,
            FileTrajectory,
            WaypointsTrajectory,
        ],
        Field(discriminator="kind"),
    ],
)


# ---------------------------------------------------------------------------- the rest
class InitialState(FileFormat):
    """The initial state; what is not given follows the reference at ``t = 0``."""

    q0: Vector | None = Field(None, description="joint positions [rad]")
    qd0: Vector | None = Field(None, description="joint velocities [rad/s]")
    offset: Vector | None = Field(None, description="q(0) = q_d(0) + offset [rad]")

    @model_validator(mode="after")
    def _exclusive(self) -> InitialState:
        if self.q0 is not None and self.offset is not None:
            raise FieldError("offset", "give either q0 or offset, not both")
        return self


class SampleDraw(FileFormat):
    seed: Count = Field(0, description="seed of the draw")


class SampledParameters(FileFormat):
    sample: SampleDraw | None = Field(None, description="a seeded uniform draw from the box")


class ParameterFile(FileFormat):
    file: _file("parameter") = Field(description="a parameter-point file")


_WORDS = ("sample", "nominal")
_POINT_FILE = _file(
    "parameter",
    "; give a file, 'sample' or 'nominal'",
    {"type": "string", "not": {"enum": list(_WORDS)}, "description": "a parameter-point file"},
)
TrueParameters = _either(
    "a parameter-point file, 'sample', 'nominal', {file: ...} or {sample: {seed: ...}}",
    scalar=Annotated[
        Annotated[Literal["sample", "nominal"], Tag("word")] | Annotated[_POINT_FILE, Tag("file")],
        Discriminator(lambda v: "word" if v in _WORDS else "file"),
    ],
    mapping=Annotated[
        Annotated[ParameterFile, Tag("file")] | Annotated[SampledParameters, Tag("sample")],
        Discriminator(lambda v: "file" if "file" in v else "sample"),
    ],
)


_LockedJoints = _either(
    "a list of joint names or a mapping name: position [rad]",
    mapping=dict[str, Number],
    array=tuple[Text, ...],
)


class ScenarioFile(FileFormat):
    """A scenario file (units in brackets; defaults as in :class:`urpc.studies.scenario.Scenario`)."""

    name: Text | None = Field(None, description="default: the file name without .yaml")
    description: Text = Field("", description="free text")
    robot: Annotated[Text, AfterValidator(_robot)] = Field(
        description="a built-in or example-robot-data name, or a URDF path"
    )
    locked_joints: _LockedJoints | None = Field(
        None, description="joint names (locked at 0) or name: position [rad or m]"
    )
    uncertainty: _file("uncertainty") = Field(
        description="the uncertainty file: what the controller knows"
    )
    true_parameters: TrueParameters = Field(
        "sample", description="a parameter-point file, sample, {sample: {seed: 7}} or nominal"
    )
    trajectory: Trajectory = Field("sinusoid", description="a kind, or kind and options")
    initial_condition: _either(
        "at_reference or a mapping of q0, qd0, offset",
        scalar=Literal["at_reference"],
        mapping=InitialState,
    ) = Field("at_reference", description="at_reference, or q0, qd0, offset")
    sample_period: Positive("s", keyword="continuous") = Field(
        1e-3, description="control period [s] (zero-order hold), or continuous"
    )
    disturbance: NonNegative("N m") = Field(
        0.0, description="bound on ||d|| [N m], drawn per sample"
    )
    epsilon: Positive("rad") = Field(1e-2, description="required ||q_d - q|| < epsilon [rad]")
    controller: ControllerName = Field("interval", description="the controller that runs")
    controller_options: ControllerOptions = Field(
        default_factory=ControllerOptions, description="the options of each controller"
    )
    duration: Positive("s") = Field(10.0, description="simulated time [s]")
    seed: Count = Field(0, description="seed of the disturbance draws (and of a sampled plant)")
    torque_limit: _either(
        "a number > 0 [N m], 'none' or a list, one per joint",
        scalar=Positive("N m", keyword="none"),
        array=Annotated[Vector, AfterValidator(_all_positive)],
    ) = Field(None, description="per-joint torque bound [N m]: a number or one per joint")
    plant: PlantBackend = Field("pinocchio", description="pinocchio, or mujoco (sampled runs)")
