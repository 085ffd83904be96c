"""Parameter boxes: intervals on link inertial and joint parameters, and the disturbance bound.

A :class:`ParameterBox` holds one :class:`LinkBox` per uncertain link or payload, each in physical
coordinates (``mass`` [kg], center of mass ``com_x, com_y, com_z`` in the link frame [m], rotational
inertia about the center of mass in link-frame axes ``ixx, ixy, iyy, ixz, iyz, izz`` [kg m^2]) or in
barycentric ones (the standard parameters about the link origin ``m, h_x, h_y, h_z, I_xx, I_xy,
I_yy, I_xz, I_yz, I_zz`` with ``h = m c``, Pinocchio's order). Boxes are read from uncertainty files
by :mod:`urpc.model.uncertainty`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..formats.uncertainty import BARYCENTRIC_FIELDS, PHYSICAL_FIELDS
from .joint_dynamics import JointBox
from .point import JOINTS as JOINTS  # the older point key, read from here
from .point import ParameterPoint
from .robot import Robot

# PHYSICAL_FIELDS (mass, CoM in the link frame, inertia about the CoM in Pinocchio's component
# order xx, xy, yy, xz, yz, zz) and BARYCENTRIC_FIELDS are the fields of the file format.
UNITS = {
    "mass": "kg", "com_x": "m", "com_y": "m", "com_z": "m",
    "m": "kg", "h_x": "kg m", "h_y": "kg m", "h_z": "kg m",
}  # fmt: skip

Kind = Literal["physical", "barycentric"]


def link_points(point: ParameterPoint | Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The link and payload entries of a parameter point (``point.links`` of a
    :class:`ParameterPoint`; kept for older callers)."""
    return dict(ParameterPoint.coerce(point).links)


def joint_values(
    box: ParameterBox, point: ParameterPoint | Mapping[str, np.ndarray]
) -> dict[str, float]:
    """``joint.field -> value`` of the uncertain joint parameters of a point (empty without)."""
    joints = box.joints
    point = ParameterPoint.coerce(point, None if joints is None else joints.dof)
    if joints is None or point.joints is None:
        return {}
    values = point.joints
    rows, columns = np.nonzero(joints.uncertain)
    return {joints.name(r, c): float(values[r, c]) for r, c in zip(rows, columns, strict=True)}


def physical_coordinates(inertia: pin.Inertia) -> np.ndarray:
    """``[mass, com_x, com_y, com_z, ixx, ixy, iyy, ixz, iyz, izz]`` of a spatial inertia."""
    I = np.asarray(inertia.inertia)
    c = np.asarray(inertia.lever)
    return np.array(
        [inertia.mass, c[0], c[1], c[2], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]
    )


def inertia_from_physical(values: np.ndarray) -> pin.Inertia:
    """The spatial inertia of physical coordinates (inverse of :func:`physical_coordinates`)."""
    m, cx, cy, cz, ixx, ixy, iyy, ixz, iyz, izz = (float(v) for v in values)
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return pin.Inertia(m, np.array([cx, cy, cz]), tensor)


def barycentric_from_physical(values: np.ndarray) -> np.ndarray:
    """Standard parameters ``[m, m c, I_O]`` (about the link origin) of physical coordinates."""
    return np.asarray(inertia_from_physical(values).toDynamicParameters()).copy()


@dataclass(frozen=True, eq=False)
class LinkBox:
    """The uncertain inertial parameters of one link (or payload), in its link frame.

    Attributes:
        link: URDF link name (or payload name).
        kind: ``"physical"`` (coordinates :data:`PHYSICAL_FIELDS`) or ``"barycentric"``
            (coordinates :data:`BARYCENTRIC_FIELDS`).
        nominal: The nominal point, 10 coordinates of ``kind``.
        lower, upper: The box, 10 coordinates of ``kind`` each; exact fields have lower == upper.
        non_physical: Which part of the box is no rigid body (``None``: every point is one); the
            bound covers the whole box, a superset of its rigid bodies
            (:mod:`urpc.model.box_consistency`).
    """

    link: str
    kind: Kind
    nominal: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    non_physical: str | None = None

    @property
    def fields(self) -> tuple[str, ...]:
        return PHYSICAL_FIELDS if self.kind == "physical" else BARYCENTRIC_FIELDS

    @property
    def uncertain(self) -> np.ndarray:
        """Boolean mask of the coordinates with a non-zero width."""
        return self.upper > self.lower

    def inertia(self, values: np.ndarray) -> pin.Inertia:
        """The spatial inertia (link frame) at a point given in this box's coordinates."""
        if self.kind == "physical":
            return inertia_from_physical(values)
        return pin.Inertia.FromDynamicParameters(np.asarray(values, dtype=float))

    def standard_parameters(self, values: np.ndarray) -> np.ndarray:
        """Standard parameters (about the link origin, link frame) at a point of this box."""
        if self.kind == "physical":
            return barycentric_from_physical(values)
        return np.asarray(values, dtype=float).copy()

    @property
    def nominal_inertia(self) -> pin.Inertia:
        return self.inertia(self.nominal)


@dataclass(frozen=True)
class Payload:
    """A rigid body fixed to a link whose parameters are uncertain (a tool, a grasped object)."""

    name: str
    link: str


@dataclass(frozen=True, eq=False)
class ParameterBox:
    """Everything a controller may not know: link parameter intervals and the disturbance bound.

    Attributes:
        links: One :class:`LinkBox` per uncertain link or payload (others are exact).
        payloads: Payload bodies, attached to their links by :meth:`nominal_robot`.
        disturbance_bound: Bound on the input disturbance ``||d||`` [N m], or ``None`` when it is
            unknown (the paper's Theorem 2 case).
        source: The file the box was read from, if any.
        joints: The box of the joints' armature, damping and friction
            (:mod:`urpc.model.joint_dynamics`), or ``None``: the robot's own joint parameters
            (its URDF's ``<dynamics>``) are exact.
        robot: The robot the box was parsed for (``None`` for a box built by hand), so that
            ``box.plant(point)`` needs no robot.
        document: The parsed uncertainty document the box was built from (``None`` for a box
            built by hand): what a saved controller embeds (:meth:`IntervalPassivityController.
            save`), so that saving needs neither the file nor its unchanged contents.
    """

    links: tuple[LinkBox, ...]
    payloads: tuple[Payload, ...] = ()
    disturbance_bound: float | None = None
    source: str | None = None
    robot_name: str | None = field(default=None, compare=False)
    joints: JointBox | None = None
    robot: Robot | None = field(default=None, compare=False, repr=False)
    document: Any = field(default=None, compare=False, repr=False)

    def joint_box(self, robot: Robot) -> JointBox:
        """The joint box, or the exact one of ``robot``'s own joint parameters."""
        if self.joints is not None:
            return self.joints
        return JointBox.exact(robot.joint_names, robot.joint_parameters)

    def link_box(self, name: str) -> LinkBox:
        for box in self.links:
            if box.link == name:
                return box
        raise KeyError(name)

    @property
    def uncertain_links(self) -> tuple[LinkBox, ...]:
        return tuple(b for b in self.links if b.uncertain.any())

    def nominal_robot(self, robot: Robot) -> Robot:
        """The controller's model: ``robot`` with every payload attached at its nominal point and
        the nominal joint parameters of :attr:`joints`.

        Idempotent: a robot that already carries them is returned unchanged.

        Raises:
            InputError: ``robot`` lacks a link the box bounds or carries a payload on (a box
                made for another robot).
        """
        self._check_robot(robot)
        for payload in self.payloads:
            if payload.name not in robot.link_names:
                box = self.link_box(payload.name)
                robot = robot.with_payload(payload.name, payload.link, box.nominal_inertia)
        if self.joints is not None and not np.array_equal(
            robot.joint_parameters, self.joints.nominal
        ):
            robot = robot.with_joint_parameters(self.joints.nominal)
        return robot

    def _check_robot(self, robot: Robot) -> None:
        payloads = {payload.name for payload in self.payloads}
        needed = [b.link for b in self.links if b.link not in payloads]
        needed += [payload.link for payload in self.payloads]
        missing = sorted({name for name in needed if name not in robot.link_names})
        if missing:
            made_for = f" (made for {self.robot_name!r})" if self.robot_name else ""
            raise InputError(
                f"the parameter box{made_for} bounds links {missing} that robot "
                f"{robot.name!r} does not have; its links: {list(robot.link_names)}",
                self.source,
                "robot",
            )

    def plant(
        self,
        robot: Robot | ParameterPoint | Mapping[str, np.ndarray] | None = None,
        point: ParameterPoint | Mapping[str, np.ndarray] | None = None,
    ) -> Robot:
        """The robot at a parameter point (a :class:`ParameterPoint`, or the older ``dict`` of
        link or payload name -> coordinates of its box's kind and :data:`JOINTS` -> the
        ``(3, dof)`` joint parameters); what it does not name stays nominal. ``point=None``
        gives the nominal robot.

        ``box.plant(point)`` uses the robot the box was parsed for; ``box.plant(robot, point)``
        (the older form) checks that ``robot`` has the links the box bounds.

        Raises:
            InputError: no robot given and the box knows none, or ``robot`` lacks a bounded link.
        """
        if not isinstance(robot, Robot):
            if point is not None:
                raise InputError(
                    f"box.plant(robot, point) takes a Robot first, got {type(robot).__name__}",
                    self.source,
                    "robot",
                )
            robot, point = self.robot, robot
            if robot is None:
                raise InputError(
                    "this parameter box was not parsed for a robot; "
                    "call box.plant(robot, point) with the robot",
                    self.source,
                    "robot",
                )
        robot = self.nominal_robot(robot)
        if point is None:
            return robot
        point = ParameterPoint.coerce(point, robot.dof)
        if point.joints is not None:
            robot = robot.with_joint_parameters(point.joints)
        if not point.links:
            return robot
        boxed = {b.link: b for b in self.links}
        inertias = {}
        for name, values in point.links.items():
            # Links without a box are given in physical coordinates.
            inertia = (
                boxed[name].inertia(values) if name in boxed else inertia_from_physical(values)
            )
            # A negative (or NaN) mass is no body at all. (A vertex of a barycentric box may
            # carry an inertia that is not positive semi-definite: the bounds cover that
            # superset of the box's rigid bodies, and the tests build plants there.)
            if not inertia.mass >= 0:
                raise InputError(
                    f"the point gives '{name}' the mass {inertia.mass:g} kg; a mass must be >= 0 "
                    f"(values {np.asarray(values).tolist()})",
                    self.source,
                    f"point.{name}",
                )
            inertias[name] = inertia
        return robot.with_link_inertias(inertias)

    def vertex(self, index: int) -> ParameterPoint:
        """The ``index``-th vertex of the box over the uncertain coordinates (bit ``k`` of
        ``index`` picks lower (0) or upper (1) of the ``k``-th uncertain coordinate)."""
        point, joint_point, bit = {}, None, 0
        for box in self.links:
            values = box.nominal.copy()
            for k in np.flatnonzero(box.uncertain):
                values[k] = box.upper[k] if (index >> bit) & 1 else box.lower[k]
                bit += 1
            point[box.link] = values
        joints = self.joints
        if joints is not None and joints.uncertain.any():
            values = joints.nominal.copy()
            for row, column in zip(*np.nonzero(joints.uncertain), strict=True):
                chosen = joints.upper if (index >> bit) & 1 else joints.lower
                values[row, column] = chosen[row, column]
                bit += 1
            joint_point = values
        return ParameterPoint(point, joint_point)

    def random_vertices(self, rng: np.random.Generator):
        """Distinct random vertex indices of :meth:`vertex`, one random bit per uncertain
        coordinate (Python integers: any number of coordinates), until every vertex is drawn."""
        n, seen = self.n_uncertain, set()
        while len(seen) < 2**n:
            bits = rng.integers(0, 2, size=n)
            index = sum(int(b) << k for k, b in enumerate(bits))
            if index not in seen:
                seen.add(index)
                yield index

    @property
    def n_uncertain(self) -> int:
        """Number of uncertain coordinates, link and joint parameters (the box has
        ``2 ** n_uncertain`` vertices)."""
        joints = 0 if self.joints is None else int(self.joints.uncertain.sum())
        return int(sum(int(b.uncertain.sum()) for b in self.links)) + joints

    def sample(self, rng: np.random.Generator) -> ParameterPoint:
        """A point drawn uniformly from the box (not necessarily physically consistent), with
        joint parameters when the box has joint intervals."""
        point = {b.link: rng.uniform(b.lower, b.upper) for b in self.links}
        joints = None
        if self.joints is not None and self.joints.uncertain.any():
            joints = rng.uniform(self.joints.lower, self.joints.upper)
        return ParameterPoint(point, joints)
