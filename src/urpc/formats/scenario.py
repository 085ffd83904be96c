"""The scenario file: everything one simulation run needs.

Documented in ``docs/scenarios.md``. :class:`Scenario` is both the file's format and the
settings the package runs: :func:`urpc.studies.scenario.load_scenario` reads one,
:meth:`Scenario.with_overrides` makes a changed copy (each value checked like the file's, the
combination on the copy) and :func:`urpc.studies.scenario.build` turns it into the objects of a
run. Paths are resolved against ``context["base"]`` (the scenario's folder) and must exist;
``context["source"]`` is the file (:attr:`Scenario.source`, whose stem names a scenario without a
``name``). The controllers' options are in :mod:`.controller_options`. The names of the
controllers, bound methods, plants and trajectories come from :mod:`urpc.names`; tests check them
against the registries of :mod:`urpc.bounds`, :mod:`urpc.sim.plants` and :mod:`urpc.trajectories`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args

from pydantic import (
    AfterValidator,
    BeforeValidator,
    Discriminator,
    Field,
    PrivateAttr,
    Tag,
    ValidationInfo,
    WithJsonSchema,
    model_validator,
)

from .. import names
from ..errors import InputError, did_you_mean, no_file
from ..wording import count
from .base import FieldError, FileFormat, validate_fields
from .controller_options import ControllerOptions
from .values import Count, NonNegative, Number, Positive, Text, Vector, either

# The fixed sets, from the one place that names them (urpc.names).
ControllerName = Literal[names.CONTROLLERS]
PlantBackend = Literal[names.PLANT_BACKENDS]
DisturbanceModel = Literal[names.DISTURBANCE_MODELS]
TrajectoryKind = Literal[names.TRAJECTORY_KINDS]


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
ScalarOrVector = either(_VECTOR, scalar=Number, array=Vector)


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
    interpolated C2 (:mod:`urpc.trajectory_samples`)."""

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


Trajectory = either(
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
TrueParameters = either(
    "a parameter-point file, 'sample', 'nominal', {file: ...} or {sample: {seed: ...}}",
    scalar=Annotated[
        Annotated[Literal["sample", "nominal"], Tag("word")] | Annotated[_POINT_FILE, Tag("file")],
        Discriminator(lambda v: "word" if v in _WORDS else "file"),
    ],
    mapping=Annotated[
        Annotated[ParameterFile, AfterValidator(lambda v: v.file), Tag("file")]
        | Annotated[SampledParameters, Tag("sample")],
        Discriminator(lambda v: "file" if "file" in v else "sample"),
    ],
)


_LockedJoints = either(
    "a list of joint names or a mapping name: position [rad]",
    mapping=dict[str, Number],
    array=tuple[Text, ...],
)


#: Where the values of :meth:`Scenario.with_overrides` come from, in error messages.
OVERRIDE_SOURCE = "command-line override"


def _default_name(name: str | None, info: ValidationInfo) -> str:
    source = (info.context or {}).get("source")
    return name or (Path(source).stem if source is not None else "scenario")


class Scenario(FileFormat):
    """A scenario file (units in brackets): the settings of one simulation run, validated and
    frozen, with paths made absolute."""

    _source: Path | None = PrivateAttr(None)
    #: The fields :meth:`with_overrides` replaced (their errors name the command line, not the
    #: file).
    _overridden: frozenset[str] = PrivateAttr(frozenset())

    name: Annotated[Text | None, AfterValidator(_default_name)] = Field(
        None, validate_default=True, description="default: the file name without .yaml"
    )
    description: Text = Field("", description="free text")
    robot: Annotated[Text, AfterValidator(_robot)] = Field(
        description="a built-in or example-robot-data name, or a URDF path"
    )
    locked_joints: _LockedJoints = Field(
        (), description="joint names (locked at 0) or name: position [rad or m]"
    )
    uncertainty: _file("uncertainty") = Field(
        description="the uncertainty file: what the controller knows"
    )
    true_parameters: TrueParameters = Field(
        "sample", description="a parameter-point file, sample, {sample: {seed: 7}} or nominal"
    )
    trajectory: Trajectory = Field("sinusoid", description="a kind, or kind and options")
    initial_condition: either(
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
    disturbance_model: DisturbanceModel = Field(
        "ball",
        description="ball (drawn uniformly in ||d|| <= bound, seeded), or at the bound: against "
        "(against r), worst (against r in the plant's M^-1 metric), lightest (along the lightest "
        "mode of the law's M_L)",
    )
    epsilon: Positive("rad") = Field(1e-2, description="required ||q_d - q|| < epsilon [rad]")
    controller: ControllerName = Field("interval", description="the controller that runs")
    controller_options: ControllerOptions = Field(
        default_factory=ControllerOptions, description="the options of each controller"
    )
    duration: Positive("s") = Field(10.0, description="simulated time [s]")
    seed: Count = Field(0, description="seed of the disturbance draws (and of a sampled plant)")
    torque_limit: either(
        "a number > 0 [N m], 'none' or a list, one per joint",
        scalar=Positive("N m", keyword="none"),
        array=Annotated[Vector, AfterValidator(_all_positive)],
    ) = Field(None, description="per-joint torque bound [N m]: a number or one per joint")
    plant: PlantBackend = Field("pinocchio", description="pinocchio, or mujoco (sampled runs)")
    actuation_delay: Count | None = Field(
        None,
        description="samples between a state and the period its torque acts over on the plant "
        "(sampled runs); default: the interval law's delay (controller_options.interval.delay), "
        "else 0",
    )

    def model_post_init(self, context: Any) -> None:
        source = (context or {}).get("source")
        self._source = None if source is None else Path(source)

    @model_validator(mode="after")
    def _consistent(self) -> Scenario:
        """The checks that combine fields, of a file and of every override."""
        period = self.sample_period
        if period is not None and period > self.duration:
            raise FieldError(
                "duration",
                f"the duration {self.duration:g} s is shorter than one sample period "
                f"(sample_period = {period:g} s): lengthen the duration or shorten the period",
            )
        if period is None and self.plant != "pinocchio":
            raise FieldError(
                "plant",
                f"the {self.plant} plant steps under a held torque: give a sample_period [s], or "
                "use plant: pinocchio for continuous time",
            )
        if period is None and self.actuation_delay:
            raise FieldError(
                "actuation_delay",
                f"an actuation delay of {count(self.actuation_delay, 'sample')} needs samples: "
                "give a sample_period [s], or set actuation_delay to 0 for continuous time",
            )
        if period is None and self.disturbance > 0:
            raise FieldError(
                "disturbance",
                "the disturbance is drawn once per control sample: give a sample_period [s] or "
                "set disturbance to 0 for continuous time",
            )
        return self

    @property
    def source(self) -> Path | None:
        """The file the scenario was read from."""
        return self._source

    @property
    def continuous(self) -> bool:
        return self.sample_period is None

    @property
    def options(self) -> dict[str, Any]:
        """The options of the controller that runs (keyword arguments of its synthesis)."""
        return self.controller_options.by_controller()[self.controller]

    @property
    def true_parameter_seed(self) -> int | None:
        """The seed of a sampled true plant: its own, else the scenario's ``seed``; ``None``
        when the true parameters are a file or the nominal ones."""
        true = self.true_parameters
        if isinstance(true, SampledParameters):
            return self.seed if true.sample is None else true.sample.seed
        return self.seed if true == "sample" else None

    def with_overrides(self, **values: Any) -> Scenario:
        """A copy with some fields replaced; ``None`` values are ignored (flags not given).

        Values are validated like file entries; relative paths are resolved against the current
        directory. ``controller_options`` entries are merged per controller.

        Raises:
            InputError: an unknown field (with the closest name) or an invalid value.
        """
        given = {key: value for key, value in values.items() if value is not None}
        update = validate_fields(Scenario, given, OVERRIDE_SOURCE, context={"base": Path.cwd()})
        if "controller_options" in update:
            update["controller_options"] = self.controller_options.merged(
                update["controller_options"]
            )
        try:
            copy = self.model_copy(update=update)._consistent()
        except FieldError as exc:
            field = exc.path[0]
            if field in update or self.source is None:
                raise InputError(str(exc), OVERRIDE_SOURCE, field) from None
            # The field is the file's: it conflicts with what the command line changed.
            changed = ", ".join(sorted(update))
            raise InputError(
                f"{exc} (the file's value conflicts with the command-line override of {changed})",
                self.source,
                field,
            ) from None
        copy._overridden = self._overridden | frozenset(update)
        return copy

    def source_of(self, field: str):
        """Where ``field``'s value came from: :data:`OVERRIDE_SOURCE` for a field
        :meth:`with_overrides` replaced, else the scenario's file (``None`` when built in
        code)."""
        return OVERRIDE_SOURCE if field in self._overridden else self.source

    def to_dict(self) -> dict[str, Any]:
        """Plain data (YAML/JSON-ready) with every key of the scenario file; paths absolute."""
        document = self.model_dump(mode="json")
        seed = self.true_parameter_seed
        if seed is not None:
            document["true_parameters"] = {"sample": {"seed": seed}}
        trajectory = self.trajectory
        document["trajectory"] = (
            {"kind": trajectory}
            if isinstance(trajectory, str)
            else {"kind": trajectory.kind, **trajectory.model_dump(mode="json", exclude_unset=True)}
        )
        ic = document["initial_condition"]
        if isinstance(ic, dict):
            document["initial_condition"] = {k: v for k, v in ic.items() if v} or "at_reference"
        if self.sample_period is None:
            document["sample_period"] = "continuous"
        document["controller_options"] = self.controller_options.by_controller("json")
        return document
