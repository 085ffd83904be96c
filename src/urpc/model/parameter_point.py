"""Parameter-point files: one point of an uncertainty box (a true plant), read against the box.

The names of the uncertainty format with single numbers (:class:`urpc.formats.parameter_point.
ParameterPointFile`); what is not given stays nominal.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, did_you_mean
from ..formats.base import read_yaml, validate
from ..formats.parameter_point import LinkPoint, ParameterPointFile, PayloadPoint
from ..formats.uncertainty import JOINT_FIELDS
from .catalog import shipped_file
from .inertia import inertia_problem
from .parameter_box import JOINTS, LinkBox, ParameterBox, physical_coordinates
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


def load_parameter_point(
    path: str | Path, robot: Robot, box: ParameterBox
) -> dict[str, np.ndarray]:
    """Read a parameter-point file (:class:`urpc.formats.parameter_point.ParameterPointFile`, a
    true plant) for ``robot`` and ``box``: a path, or a shipped name (``"rr_planar"`` for its
    ``true_parameters.yaml``, ``"ur5/heavy_payload"``).

    The file uses the names of the uncertainty format, with single numbers::

        links:
          link2: {mass: 10, com_x: 0.525, iyy: 20/12}
        payload: {mass: 2.0, com_z: 0.03}

    A ``joints:`` section gives joint parameters (``armature``, ``damping``, ``friction``).
    Links and joints not listed stay at their nominal values. Returns link or payload name ->
    coordinates (in the kind of that link's box, physical for links without a box), and
    :data:`~urpc.model.parameter_box.JOINTS` -> the ``(3, dof)`` joint parameters when given,
    for :meth:`ParameterBox.plant`.
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
        except KeyError:
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
        problem = inertia_problem(np.asarray(link_box.inertia(coordinates).inertia))
        if problem:
            raise InputError(
                f"the inertia of '{name}' is not physical: {problem}",
                source=source,
                field=fieldname,
            )
        point[name] = coordinates
    if spec.joints:
        point[JOINTS] = _joint_point(spec, nominal_robot, box, source)
    return point


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


def outside_box(box: ParameterBox, point: Mapping[str, np.ndarray]) -> list[str]:
    """Names ``link.field`` of the coordinates of ``point`` that lie outside ``box``."""
    outside = []
    for name, values in point.items():
        if name == JOINTS:
            joints = box.joints
            if joints is not None:
                rows, columns = np.nonzero(
                    (values < joints.lower - 1e-12) | (values > joints.upper + 1e-12)
                )
                outside += [joints.name(r, c) for r, c in zip(rows, columns, strict=True)]
            continue
        try:
            link_box = box.link_box(name)
        except KeyError:
            continue
        for k in np.flatnonzero(
            (values < link_box.lower - 1e-12) | (values > link_box.upper + 1e-12)
        ):
            outside.append(f"{name}.{link_box.fields[k]}")
    return outside
