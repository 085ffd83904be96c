"""The options of each controller in a scenario file: the keyword arguments of its synthesis.

Part of the scenario format (:class:`urpc.formats.scenario.Scenario`, ``controller_options``);
documented in ``docs/scenarios.md``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Discriminator, Field, Tag, model_validator

from .. import names
from .base import FieldError, FileFormat
from .values import Count, NonNegative, Positive, PositiveCount, Vector, either

BoundMethodName = Literal[names.BOUND_METHODS]
#: How a sampled interval controller runs: ``implicit`` (the sampled-data law) or ``paper`` (the
#: paper's law unchanged).
SampledLaw = Literal[names.SAMPLED_LAWS]

#: A gain: a number, a diagonal (one per joint) or a matrix (list of rows).
Gain = either(
    "a number, a list (diagonal) or a list of rows (matrix)",
    scalar=Positive("SI"),
    array=Annotated[
        Annotated[Vector, Tag("diagonal")] | Annotated[tuple[Vector, ...], Tag("rows")],
        Discriminator(lambda v: "rows" if v and isinstance(v[0], list | tuple) else "diagonal"),
    ],
)


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
        either(
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

    def by_controller(self, mode: Literal["python", "json"] = "python") -> dict[str, dict]:
        """The options given for each controller (``{}``: none), by controller name."""
        return {
            field.alias or key: {}
            if (options := getattr(self, key)) is None
            else options.model_dump(mode=mode, exclude_unset=True)
            for key, field in type(self).model_fields.items()
        }

    def merged(self, other: ControllerOptions) -> ControllerOptions:
        """These options with those given in ``other`` in their place, per controller."""
        update = {}
        for key in other.model_fields_set:
            mine, given = getattr(self, key), getattr(other, key)
            values = {name: getattr(given, name) for name in given.model_fields_set}
            update[key] = given if mine is None else mine.model_copy(update=values)
        return self.model_copy(update=update)
