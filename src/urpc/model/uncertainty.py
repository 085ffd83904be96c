"""Uncertainty files and parameter-point files, read into parameter boxes and points.

Which link inertial parameters are uncertain, and by how much. The file format is documented in ``docs/uncertainty-format.md``. In short::

    disturbance: unknown            # or a bound on ||d|| [N m]
    links:
      link2:                        # a URDF link name
        mass: [5, 10]               # absolute interval [kg]
        com_x: ["+0", "+0.025"]     # offsets from the URDF nominal [m]
        iyy: [0%, +300%]            # relative to the URDF nominal
      link3:
        barycentric:                # or a box on the 10 standard parameters
          m: 10%
    payload:
      name: payload
      link: link2
      mass: [0, 3]
      com_z: [0, 0.05]

The schemas are :class:`urpc.formats.uncertainty.UncertaintyFile` and
:class:`urpc.formats.parameter_point.ParameterPointFile`; this module resolves them against the
robot (link names, URDF nominal values, physical consistency). The box values live in
:mod:`urpc.model.parameter_box` and are importable from here too.
"""

from __future__ import annotations

import copy
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import InputError, did_you_mean
from ..formats.base import read_yaml, validate
from ..formats.uncertainty import (
    BARYCENTRIC_FIELDS,
    PHYSICAL_FIELDS,
    LinkEntry,
    PayloadEntry,
    PhysicalBox,
    UncertaintyFile,
)
from ..formats.values import Interval
from ..validation import check_type
from .box_consistency import (
    NonPhysicalBoxWarning,
    corner_check,
    describe_non_physical_part,
    negative_lower_end,
    too_large,
)
from .catalog import shipped_file
from .inertia import inertia_problem
from .joint_dynamics import resolve_joint_box
from .parameter_box import (
    UNITS,
    Kind,
    LinkBox,
    ParameterBox,
    Payload,
    barycentric_from_physical,
    inertia_from_physical,
    physical_coordinates,
)
from .parameter_point import check_file_arguments, load_parameter_point, outside_box
from .robot import Robot

__all__ = [
    "BARYCENTRIC_FIELDS",
    "PHYSICAL_FIELDS",
    "UNITS",
    "LinkBox",
    "NonPhysicalBoxWarning",
    "ParameterBox",
    "Payload",
    "barycentric_from_physical",
    "inertia_from_physical",
    "load_parameter_point",
    "load_uncertainty",
    "outside_box",
    "parse_uncertainty",
    "physical_coordinates",
    "resolve_link_box",
]


# ============================================================================ loading
def load_uncertainty(path: str | Path, robot: Robot) -> ParameterBox:
    """Read and validate an uncertainty file (:class:`urpc.formats.uncertainty.UncertaintyFile`)
    for ``robot``: a path, or a robot name for its shipped box (``"rr_planar"``).

    Raises:
        InputError: naming the file and the field, for: malformed YAML, an unknown key or link,
            a wrong type, lo > hi, a non-positive mass, a nominal outside its box, a
            non-physical nominal inertia.
    """
    check_file_arguments(path, robot, "load_uncertainty", "parse_uncertainty")
    path = shipped_file(path, "uncertainty.yaml", "uncertainty box")
    document = read_yaml(path)
    if document is None:
        raise InputError(
            "the file is empty; an empty file is not read as 'no uncertainty': write "
            "'links: {}' to say every parameter is exact, or list the uncertain links",
            source=path,
        )
    return parse_uncertainty(document, robot, source=str(path))


def parse_uncertainty(document: Any, robot: Robot, source: str | None = None) -> ParameterBox:
    """Validate an uncertainty document (already parsed YAML) against ``robot``.

    Raises:
        InputError: as :func:`load_uncertainty`, and a box whose ``robot:`` names another robot
            ("this box is for robot X").
    """
    check_type("robot", robot, Robot, "a Robot (urpc.load_robot(...))")
    if document is None:  # (other non-mappings: the format's own message, key: value lines)
        raise InputError(
            "expected a mapping with 'links' (and optionally 'payload', 'joints', "
            "'disturbance'), got None; {'links': {}} says every parameter is exact",
            source=source,
            field="document",
        )
    hints = {"payload.link": robot.moving_link_names, "joints": robot.joint_names}
    spec = validate(UncertaintyFile, document, source, hints=hints)
    if spec.robot is not None and not _same_robot(spec.robot, robot):
        raise InputError(
            f"this box is for robot '{spec.robot}', not for '{robot.name}' (URDF "
            f"{robot.urdf_path.name}); give a box written for {robot.name} (urpc init "
            f"{robot.name} --out box.yaml starts one)",
            source=source,
            field="robot",
        )
    boxes: list[LinkBox] = []
    payloads: list[Payload] = []
    if spec.payload is not None:
        payload, payload_box = _payload(spec.payload, robot, source)
        payloads.append(payload)
        robot = robot.with_payload(payload.name, payload.link, payload_box.nominal_inertia)
        boxes.append(payload_box)
    for name, entry in spec.links.items():
        if name not in robot.link_names:
            raise InputError(
                f"unknown link '{name}'; " + did_you_mean(name, robot.moving_link_names),
                source=source,
                field=f"links.{name}",
            )
        link = robot.link(name)
        if link.joint_index == 0:
            raise InputError(
                f"link '{name}' is fixed to the base, so its parameters do not enter the dynamics; "
                f"uncertain links must be moving: {', '.join(robot.moving_link_names)}",
                source=source,
                field=f"links.{name}",
            )
        boxes.append(resolve_link_box(entry, name, link.inertia, source, f"links.{name}"))
    return ParameterBox(
        links=tuple(boxes),
        payloads=tuple(payloads),
        disturbance_bound=spec.disturbance,
        source=source,
        robot_name=robot.name,
        joints=resolve_joint_box(spec.joints, robot, source) if spec.joints else None,
        robot=robot,
        document=copy.deepcopy(document),
    )


def _same_robot(declared: str, robot: Robot) -> bool:
    """Whether a box's ``robot:`` may name ``robot``: its name, its URDF's robot name or file
    stem; a URDF path (``urpc init path/arm.urdf`` writes one) is compared by file stem only."""
    text = declared.strip()
    if text.endswith(".urdf") or "/" in text or "\\" in text:
        return Path(text).stem == robot.urdf_path.stem
    return text in {robot.name, robot.model.name, robot.urdf_path.stem}


def _payload(entry: PayloadEntry, robot: Robot, source: str | None) -> tuple[Payload, LinkBox]:
    if entry.link not in robot.link_names or robot.link(entry.link).joint_index == 0:
        raise InputError(
            f"unknown or fixed link '{entry.link}'; "
            + did_you_mean(entry.link, robot.moving_link_names),
            source=source,
            field="payload.link",
        )
    if entry.name in robot.link_names:
        raise InputError(
            f"the payload name '{entry.name}' is already a link name; choose another",
            source=source,
            field="payload.name",
        )
    # The payload's nominal: explicit values, else the middle of each absolute interval.
    given = {} if entry.nominal is None else entry.nominal.model_dump()
    center = np.zeros(10)
    for k, key in enumerate(PHYSICAL_FIELDS):
        interval = getattr(entry, key)
        if given.get(key) is not None:
            center[k] = given[key]
        elif interval is not None:
            lo, hi = _resolved(interval, None, source, f"payload.{key}")
            center[k] = 0.5 * (lo + hi)
    nominal = inertia_from_physical(center)
    box = resolve_link_box(entry, entry.name, nominal, source, "payload", allow_zero_mass=True)
    return Payload(entry.name, entry.link), box


def resolve_link_box(
    entry: LinkEntry | PhysicalBox,
    name: str,
    nominal_inertia: pin.Inertia,
    source: str | None,
    prefix: str,
    allow_zero_mass: bool = False,
) -> LinkBox:
    """The :class:`LinkBox` of a validated box entry around a nominal inertia.

    Raises:
        InputError: lo > hi, a relative interval without a nominal, a nominal outside its
            interval, a non-positive mass (negative with ``allow_zero_mass``), a non-physical
            nominal inertia; naming ``source`` and the field under ``prefix``.
    """
    barycentric = getattr(entry, "barycentric", None) is not None
    kind: Kind = "barycentric" if barycentric else "physical"
    if barycentric:
        keys, values = BARYCENTRIC_FIELDS, np.asarray(nominal_inertia.toDynamicParameters()).copy()
        prefix = f"{prefix}.barycentric"
        given = {k: v for k, v in entry.barycentric if v is not None}
    else:
        keys, values = PHYSICAL_FIELDS, physical_coordinates(nominal_inertia)
        given = {k: getattr(entry, k) for k in PHYSICAL_FIELDS if getattr(entry, k) is not None}
    lower, upper = values.copy(), values.copy()
    for k, key in enumerate(keys):
        if key not in given:
            continue
        lower[k], upper[k] = _resolved(given[key], values[k], source, f"{prefix}.{key}")
        if not lower[k] <= values[k] <= upper[k] and not np.isclose(
            values[k], np.clip(values[k], lower[k], upper[k]), rtol=1e-12, atol=1e-15
        ):
            raise InputError(
                f"the nominal value {values[k]:.6g} lies outside the box "
                f"[{lower[k]:.6g}, {upper[k]:.6g}]; widen the interval or change the URDF",
                source=source,
                field=f"{prefix}.{key}",
            )
    if lower[0] < 0 or (not allow_zero_mass and lower[0] <= 0):
        raise InputError(
            f"mass interval [{lower[0]:.6g}, {upper[0]:.6g}] kg must be "
            + ("non-negative" if allow_zero_mass else "strictly positive (m > 0)"),
            source=source,
            field=f"{prefix}.{keys[0]}",
        )
    box = LinkBox(name, kind, values, lower, upper)
    negative = negative_lower_end(box)
    if negative is not None:
        key, message = negative
        raise InputError(f"the box of '{name}': {message}", source=source, field=f"{prefix}.{key}")
    problem = too_large(box)
    if problem:
        raise InputError(f"the box of '{name}': {problem}", source=source, field=prefix)
    inertia = box.nominal_inertia
    # Barycentric: I_C = I_O - m S(c)^T S(c); physical iff the pseudo-inertia is PSD.
    massless = kind == "barycentric" and inertia.mass <= 0
    problem = inertia_problem(np.zeros((3, 3)) if massless else np.asarray(inertia.inertia))
    if problem:
        # The nominal lies in its box: a box whose nominal is a rigid body has one in it.
        raise InputError(
            f"the nominal inertia of '{name}' is not physical: {problem}",
            source=source,
            field=prefix,
        )
    check = corner_check(box)
    if not check.all_physical:
        part = describe_non_physical_part(box, check)
        box = LinkBox(name, kind, values, lower, upper, non_physical=part)
        where = ": ".join([*([source] if source else []), f"field '{prefix}'"])
        warnings.warn(
            NonPhysicalBoxWarning(
                f"{where}: part of the box of '{name}' is no rigid body: {part}; accepted, as the "
                "bound over the whole box (a superset of its rigid bodies) stays sound, but "
                "narrow the intervals to state only rigid bodies"
            ),
            stacklevel=2,
        )
    return box


def _resolved(
    interval: Interval, nominal: float | None, source: str | None, fieldname: str
) -> tuple[float, float]:
    try:
        return interval.around(None if nominal is None else float(nominal))
    except ValueError as exc:
        raise InputError(str(exc), source=source, field=fieldname) from None
