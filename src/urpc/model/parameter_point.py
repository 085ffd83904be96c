"""Parameter-point files: one point of an uncertainty box (the parameters of a true plant), read
against the box.

The names of the uncertainty format with single numbers (:class:`urpc.formats.parameter_point.
ParameterPointFile`); what is not given stays nominal.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, did_you_mean
from ..formats.base import read_yaml, validate
from ..formats.parameter_point import LinkPoint, ParameterPointFile, PayloadPoint
from ..formats.uncertainty import JOINT_FIELDS, PHYSICAL_FIELDS
from .catalog import shipped_file
from .inertia import inertia_problem
from .joint_dynamics import JointBox
from .parameter_box import LinkBox, ParameterBox, physical_coordinates
from .point import JOINTS, ParameterPoint
from .robot import Robot


def check_file_arguments(path: Any, robot: Any, function: str, parser: str | None) -> None:
    """Typed errors for API mistakes: a document instead of a path, something else than a
    :class:`~urpc.model.robot.Robot`."""
    if not isinstance(path, str | Path):
        instead = f"; for an already parsed document use urpc.{parser}(document, robot)"
        raise InputError(
            f"{function}() reads a file: expected a path or a shipped name (str or Path), got "
            f"{type(path).__name__}" + (instead if parser and isinstance(path, Mapping) else ""),
            field="path",
        )
    if not isinstance(robot, Robot):
        raise InputError(
            f"expected a Robot (urpc.load_robot(...)), got {type(robot).__name__} {robot!r:.60}",
            field="robot",
        )


def load_parameter_point(path: str | Path, robot: Robot, box: ParameterBox) -> ParameterPoint:
    """Read a parameter-point file (:class:`urpc.formats.parameter_point.ParameterPointFile`, the
    parameters of a true plant) for ``robot`` and ``box``: a path, or a shipped name
    (``"rr_planar"`` for its ``true_parameters.yaml``, ``"ur5/heavy_payload"``).

    The file uses the names of the uncertainty format, with single numbers::

        links:
          link2: {mass: 10, com_x: 0.525, iyy: 20/12}
        payload: {mass: 2.0, com_z: 0.03}

    A ``joints:`` section gives joint parameters (``armature``, ``damping``, ``friction``).
    Links and joints not listed stay at their nominal values. Returns the
    :class:`~urpc.model.point.ParameterPoint` of the listed links and payloads (coordinates in
    the kind of that link's box, physical for links without a box) and, when given, the
    ``(3, dof)`` joint parameters, for :meth:`ParameterBox.plant`.
    """
    check_file_arguments(path, robot, "load_parameter_point", None)
    if not isinstance(box, ParameterBox):
        raise InputError(
            f"expected a ParameterBox (urpc.load_uncertainty(path, robot)), got "
            f"{type(box).__name__}",
            field="box",
        )
    path = shipped_file(path, "true_parameters.yaml", "parameter point")
    source = str(path)
    spec = validate(ParameterPointFile, read_yaml(path), source)
    nominal_robot = box.nominal_robot(robot)
    entries: dict[str, LinkPoint | PayloadPoint] = dict(spec.links)
    if spec.payload is not None:
        if not box.payloads:
            raise InputError("this uncertainty box has no payload", source=source, field="payload")
        entries[box.payloads[0].name] = spec.payload
    _refuse_what_the_box_lacks(spec, nominal_robot, box, source)
    point: dict[str, np.ndarray] = {}
    for name, entry in entries.items():
        fieldname = "payload" if isinstance(entry, PayloadPoint) else f"links.{name}"
        if name not in nominal_robot.moving_link_names:
            raise InputError(
                f"unknown link '{name}'; " + did_you_mean(name, nominal_robot.moving_link_names),
                source=source,
                field=fieldname,
            )
        try:
            link_box = box.link_box(name)
        except KeyError:  # exact for the controller: the point may move it (outside the box)
            nominal = physical_coordinates(nominal_robot.link(name).inertia)
            link_box = LinkBox(name, "physical", nominal, nominal, nominal)
        barycentric = getattr(entry, "barycentric", None) is not None
        if barycentric != (link_box.kind == "barycentric"):
            raise InputError(
                f"the box of '{name}' is {link_box.kind}: give its point in "
                + (
                    "barycentric values under 'barycentric:'"
                    if not barycentric
                    else "mass, com_*, i**"
                ),
                source=source,
                field=fieldname,
            )
        coordinates = link_box.nominal.copy()
        for key, value in entry.values().items():
            coordinates[link_box.fields.index(key)] = value
        try:
            problem = inertia_problem(np.asarray(link_box.inertia(coordinates).inertia))
        except (RuntimeError, ValueError) as error:  # Pinocchio refuses a negative tensor
            problem = (
                f"{error} (given: {', '.join(f'{k} = {v:g}' for k, v in entry.values().items())})"
            )
        if problem:
            raise InputError(
                f"the inertia of '{name}' is not physical: {problem}",
                source=source,
                field=fieldname,
            )
        point[name] = coordinates
    joints = _joint_point(spec, nominal_robot, box, source) if spec.joints else None
    return ParameterPoint(point, joints)


def _refuse_what_the_box_lacks(
    spec: ParameterPointFile, nominal_robot: Robot, box: ParameterBox, source: str
) -> None:
    """Refuse joint values for a box without a ``joints:`` section: the controller then has no
    drive model at all (rigid joints), so the values cannot be checked against an interval and
    would silently change the plant. (A link the box does not list is exact for the controller:
    its values are accepted and recorded outside the box when they differ, :func:`box_excursions`.)
    """
    if spec.joints and box.joints is None:
        fields = ", ".join(
            f"joints.{joint}.{key}"
            for joint, entry in spec.joints.items()
            for key in entry.values()
        )
        raise InputError(
            f"the box ({box.source or 'given'}) has no 'joints:' section, so the joint drives "
            f"are exact for the controller; this point gives {fields or 'joints:'}: add a "
            "'joints:' section to the box (e.g. joints: {JOINT: {friction: [0, 1]}}) or remove "
            "joints: from the point",
            source=source,
            field="joints",
        )


def _joint_point(
    spec: ParameterPointFile, nominal_robot: Robot, box: ParameterBox, source: str
) -> np.ndarray:
    """The ``(3, dof)`` joint parameters of a point: the box's nominal, with the given values."""
    values = box.joint_box(nominal_robot).nominal.copy()
    names = nominal_robot.joint_names
    for name, entry in spec.joints.items():
        if name not in names:
            raise InputError(
                f"unknown joint '{name}'; " + did_you_mean(name, names),
                source=source,
                field=f"joints.{name}",
            )
        for key, value in entry.values().items():
            values[JOINT_FIELDS.index(key), names.index(name)] = value
    return values


def box_excursions(
    box: ParameterBox, point: ParameterPoint | Mapping[str, np.ndarray], robot: Robot | None = None
) -> dict[str, float]:
    """``link.field`` or ``joint.field`` -> distance [SI] outside ``box`` of each coordinate of
    ``point`` that is not in it (rounding of 1e-12 relative tolerated): links, payloads and the
    joint drives alike.

    Values the box has no interval for (a link it does not list, drives without a ``joints:``
    section) are exact for the controller: with ``robot`` (the controller's nominal model) they
    are compared with its values; without it, each such entry counts as outside (distance inf).
    """
    excursions: dict[str, float] = {}

    def record(names, values, lower, upper) -> None:
        values = np.asarray(values, dtype=float)
        tolerance = 1e-12 * np.maximum(1.0, np.abs(values))
        distance = np.maximum(lower - values, values - upper)
        for index in zip(*np.nonzero(~(distance <= tolerance)), strict=True):
            gap = float(distance[index])
            excursions[names(*index)] = gap if math.isfinite(gap) else math.inf

    point = ParameterPoint.coerce(point)
    boxed = {b.link: b for b in box.links}
    for name, values in point.links.items():
        if name in boxed:
            b = boxed[name]
            record(lambda k, b=b: f"{b.link}.{b.fields[k]}", values, b.lower, b.upper)
        elif robot is not None and name in robot.link_names:
            nominal = physical_coordinates(robot.link(name).inertia)
            record(lambda k, n=name: f"{n}.{PHYSICAL_FIELDS[k]}", values, nominal, nominal)
        else:
            excursions[name] = math.inf
    if point.joints is not None:
        joints = box.joints
        if joints is None and robot is not None:
            joints = JointBox.exact(robot.joint_names, robot.joint_parameters)
        if joints is None:
            excursions[JOINTS] = math.inf
        else:
            record(joints.name, point.joints, joints.lower, joints.upper)
    return excursions


def outside_box(
    box: ParameterBox, point: ParameterPoint | Mapping[str, np.ndarray], robot: Robot | None = None
) -> list[str]:
    """Names ``link.field`` / ``joint.field`` of the coordinates of ``point`` that lie outside
    ``box`` (:func:`box_excursions`)."""
    return list(box_excursions(box, point, robot))


#: Relative tolerance on the smallest pseudo-inertia eigenvalue (vertices sit on the boundary).
PSEUDO_INERTIA_TOLERANCE = 1e-12
#: Uniform draws tried before a box is declared (almost) nowhere a rigid body.
MAX_DRAWS = 1000


def physically_consistent(box: ParameterBox, point: ParameterPoint | Mapping[str, Any]) -> bool:
    """Whether every link point of ``point`` is a realizable rigid body: its pseudo-inertia
    matrix (Pinocchio's ``PseudoInertia``) is positive semi-definite, and a massless point
    carries no first or second moment either; joint parameters (if any) are ``>= 0``."""
    import pinocchio as pin

    point = ParameterPoint.coerce(point)
    for name, values in point.links.items():
        try:
            link_box = box.link_box(name)
        except KeyError:
            raise InputError(
                f"no box for link '{name}'; " + did_you_mean(name, [b.link for b in box.links]),
                field=f"point.{name}",
            ) from None
        parameters = link_box.standard_parameters(values)
        if not np.all(np.isfinite(parameters)):
            return False
        pseudo = pin.PseudoInertia.FromDynamicParameters(parameters).toMatrix()
        eigenvalues = np.linalg.eigvalsh(pseudo)
        scale = max(1.0, float(np.abs(eigenvalues).max()))
        if eigenvalues[0] < -PSEUDO_INERTIA_TOLERANCE * scale:
            return False
        if parameters[0] <= 0 and np.abs(pseudo).max() > PSEUDO_INERTIA_TOLERANCE * scale:
            return False
    return point.joints is None or bool(np.all(point.joints >= 0))


def sample_rigid_point(
    box: ParameterBox, rng: np.random.Generator | int, tries: int = MAX_DRAWS
) -> tuple[ParameterPoint, int]:
    """A point drawn uniformly from the rigid bodies of ``box``: uniform draws from the box,
    rejected until one is :func:`physically_consistent` (on a box that is partly no rigid body,
    e.g. wide mass and CoM intervals with a narrow inertia, a plain draw can be none).

    Args:
        box: The parameter box.
        rng: A NumPy generator, or a seed.
        tries: Draws allowed before giving up.

    Returns:
        The point (as :meth:`ParameterBox.sample`) and the number of draws rejected before it.

    Raises:
        InputError: no rigid body in ``tries`` draws (the box is almost nowhere physical).
    """
    if not isinstance(rng, np.random.Generator):
        rng = np.random.default_rng(rng)
    for rejected in range(tries):
        point = box.sample(rng)
        if physically_consistent(box, point):
            return point, rejected
    raise InputError(
        f"no physically consistent point in {tries} uniform draws from the box (pseudo-inertia "
        "not positive semi-definite): tighten the inertia intervals so that the triangle "
        "inequality holds, or give a true_parameters file",
        source=box.source,
        field="links",
    )
