"""The uncertainty file: which link inertial and joint parameters are uncertain, and by how much.

Documented in ``docs/uncertainty-format.md``; read by :func:`urpc.model.uncertainty.load_uncertainty`,
which resolves every interval against the URDF's nominal value. Module files carry one
:class:`LinkEntry` as their ``uncertainty``.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, model_validator

from .base import FieldError, FileFormat
from .values import IntervalEntry, NonNegative, Number, Text

_MASS = "mass [kg]"
_COM = "center of mass in the link frame, {} [m]"
_INERTIA = "rotational inertia about the center of mass, link-frame axes, {} [kg m^2]"


def _interval(description: str, required: bool = False) -> Any:
    return Field(... if required else None, description=description)


class PhysicalBox(FileFormat):
    """Intervals on the physical parameters of a body (fields not given are exact)."""

    mass: IntervalEntry | None = _interval(_MASS)
    com_x: IntervalEntry | None = _interval(_COM.format("x"))
    com_y: IntervalEntry | None = _interval(_COM.format("y"))
    com_z: IntervalEntry | None = _interval(_COM.format("z"))
    ixx: IntervalEntry | None = _interval(_INERTIA.format("xx"))
    ixy: IntervalEntry | None = _interval(_INERTIA.format("xy"))
    iyy: IntervalEntry | None = _interval(_INERTIA.format("yy"))
    ixz: IntervalEntry | None = _interval(_INERTIA.format("xz"))
    iyz: IntervalEntry | None = _interval(_INERTIA.format("yz"))
    izz: IntervalEntry | None = _interval(_INERTIA.format("zz"))


#: Physical coordinates in Pinocchio's order: mass, CoM, inertia about the CoM (xx, xy, yy, xz,
#: yz, zz).
PHYSICAL_FIELDS: tuple[str, ...] = tuple(PhysicalBox.model_fields)

_H = "first moment of mass h = m c about the link origin, {} [kg m]"
_I_O = "rotational inertia about the link origin, {} [kg m^2]"


class BarycentricBox(FileFormat):
    """Intervals on the ten standard parameters about the link origin (Pinocchio's order)."""

    m: IntervalEntry | None = _interval(_MASS)
    h_x: IntervalEntry | None = _interval(_H.format("x"))
    h_y: IntervalEntry | None = _interval(_H.format("y"))
    h_z: IntervalEntry | None = _interval(_H.format("z"))
    I_xx: IntervalEntry | None = _interval(_I_O.format("xx"))
    I_xy: IntervalEntry | None = _interval(_I_O.format("xy"))
    I_yy: IntervalEntry | None = _interval(_I_O.format("yy"))
    I_xz: IntervalEntry | None = _interval(_I_O.format("xz"))
    I_yz: IntervalEntry | None = _interval(_I_O.format("yz"))
    I_zz: IntervalEntry | None = _interval(_I_O.format("zz"))


#: Standard (barycentric) parameters about the link origin, Pinocchio's order.
BARYCENTRIC_FIELDS: tuple[str, ...] = tuple(BarycentricBox.model_fields)


class LinkEntry(PhysicalBox):
    """The box of one link: physical intervals, or ``barycentric:`` intervals, not both."""

    barycentric: BarycentricBox | None = Field(
        None, description="a box on the standard parameters instead of the physical ones"
    )

    @model_validator(mode="after")
    def _one_kind(self) -> LinkEntry:
        check_one_kind(self, "a link box")
        return self

    def entries(self) -> dict[str, Any]:
        """The given intervals by field name (of the barycentric box when there is one)."""
        box = self.barycentric if self.barycentric is not None else self
        fields = BARYCENTRIC_FIELDS if self.barycentric is not None else PHYSICAL_FIELDS
        return {key: getattr(box, key) for key in fields if getattr(box, key) is not None}


def check_one_kind(entry: Any, what: str) -> None:
    """``entry`` (:class:`LinkEntry`, a parameter point's link) gives physical fields or a
    ``barycentric:`` section, not both (``what`` names it in the error: ``"a link box"``).

    Raises:
        FieldError: both given, on ``barycentric``.
    """
    physical = [key for key in PHYSICAL_FIELDS if getattr(entry, key) is not None]
    if entry.barycentric is not None and physical:
        raise FieldError(
            "barycentric",
            f"{what} is either physical or barycentric, not both (also found {physical})",
        )


class PhysicalPoint(FileFormat):
    """Single values of the physical parameters (fields not given: see where it is used)."""

    mass: Number | None = Field(None, description=_MASS)
    com_x: Number | None = Field(None, description=_COM.format("x"))
    com_y: Number | None = Field(None, description=_COM.format("y"))
    com_z: Number | None = Field(None, description=_COM.format("z"))
    ixx: Number | None = Field(None, description=_INERTIA.format("xx"))
    ixy: Number | None = Field(None, description=_INERTIA.format("xy"))
    iyy: Number | None = Field(None, description=_INERTIA.format("yy"))
    ixz: Number | None = Field(None, description=_INERTIA.format("xz"))
    iyz: Number | None = Field(None, description=_INERTIA.format("yz"))
    izz: Number | None = Field(None, description=_INERTIA.format("zz"))


class PayloadEntry(PhysicalBox):
    """A rigid body fixed to a link, with a physical box (unlisted fields are 0)."""

    name: Text = Field("payload", description="its name in the model; not a URDF link name")
    link: str = Field(description="the link the payload is fixed to")
    mass: IntervalEntry = _interval("mass [kg]; 0 is allowed (no object held)", required=True)
    nominal: PhysicalPoint | None = Field(
        None, description="the controller's nominal payload; default: the middle of each interval"
    )

    @model_validator(mode="before")
    @classmethod
    def _physical_only(cls, data: Any) -> Any:
        if isinstance(data, dict) and "barycentric" in data:
            raise FieldError(
                "barycentric",
                "a payload box is physical (mass, com_*, i**); barycentric payloads are not "
                "supported",
            )
        return data


_ARMATURE = "armature: rotor inertia reflected to the joint [kg m^2] (kg for a prismatic joint)"
_DAMPING = "viscous damping coefficient [N m s/rad] (N s/m for a prismatic joint)"
_FRICTION = "Coulomb (dry) friction torque [N m] (N for a prismatic joint)"


class JointPoint(FileFormat):
    """Single values of a joint's parameters (each >= 0)."""

    armature: NonNegative("kg m^2") | None = Field(None, description=_ARMATURE)
    damping: NonNegative("N m s/rad") | None = Field(None, description=_DAMPING)
    friction: NonNegative("N m") | None = Field(None, description=_FRICTION)

    def values(self) -> dict[str, float]:
        return {k: v for k, v in self.model_dump().items() if v is not None}


class JointEntry(FileFormat):
    """The box of one joint's drive: armature, viscous damping and Coulomb friction (fields not
    given stay exact at their nominal)."""

    armature: IntervalEntry | None = _interval(_ARMATURE)
    damping: IntervalEntry | None = _interval(_DAMPING)
    friction: IntervalEntry | None = _interval(_FRICTION)
    nominal: JointPoint | None = Field(
        None,
        description="the controller's nominal values; default: the URDF's <dynamics> damping "
        "and friction (armature 0), or the middle of an absolute interval that excludes it",
    )

    def entries(self) -> dict[str, Any]:
        """The given intervals by field name."""
        return {key: getattr(self, key) for key in JOINT_FIELDS if getattr(self, key) is not None}


#: The joint parameters, in the order of :class:`urpc.model.joint_dynamics.JointBox` rows.
JOINT_FIELDS: tuple[str, ...] = ("armature", "damping", "friction")

#: A bound on the input disturbance ``||d||`` [N m], or ``unknown`` (``None``).
Disturbance = NonNegative("N m", keyword="unknown")


class UncertaintyFile(FileFormat):
    """An uncertainty file: what the controller knows about the robot's parameters."""

    robot: Text | None = Field(None, description="the robot the box is for (informative)")
    description: Text | None = Field(None, description="free text")
    disturbance: Disturbance = Field(
        None, description="bound on ||d|| [N m], or 'unknown' (default)"
    )
    links: dict[str, LinkEntry] = Field(
        default_factory=dict, description="URDF link name -> its box (moving links only)"
    )
    payload: PayloadEntry | None = Field(None, description="one uncertain body fixed to a link")
    joints: dict[str, JointEntry] = Field(
        default_factory=dict,
        description="joint name -> the box of its drive: armature, damping, friction "
        "(joints not listed keep the URDF's <dynamics>, exactly)",
    )
