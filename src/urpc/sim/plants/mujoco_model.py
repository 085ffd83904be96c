"""The MuJoCo model of a robot: MuJoCo compiles the robot's URDF itself, then every body receives
the inertia the :class:`~urpc.model.robot.Robot` gives its link."""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ElementTree
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ...errors import InputError
from ...model.robot import Robot
from .plant import DEFAULT_MAX_STEP

if TYPE_CHECKING:
    import mujoco


def import_mujoco() -> ModuleType:
    """The ``mujoco`` module, or an :class:`InputError` saying how to install it."""
    try:
        import mujoco
    except ImportError:
        raise InputError(
            "the MuJoCo plant needs the optional package 'mujoco': "
            "install with pip install 'urpc[mujoco]'",
            field="plant",
        ) from None
    return mujoco


#: MuJoCo's ``solimp`` of the joints' friction constraint (``dof_solimp``).
FRICTION_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


# ============================================================================== MuJoCo model
def build_mujoco_model(robot: Robot) -> mujoco.MjModel:
    """Compile ``robot`` into a MuJoCo model from its URDF, with the robot's inertias.

    * MuJoCo parses the URDF (visuals and collisions removed: their ``package://`` meshes do not
      resolve and no geometry is needed) with ``fusestatic="false"``, so every URDF link is a
      MuJoCo body whose frame is the link frame. Locked joints become fixed joints at their locked
      position.
    * Every body gets the inertia :attr:`Robot.links` gives its link (mass, CoM in the link frame,
      rotational inertia about the CoM); bodies of links the robot does not list are massless,
      and links not in the URDF (a payload) become bodies fixed at their placement in their
      joint's frame. MuJoCo itself sums the links welded to each moving body.
    * The joints' drive from the robot's Pinocchio model: ``armature``, viscous ``damping`` and
      Coulomb friction as MuJoCo's ``frictionloss`` (a soft constraint solved by MuJoCo, an
      independent treatment of sticking). No contact, limit or spring; gravity is Pinocchio's
      ``model.gravity``; the integrator is RK4.

    Raises:
        InputError: ``mujoco`` is not installed; MuJoCo rejects the URDF; a joint MuJoCo makes
            differs from Pinocchio's; the robot's links do not add up to its Pinocchio bodies.
    """
    mujoco = import_mujoco()
    _check_links_match_bodies(robot)
    try:
        spec = mujoco.MjSpec.from_string(_mujoco_urdf(robot))
    except Exception as exc:
        raise InputError(f"MuJoCo cannot parse this URDF: {exc}", source=robot.urdf_path) from None

    listed = {link.name: link for link in robot.links}
    for body in spec.bodies[1:]:  # [0] is the world body (it holds a URDF link named 'world')
        link = listed.pop(body.name, None)
        _set_inertia(body, pin.Inertia.Zero() if link is None else link.inertia)
    for link in listed.values():  # links that are not MuJoCo bodies: payloads (or the world)
        if link.joint_index == 0:
            continue  # fixed to the ground: no effect on the dynamics
        parent = spec.joint(robot.model.names[link.joint_index]).parent
        body = parent.add_body(
            name=link.name,
            pos=link.placement.translation.copy(),
            quat=pin.Quaternion(link.placement.rotation).coeffs()[[3, 0, 1, 2]],
        )
        _set_inertia(body, link.inertia)
    for joint in spec.joints:
        joint.limited = mujoco.mjtLimited.mjLIMITED_FALSE
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
        joint.damping = joint.stiffness = np.zeros(3)  # MuJoCo 4 polynomial coefficients
        joint.armature = joint.frictionloss = 0.0
    armature, damping, friction = robot.joint_parameters
    for k, name in enumerate(robot.joint_names):  # the drive: Pinocchio's model.armature ...
        joint = spec.joint(name)
        joint.armature = float(armature[k])
        joint.damping = np.array([damping[k], 0.0, 0.0])
        joint.frictionloss = float(friction[k])

    option = spec.option
    option.integrator = mujoco.mjtIntegrator.mjINT_RK4
    option.timestep = DEFAULT_MAX_STEP
    option.gravity = np.asarray(robot.model.gravity.linear, dtype=float)
    disabled = mujoco.mjtDisableBit
    option.disableflags |= (
        disabled.mjDSBL_CONTACT
        | disabled.mjDSBL_SPRING
        | disabled.mjDSBL_AUTORESET  # a diverged state stays non-finite, and is reported
    )
    if not np.any(friction):  # frictionloss is MuJoCo's only constraint here
        option.disableflags |= disabled.mjDSBL_CONSTRAINT
    if not np.any(damping):
        option.disableflags |= disabled.mjDSBL_DAMPER
    try:
        model = spec.compile()
    except Exception as exc:
        raise InputError(
            f"MuJoCo cannot compile this robot: {exc}", source=robot.urdf_path
        ) from None
    mujoco_joint_indices(model, robot)  # checks joint count, names and types
    # frictionloss as a stiff soft constraint (impedance 0.9999, time constant two steps; MuJoCo
    # clamps it to twice the step in use): with the defaults a light joint creeps at tenths of a
    # rad/s under a torque it should hold, against the set-valued law's rest.
    model.dof_solimp[:] = FRICTION_SOLIMP
    model.dof_solref[:] = (2.0 * DEFAULT_MAX_STEP, 1.0)
    return model


def mujoco_joint_indices(model: mujoco.MjModel, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """``qpos`` and ``qvel`` addresses of Pinocchio's joints, in Pinocchio's order.

    Raises:
        InputError: a joint missing from the MuJoCo model, or of another type.
    """
    import mujoco

    expected = {"revolute": mujoco.mjtJoint.mjJNT_HINGE, "continuous": mujoco.mjtJoint.mjJNT_HINGE}
    expected["prismatic"] = mujoco.mjtJoint.mjJNT_SLIDE
    qpos, dof = np.empty(robot.dof, dtype=int), np.empty(robot.dof, dtype=int)
    for j, (name, kind) in enumerate(zip(robot.joint_names, robot.joint_kinds, strict=True), 1):
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0 or model.jnt_type[jid] != expected[kind]:
            raise InputError(
                f"MuJoCo's model of this URDF has no {kind} joint '{name}' "
                "(MuJoCo supports hinge and slide joints)",
                source=robot.urdf_path,
                field=f"joint.{name}",
            )
        v = robot.model.joints[j].idx_v
        qpos[v], dof[v] = model.jnt_qposadr[jid], model.jnt_dofadr[jid]
    if model.nv != robot.dof:
        raise InputError(
            f"MuJoCo's model of this URDF has {model.nv} degrees of freedom, Pinocchio's "
            f"{robot.dof}",
            source=robot.urdf_path,
        )
    return qpos, dof


def _mujoco_urdf(robot: Robot) -> str:
    """The robot's URDF as MuJoCo should compile it (see :func:`build_mujoco_model`)."""
    try:
        root = ElementTree.parse(robot.urdf_path).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise InputError(f"cannot read the URDF ({exc})", source=robot.urdf_path) from None
    _warn_missing_meshes(root, robot.urdf_path)
    for element in list(root):
        if element.tag == "link":
            for child in list(element):
                if child.tag in ("visual", "collision"):
                    element.remove(child)
        elif element.tag == "joint":
            if element.get("name") in robot.locked_joints:
                _fix_joint(element, robot.locked_joints[element.get("name")])
        elif element.tag != "material":  # gazebo, transmission, an own <mujoco> block, ...
            root.remove(element)
    extension = ElementTree.SubElement(root, "mujoco")
    ElementTree.SubElement(
        extension,
        "compiler",
        angle="radian",
        discardvisual="true",
        fusestatic="false",
        balanceinertia="false",
        inertiafromgeom="false",
        boundmass="0",
        boundinertia="0",
    )
    return ElementTree.tostring(root, encoding="unicode")


class MissingMeshWarning(UserWarning):
    """Meshes a URDF names cannot be found (the MuJoCo plant itself does not need them)."""


def _warn_missing_meshes(root: ElementTree.Element, urdf_path) -> None:
    """One warning naming the meshes of the URDF that cannot be found: an unexpanded xacro
    ``$(find ...)``, a ``package://`` path no folder above the URDF holds, a missing file. The
    plant does not need them (visuals and collisions are removed, the dynamics come from the
    ``<inertial>`` elements), but a URDF with unresolved paths is often not the one meant."""
    from pathlib import Path

    base = Path(urdf_path).resolve().parent
    missing = []
    for link in root.iter("link"):
        for mesh in link.iter("mesh"):
            name = mesh.get("filename", "")
            if name and not _mesh_found(name, base):
                missing.append(f"{link.get('name')}: {name}")
    if missing:
        shown = ", ".join(missing[:3]) + (
            f" and {len(missing) - 3} more" if len(missing) > 3 else ""
        )
        warnings.warn(
            f"{urdf_path}: {len(missing)} mesh file(s) of the URDF cannot be found ({shown}); "
            "the MuJoCo plant does not use meshes (its dynamics come from each <inertial>), but "
            "an unexpanded $(find ...) or package:// path often means the URDF is not the one "
            "meant (run xacro first)",
            MissingMeshWarning,
            stacklevel=3,
        )


def _mesh_found(name: str, base) -> bool:
    from pathlib import Path

    if "$(" in name:
        return False
    if name.startswith("package://"):
        relative = name.removeprefix("package://")
        return any((folder / relative).is_file() for folder in (base, *base.parents))
    path = Path(name.removeprefix("file://"))
    return (path if path.is_absolute() else base / path).is_file()


def _fix_joint(joint: ElementTree.Element, value: float) -> None:
    """Turn a locked revolute or prismatic joint into a fixed one at ``value`` [rad or m]
    (clipped into its limits, as :func:`urpc.model.robot.load_robot` locks it)."""
    limit = joint.find("limit")
    if limit is not None and joint.get("type") in ("revolute", "prismatic"):
        value = min(max(value, float(limit.get("lower", "0"))), float(limit.get("upper", "0")))
    origin = joint.find("origin")
    if origin is None:
        origin = ElementTree.SubElement(joint, "origin")
    xyz = np.array(origin.get("xyz", "0 0 0").split(), dtype=float)
    rpy = np.array(origin.get("rpy", "0 0 0").split(), dtype=float)
    axis_element = joint.find("axis")
    axis = np.array(
        (axis_element.get("xyz", "1 0 0") if axis_element is not None else "1 0 0").split(),
        dtype=float,
    )
    axis /= np.linalg.norm(axis)
    placement = pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz)
    if joint.get("type") == "prismatic":
        motion = pin.SE3(np.eye(3), axis * value)
    else:
        motion = pin.SE3(pin.exp3(axis * value), np.zeros(3))
    locked = placement * motion
    origin.set("xyz", " ".join(repr(float(x)) for x in locked.translation))
    origin.set("rpy", " ".join(repr(float(x)) for x in pin.rpy.matrixToRpy(locked.rotation)))
    joint.set("type", "fixed")


def _set_inertia(body: mujoco.MjsBody, inertia: pin.Inertia) -> None:
    """Give a MuJoCo body a spatial inertia expressed in its frame: mass [kg], CoM ``ipos`` [m],
    principal moments [kg m^2] and the rotation to the principal axes ``iquat``."""
    moments, axes = np.linalg.eigh(np.asarray(inertia.inertia))
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]
    body.explicitinertial = True
    body.mass = float(inertia.mass)
    body.ipos = np.asarray(inertia.lever, dtype=float).copy()
    body.inertia = np.maximum(moments, 0.0)
    body.iquat = pin.Quaternion(axes).coeffs()[[3, 0, 1, 2]]
    body.fullinertia = np.r_[np.nan, np.zeros(5)]  # unset: ``inertia`` and ``iquat`` hold


def _check_links_match_bodies(robot: Robot, tolerance: float = 1e-9) -> None:
    """The MuJoCo model is built per link; check the links add up to Pinocchio's bodies."""
    for j in range(1, robot.model.njoints):
        total = pin.Inertia.Zero()
        for link in robot.links:
            if link.joint_index == j:
                total += link.placement.act(link.inertia)
        body = robot.model.inertias[j]
        difference = np.abs(total.toDynamicParameters() - body.toDynamicParameters()).max()
        if difference > tolerance * max(1.0, np.abs(body.toDynamicParameters()).max()):
            raise InputError(
                f"the links carried by joint '{robot.model.names[j]}' do not add up to its "
                f"Pinocchio body inertia (difference {difference:.3g}); build true plants with "
                "Robot.with_link_inertias or Robot.with_payload",
                source=robot.urdf_path,
                field=f"joint.{robot.model.names[j]}",
            )
