"""The URDF of a modular arm: module bodies joined at their flanges (written with yourdfpy).

Connecting module ``b`` after module ``a`` makes ``b``'s input frame coincide with ``a``'s output
frame, so ``b``'s module frame sits at ``X_a = D_a P_b^-1`` in ``a``'s module frame (``D``, ``P``
the output and input frame placements).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from .modules import Module
from .urdf import yourdfpy_module

#: Name of the massless link at the output frame of the last module (payloads are fixed to it).
TCP_LINK = "tcp"
#: Name of the payload body in the combined uncertainty box.
PAYLOAD_NAME = "payload"
#: Rotation entries this close to 0 or +-1 are made exact (rpy round trip).
SNAP = 1e-12


@dataclass(frozen=True)
class Part:
    """Where one module of an assembly went.

    Attributes:
        module: Module name.
        kind: Module kind.
        link: Its URDF link (``m<i>_<module>``), or the payload's name in the box.
        joint: The URDF joint attaching that link to the previous one (``joint<k>`` for an
            actuator, ``m<i>_<module>_fixed`` otherwise), ``None`` for the base and a payload.
    """

    module: str
    kind: str
    link: str
    joint: str | None


def compose_urdf(chain: Sequence[Module], name: str) -> tuple[Any, tuple[Part, ...]]:
    """The yourdfpy URDF of a validated chain of modules, and where each module went.

    The link of module ``i`` is ``m<i>_<module>`` (its frame is the module frame), revolute
    joints are ``joint1 .. jointN`` (with ``<dynamics>`` from an actuator's drive), a massless :data:`TCP_LINK` marks the output frame of the last
    body, and a payload module is left out of the URDF (:data:`PAYLOAD_NAME` in the box).
    """
    yourdfpy = yourdfpy_module()

    links, joints, parts = [], [], []
    parent: Module | None = None
    parent_link = ""
    n_joints = 0
    for i, module in enumerate(chain):
        if module.kind == "payload":
            parts.append(Part(module.name, module.kind, PAYLOAD_NAME, None))
            continue
        link = f"m{i}_{module.name}"
        links.append(
            yourdfpy.Link(name=link, inertial=_inertial(module), visuals=_visuals(module, link))
        )
        joint_name = None
        if parent is not None:
            origin = homogeneous(parent.distal.placement * module.proximal.placement.inverse())
            if module.kind == "actuator":
                n_joints += 1
                joint_name = f"joint{n_joints}"
                spec = module.joint
                joints.append(
                    yourdfpy.Joint(
                        name=joint_name,
                        type="revolute",
                        parent=parent_link,
                        child=link,
                        origin=origin,
                        axis=np.array(spec.axis),
                        dynamics=_dynamics(module),
                        limit=yourdfpy.Limit(
                            effort=spec.effort,
                            velocity=spec.velocity,
                            lower=spec.lower,
                            upper=spec.upper,
                        ),
                    )
                )
            else:
                joint_name = f"{link}_fixed"
                joints.append(
                    yourdfpy.Joint(
                        name=joint_name, type="fixed", parent=parent_link, child=link, origin=origin
                    )
                )
        parts.append(Part(module.name, module.kind, link, joint_name))
        parent, parent_link = module, link
    links.append(yourdfpy.Link(name=TCP_LINK))
    joints.append(
        yourdfpy.Joint(
            name=f"{TCP_LINK}_fixed",
            type="fixed",
            parent=parent_link,
            child=TCP_LINK,
            origin=homogeneous(parent.distal.placement),
        )
    )
    robot = yourdfpy.Robot(name=name, links=links, joints=joints)
    urdf = yourdfpy.URDF(robot=robot, build_scene_graph=False, load_meshes=False)
    return urdf, tuple(parts)


def _dynamics(module: Module) -> Any:
    """``<dynamics damping friction>`` of an actuator's joint: its drive's nominal viscous
    damping [N m s/rad] and Coulomb friction [N m] (none without a drive); ``Robot.urdf_dynamics``
    of the loaded assembly, the box's ``joints:`` entry being what enters the dynamics."""
    yourdfpy = yourdfpy_module()

    drive = module.drive
    return None if drive is None else yourdfpy.Dynamics(drive.damping, drive.friction)


def _inertial(module: Module) -> Any:
    yourdfpy = yourdfpy_module()

    inertia = module.inertia
    origin = np.eye(4)
    origin[:3, 3] = inertia.lever
    return yourdfpy.Inertial(
        origin=origin, mass=float(inertia.mass), inertia=np.asarray(inertia.inertia).copy()
    )


def _visuals(module: Module, link: str) -> list[Any]:
    yourdfpy = yourdfpy_module()

    shape = module.shape
    if shape is None:
        return []
    d = shape.dimensions
    if shape.kind == "box":
        geometry = yourdfpy.Geometry(box=yourdfpy.Box(size=np.array(d["size"])))
    else:
        radius = d["radius"] + (d["wall"] / 2 if shape.kind == "tube" else 0.0)
        geometry = yourdfpy.Geometry(cylinder=yourdfpy.Cylinder(radius=radius, length=d["length"]))
    return [
        yourdfpy.Visual(
            name=f"{link}_visual", origin=homogeneous(shape.placement), geometry=geometry
        )
    ]


def snapped(matrix: np.ndarray) -> np.ndarray:
    """Entries within :data:`SNAP` of 0 or +-1 made exact.

    Rotations by multiples of 90 degrees (the usual flange orientations) then survive yourdfpy's
    matrix -> rpy conversion exactly, also at the rpy singularity (pitch = +-90 degrees).
    """
    matrix = np.where(np.abs(matrix) < SNAP, 0.0, matrix)
    return np.where(np.abs(np.abs(matrix) - 1.0) < SNAP, np.sign(matrix), matrix)


def homogeneous(placement: pin.SE3) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = snapped(placement.rotation)
    matrix[:3, 3] = np.where(np.abs(placement.translation) < SNAP, 0.0, placement.translation)
    return matrix
