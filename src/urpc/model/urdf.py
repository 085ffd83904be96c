"""Reading a URDF beyond what Pinocchio keeps: per-link inertias (each URDF link, even when
Pinocchio merges links joined by fixed joints), joint-type checks, and locking joints."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError, did_you_mean
from .inertia import inertia_problem

#: URDF joint types accepted.
_URDF_SUPPORTED = ("revolute", "continuous", "prismatic", "fixed")


def lock_joints(model: pin.Model, locked: Mapping[str, float], urdf: Path) -> pin.Model:
    """``model`` with the named 1-dof joints removed, each at its position [rad or m] clipped into
    its limits (Pinocchio's ``buildReducedModel``)."""
    names = [model.names[j] for j in range(1, model.njoints)]
    reference = pin.neutral(model)
    ids = []
    for name, value in locked.items():
        if name not in names:
            raise InputError(
                f"cannot lock unknown joint '{name}'; " + did_you_mean(name, names),
                source=urdf,
                field="locked_joints",
            )
        j = model.getJointId(name)
        joint = model.joints[j]
        if joint.nq != 1:
            raise InputError(f"only 1-dof joints can be locked, not '{name}'", source=urdf)
        lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
        reference[joint.idx_q] = min(max(value, lo), hi)
        ids.append(j)
    return pin.buildReducedModel(model, ids, reference)


def read_urdf_inertials(path: Path) -> dict[str, pin.Inertia]:
    """Per-link inertias from the URDF (yourdfpy), in link frames, with joint-type checks."""
    import xml.etree.ElementTree as ElementTree

    import yourdfpy

    # Check well-formedness first: the C++ URDF parser prints its own lines on stderr otherwise.
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as exc:
        raise InputError(f"malformed XML ({exc})", source=path) from None
    except OSError as exc:
        raise InputError(f"cannot read the file ({exc})", source=path) from None
    if root.tag != "robot" or not root.get("name"):
        raise InputError(
            f"not a URDF: the root element must be <robot name=...>, found <{root.tag}>",
            source=path,
        )
    try:
        urdf = yourdfpy.URDF.load(
            str(path), load_meshes=False, build_scene_graph=False, load_collision_meshes=False
        )
    except Exception as exc:
        raise InputError(f"not a readable URDF ({exc})", source=path) from None
    if urdf.robot is None or not urdf.robot.links:
        raise InputError("the URDF defines no link", source=path)
    for joint in urdf.robot.joints:
        if joint.type not in _URDF_SUPPORTED:
            raise InputError(
                f"joint '{joint.name}' has type '{joint.type}'; urpc supports fixed-base arms with "
                f"joint types {', '.join(_URDF_SUPPORTED)}",
                source=path,
                field=f"joint.{joint.name}.type",
            )
    inertias = {}
    for link in urdf.robot.links:
        inertial = link.inertial
        if inertial is None:
            inertias[link.name] = pin.Inertia.Zero()
            continue
        mass = float(inertial.mass if inertial.mass is not None else 0.0)
        origin = np.eye(4) if inertial.origin is None else np.asarray(inertial.origin, dtype=float)
        tensor = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia)
        rotated = origin[:3, :3] @ tensor @ origin[:3, :3].T
        field = f"link.{link.name}.inertial"
        if not np.isfinite(mass) or mass < 0:
            raise InputError(
                f"mass {mass} must be a finite number >= 0 [kg]", source=path, field=field
            )
        # Real URDFs often carry tiny triangle-inequality violations on massless frames, so only
        # an inertia that is not positive semi-definite is refused here; the uncertainty file
        # checks the full physical consistency of the links it makes uncertain.
        problem = inertia_problem(rotated, triangle=False)
        if problem:
            raise InputError(f"non-physical inertia: {problem}", source=path, field=field)
        inertias[link.name] = pin.Inertia(mass, origin[:3, 3].copy(), rotated)
    return inertias
