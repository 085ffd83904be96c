"""The parameter-point file: one point of an uncertainty box, a true plant for simulation.

The names of the uncertainty format with single numbers; what is not given stays nominal. Read by
:func:`urpc.model.uncertainty.load_parameter_point`.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, model_validator

from .base import FileFormat
from .uncertainty import _H, _I_O, JointPoint, PhysicalPoint, check_one_kind
from .values import NonNegative, Number, Positive, Text


class BarycentricPoint(FileFormat):
    """Single values of the standard parameters about the link origin."""

    m: Positive("kg") | None = Field(None, description="mass [kg], > 0")
    h_x: Number | None = Field(None, description=_H.format("x"))
    h_y: Number | None = Field(None, description=_H.format("y"))
    h_z: Number | None = Field(None, description=_H.format("z"))
    I_xx: Number | None = Field(None, description=_I_O.format("xx"))
    I_xy: Number | None = Field(None, description=_I_O.format("xy"))
    I_yy: Number | None = Field(None, description=_I_O.format("yy"))
    I_xz: Number | None = Field(None, description=_I_O.format("xz"))
    I_yz: Number | None = Field(None, description=_I_O.format("yz"))
    I_zz: Number | None = Field(None, description=_I_O.format("zz"))


class LinkPoint(PhysicalPoint):
    """A link's parameters: physical values, or ``barycentric:`` values for a barycentric box."""

    mass: Positive("kg") | None = Field(None, description="mass [kg], > 0")
    barycentric: BarycentricPoint | None = Field(
        None, description="for a link whose box is barycentric, instead of the physical values"
    )

    @model_validator(mode="after")
    def _one_kind(self) -> LinkPoint:
        check_one_kind(self, "a point")
        return self

    def values(self) -> dict[str, float]:
        """The given values by field name (of the barycentric point when there is one)."""
        point: Any = self.barycentric if self.barycentric is not None else self
        return {k: v for k, v in point.model_dump(exclude={"barycentric"}).items() if v is not None}


class PayloadPoint(PhysicalPoint):
    """The payload's parameters (physical; a mass of 0 means no object held)."""

    mass: NonNegative("kg") | None = Field(None, description="mass [kg], >= 0")

    def values(self) -> dict[str, float]:
        return {k: v for k, v in self.model_dump().items() if v is not None}


class ParameterPointFile(FileFormat):
    """A parameter-point file (a true plant)."""

    robot: Text | None = Field(None, description="the robot the point is for (informative)")
    description: Text | None = Field(None, description="free text")
    links: dict[str, LinkPoint] = Field(
        default_factory=dict, description="URDF link name -> its parameters"
    )
    payload: PayloadPoint | None = Field(None, description="the box's payload")
    joints: dict[str, JointPoint] = Field(
        default_factory=dict,
        description="joint name -> its armature, damping and friction (others stay nominal)",
    )
