"""The module file: one rigid body of a modular arm, its flanges, its joint and its uncertainty.

Documented in ``docs/modular.md``; read by :func:`urpc.model.modules.read_module`, which adds the
checks that need the rigid-body model (a physical inertia, the box around the nominal values).
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from .base import FieldError, FileFormat
from .uncertainty import JointEntry, LinkEntry, PhysicalPoint
from .values import Number, Positive, Text, Vector3

ModuleKind = Literal["base", "actuator", "link", "tool", "payload"]


class Connector(FileFormat):
    """A connection frame (flange) in the module frame; its z axis points along the chain."""

    connector: Text = Field(
        description="connector type (for example L, M or tcp): only flanges of the same type "
        "connect"
    )
    xyz: Vector3 = Field((0.0, 0.0, 0.0), description="origin of the frame [m]")
    rpy: Vector3 = Field((0.0, 0.0, 0.0), description="orientation, URDF roll-pitch-yaw [rad]")


class Joint(FileFormat):
    """The revolute joint of an actuator, at the module frame."""

    axis: Vector3 = Field(description="joint axis in the module frame (normalized when read)")
    lower: Number = Field(description="lower position limit [rad]")
    upper: Number = Field(description="upper position limit [rad]")
    effort: Positive("N m") = Field(description="torque limit [N m]")
    velocity: Positive("rad/s") = Field(description="velocity limit [rad/s]")

    @model_validator(mode="after")
    def _limits(self) -> Joint:
        if not math.hypot(*self.axis) > 1e-9:
            raise FieldError("axis", "the joint axis must be a non-zero vector")
        if not self.lower < self.upper:
            raise FieldError(
                "lower",
                f"lower limit {self.lower:g} must be below upper limit {self.upper:g} [rad]",
            )
        return self


class Cylinder(FileFormat):
    """A solid cylinder along z."""

    radius: Positive("m") = Field(description="[m]")
    length: Positive("m") = Field(description="[m]")


class Tube(FileFormat):
    """A thin-walled tube along z."""

    radius: Positive("m") = Field(description="mean radius [m]")
    wall: Positive("m") = Field(description="wall thickness [m]")
    length: Positive("m") = Field(description="[m]")
    density: Positive("kg/m^3") = Field(description="[kg/m^3]")


class Box(FileFormat):
    """A solid box."""

    size: Vector3 = Field(description="sides along x, y, z [m]")


class Shape(FileFormat):
    """Geometry for drawings and URDF visuals: exactly one of cylinder, tube or box."""

    cylinder: Cylinder | None = None
    tube: Tube | None = None
    box: Box | None = None
    xyz: Vector3 = Field((0.0, 0.0, 0.0), description="center of the shape [m]")
    rpy: Vector3 = Field((0.0, 0.0, 0.0), description="orientation, roll-pitch-yaw [rad]")

    @model_validator(mode="after")
    def _one(self) -> Shape:
        if sum(x is not None for x in (self.cylinder, self.tube, self.box)) != 1:
            raise ValueError("give exactly one shape, one of: cylinder, tube, box")
        return self


class Inertial(PhysicalPoint):
    """Nominal physical parameters in the module frame (fields other than mass default to 0)."""

    mass: Number = Field(description="nominal mass [kg]: > 0, >= 0 for a payload")


_FRAMES = {
    "proximal": (lambda kind: kind != "base", "the input frame; only a base has none"),
    "distal": (lambda kind: kind != "payload", "the output frame; only a payload has none"),
    "joint": (lambda kind: kind == "actuator", "only actuators have a joint"),
}


class ModuleFile(FileFormat):
    """A module file ``<name>.yaml`` of a module library."""

    name: Text | None = Field(None, description="the module name; must equal the file stem")
    kind: ModuleKind = Field(
        title="module kind", description="base, actuator, link, tool or payload"
    )
    description: Text = Field("", description="free text")
    shape: Shape | None = Field(None, description="geometry for drawings")
    inertial: Inertial = Field(description="nominal inertial parameters, module frame")
    joint: Joint | None = Field(None, description="the joint (actuators only)")
    proximal: Connector | None = Field(None, description="input flange (all kinds but base)")
    distal: Connector | None = Field(None, description="output flange (all kinds but payload)")
    uncertainty: LinkEntry | None = Field(
        None, description="the module's box in the uncertainty format, module frame"
    )
    drive: JointEntry | None = Field(
        None,
        description="the joint's drive (actuators only): armature [kg m^2], viscous damping "
        "[N m s/rad] and Coulomb friction [N m], each an interval, with their nominal: values; "
        "default nominal: the middle of an absolute interval, 0 for a field not given",
    )

    @model_validator(mode="after")
    def _fits_kind(self) -> ModuleFile:
        kind = self.kind
        a_kind = f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"
        for key, (needed, why) in _FRAMES.items():
            if needed(kind) and getattr(self, key) is None:
                raise FieldError(key, f"{a_kind} module needs '{key}' ({why})")
            if not needed(kind) and getattr(self, key) is not None:
                raise FieldError(key, f"{a_kind} module has no '{key}' ({why})")
        if self.drive is not None and self.joint is None:
            raise FieldError(
                "drive",
                f"{a_kind} module has no joint, so it has no drive (armature, damping, "
                "friction belong to an actuator's joint); remove 'drive'",
            )
        if kind == "base" and self.uncertainty is not None and self.uncertainty.entries():
            raise FieldError(
                "uncertainty",
                "a base is fixed to the world, so its parameters do not enter the dynamics; "
                "remove its uncertainty",
            )
        if kind == "payload" and self.uncertainty and self.uncertainty.barycentric is not None:
            raise FieldError(
                ("uncertainty", "barycentric"),
                "a payload box is physical (mass, com_*, i**): it becomes the uncertainty file's "
                "payload entry, which has no barycentric form",
            )
        mass, payload = self.inertial.mass, kind == "payload"
        if mass < 0 or (mass == 0 and not payload):
            raise FieldError(
                ("inertial", "mass"),
                f"{a_kind} module needs a mass {'>= 0' if payload else '> 0'} [kg]; got {mass:g}",
            )
        return self
