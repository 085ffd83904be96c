"""Plants: the true robot, integrated under a torque held constant over each control period.

A :class:`Plant` holds the state ``(q, qd)`` of a fixed-base arm and advances it under a
zero-order-hold torque: :meth:`Plant.step` keeps ``tau`` constant over ``duration`` [s] and
integrates

    M(q) qdd + C(q, qd) qd + g(q) = tau

with classical Runge-Kutta 4 in steps of at most ``max_step`` [s]. Two backends:

* :class:`PinocchioPlant`: accelerations from Pinocchio's articulated-body algorithm on the
  :class:`~urpc.model.robot.Robot` (the reference plant of urpc).
* :class:`MujocoPlant`: an independent plant. MuJoCo compiles the robot's URDF itself (its own
  parser for joint origins, axes and fixed links), then every body receives the inertia the
  :class:`~urpc.model.robot.Robot` gives its URDF link, so true parameters and payloads are honored.
  ``mujoco`` is an optional dependency (``pip install 'urpc[mujoco]'``).

Build a plant with :func:`make_plant`; ``docs/plants.md`` gives the measured agreement.
"""

from __future__ import annotations

import inspect
import math
import xml.etree.ElementTree as ElementTree
from abc import ABC, abstractmethod
from types import ModuleType
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np
import pinocchio as pin

from ..errors import InputError, SimulationError
from ..model.robot import Robot
from ..validation import finite_vector, positive_number

if TYPE_CHECKING:
    import mujoco

#: Default largest integration step [s]: ten RK4 steps per 1 kHz control period.
DEFAULT_MAX_STEP = 1e-4

PlantKind = Literal["pinocchio", "mujoco"]


class PlantState(NamedTuple):
    """Joint positions ``q`` [rad or m] and velocities ``qd`` [rad/s or m/s], length ``dof``."""

    q: np.ndarray
    qd: np.ndarray


class Plant(ABC):
    """A simulated arm driven by a torque held constant over each step (zero-order hold).

    Coordinates follow :class:`~urpc.model.robot.Robot`: ``dof`` joint angles [rad] or positions [m]
    in Pinocchio's joint order (a continuous joint is one unbounded angle).

    Args:
        robot: The true plant: a robot carrying the true inertial parameters.
        max_step: Largest integration step [s]; a step of ``duration`` is split into
            ``ceil(duration / max_step)`` equal RK4 steps.

    Attributes:
        robot: The robot being simulated.
        max_step: Largest integration step [s].
        time: Simulated time since the last :meth:`reset` [s].

    Raises:
        InputError: ``max_step`` is not a finite number > 0.
    """

    #: Backend name, as accepted by :func:`make_plant`.
    kind: str = ""

    def __init__(self, robot: Robot, max_step: float = DEFAULT_MAX_STEP):
        self.robot = robot
        self.max_step = positive_number("max_step", max_step, "a finite number > 0 [s]")
        self._q = np.zeros(robot.dof)
        self._qd = np.zeros(robot.dof)
        self.time = 0.0
        self._last_duration = math.nan
        self._last_substeps = 1

    @property
    def dof(self) -> int:
        """Number of joint coordinates."""
        return self.robot.dof

    @property
    def state(self) -> PlantState:
        """A copy of the current ``(q, qd)``."""
        return PlantState(self._q.copy(), self._qd.copy())

    def reset(self, q: np.ndarray, qd: np.ndarray | None = None) -> PlantState:
        """Set the state (``qd`` defaults to zero) and the time [s] to 0.

        Raises:
            InputError: a vector of the wrong length or with non-finite entries.
        """
        self._q = finite_vector("q", q, self.dof)
        self._qd = np.zeros(self.dof) if qd is None else finite_vector("qd", qd, self.dof)
        self.time = 0.0
        self._load_state()
        return self.state

    def step(self, torque: np.ndarray, duration: float) -> PlantState:
        """Hold ``torque`` [N m or N] constant over ``duration`` [s] and return the new state.

        Raises:
            InputError: a torque of the wrong length or non-finite, a duration that is not > 0.
            SimulationError: the state became non-finite (the plant diverged).
        """
        # The simulator calls this once per control period: validate cheaply (shape and one
        # finiteness test on dot products) and cache the substep count of the last duration.
        if (
            type(torque) is np.ndarray
            and torque.shape == (self.dof,)
            and math.isfinite(torque @ torque)
        ):
            tau = torque
        else:
            tau = finite_vector("torque", torque, self.dof)
        if duration != self._last_duration:
            duration = positive_number("duration", duration, "a finite number > 0 [s]")
            self._last_substeps = max(1, math.ceil(duration / self.max_step - 1e-9))
            self._last_duration = duration
        substeps = self._last_substeps
        q, qd = self._advance(tau, duration / substeps, substeps)
        if not math.isfinite(q @ q + qd @ qd):
            raise SimulationError(
                f"the {self.kind} plant diverged at t = {self.time + duration:.6g} s "
                f"(q = {np.round(q, 6).tolist()}, qd = {np.round(qd, 6).tolist()})"
            )
        self._q, self._qd = q, qd
        self.time += duration
        # Fresh arrays every step (not copies of internal buffers the next step reuses); the
        # caller must not modify them in place.
        return PlantState(q, qd)

    @abstractmethod
    def _load_state(self) -> None:
        """Copy ``self._q, self._qd`` into the backend (after :meth:`reset`)."""

    @abstractmethod
    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        """``substeps`` RK4 steps of ``h`` [s] from the current state under constant ``tau``."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.robot.name!r}, max_step={self.max_step:g})"


class PinocchioPlant(Plant):
    """Classical RK4 on ``x = (q, qd)``, ``xd = (qd, ABA(q, qd, tau))`` (Pinocchio).

    One step of ``h``: ``k1 = f(x)``, ``k2 = f(x + h/2 k1)``, ``k3 = f(x + h/2 k2)``,
    ``k4 = f(x + h k3)``, ``x <- x + h/6 (k1 + 2 k2 + 2 k3 + k4)``; the error is ``O(h^4)``.
    """

    kind = "pinocchio"

    def __init__(self, robot: Robot, max_step: float = DEFAULT_MAX_STEP):
        super().__init__(robot, max_step)
        self._data = robot.model.createData()
        model = robot.model
        self._configuration = (lambda q: q) if model.nq == model.nv else robot.configuration

    def _load_state(self) -> None:
        """Nothing to do: the state lives in ``self._q, self._qd``."""

    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        model, data, configuration, aba = self.robot.model, self._data, self._configuration, pin.aba
        half, sixth = 0.5 * h, h / 6.0
        q, v = self._q, self._qd
        for _ in range(substeps):
            a1 = aba(model, data, configuration(q), v, tau)
            v2 = v + half * a1
            a2 = aba(model, data, configuration(q + half * v), v2, tau)
            v3 = v + half * a2
            a3 = aba(model, data, configuration(q + half * v2), v3, tau)
            v4 = v + h * a3
            a4 = aba(model, data, configuration(q + h * v3), v4, tau)
            q = q + sixth * (v + 2.0 * (v2 + v3) + v4)
            v = v + sixth * (a1 + 2.0 * (a2 + a3) + a4)
        return q, v


class MujocoPlant(Plant):
    """The same arm simulated by MuJoCo (model from :func:`build_mujoco_model`).

    MuJoCo's own RK4 (``mjINT_RK4``) advances the state with the torque applied as
    ``qfrc_applied``; with hinge and slide joints it is the same classical RK4 as
    :class:`PinocchioPlant`, so the two plants differ only by the dynamics algorithms
    (and their rounding), not by the integration scheme.

    Attributes:
        model: The compiled ``mujoco.MjModel``.
        data: The ``mujoco.MjData`` holding the simulated state.
    """

    kind = "mujoco"

    def __init__(self, robot: Robot, max_step: float = DEFAULT_MAX_STEP):
        super().__init__(robot, max_step)
        self._mujoco = import_mujoco()
        self.model = build_mujoco_model(robot)
        self.data = self._mujoco.MjData(self.model)
        self._query = self._mujoco.MjData(self.model)
        self._qpos_index, self._dof_index = mujoco_joint_indices(self.model, robot)
        self._load_state()

    def _load_state(self) -> None:
        self._mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self._qpos_index] = self._q
        self.data.qvel[self._dof_index] = self._qd

    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        self.model.opt.timestep = h
        self.data.qfrc_applied[self._dof_index] = tau
        self._mujoco.mj_step(self.model, self.data, substeps)
        return self.data.qpos[self._qpos_index].copy(), self.data.qvel[self._dof_index].copy()

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """MuJoCo's joint-space inertia matrix [kg m^2] at ``q``, in Pinocchio's joint order."""
        mj, data = self._mujoco, self._query
        data.qpos[self._qpos_index] = finite_vector("q", q, self.dof)
        mj.mj_forward(self.model, data)
        full = np.zeros((self.model.nv, self.model.nv))
        mj.mj_fullM(self.model, data, full)
        return full[np.ix_(self._dof_index, self._dof_index)]

    def bias_forces(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """MuJoCo's ``C(q, qd) qd + g(q)`` [N m or N] (``qfrc_bias``), in Pinocchio's order."""
        mj, data = self._mujoco, self._query
        data.qpos[self._qpos_index] = finite_vector("q", q, self.dof)
        data.qvel[self._dof_index] = finite_vector("qd", qd, self.dof)
        mj.mj_forward(self.model, data)
        return data.qfrc_bias[self._dof_index].copy()


# ============================================================================== factory
PLANTS: dict[str, type[Plant]] = {"pinocchio": PinocchioPlant, "mujoco": MujocoPlant}


def make_plant(kind: PlantKind | str, robot: Robot, **options: Any) -> Plant:
    """Build a plant of backend ``kind`` (``"pinocchio"`` or ``"mujoco"``) for ``robot``.

    Args:
        kind: Backend name, a key of :data:`PLANTS`.
        robot: The true plant (a robot with the true parameters).
        **options: Passed to the backend (``max_step`` [s]).

    Raises:
        InputError: an unknown kind or option, ``mujoco`` not installed, a robot MuJoCo cannot
            represent.
    """
    try:
        cls = PLANTS[kind]
    except (KeyError, TypeError):
        raise InputError(
            f"unknown plant {kind!r}; valid: {', '.join(PLANTS)}", field="plant"
        ) from None
    valid = [p for p in inspect.signature(cls.__init__).parameters if p not in ("self", "robot")]
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise InputError(
            f"unknown option(s) {', '.join(unknown)} for the {kind} plant; valid: {', '.join(valid)}",
            field="plant",
        )
    return cls(robot, **options)


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
    * No contact, constraint, limit, damping, armature, friction or spring; gravity is
      Pinocchio's ``model.gravity``; the integrator is RK4.

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

    option = spec.option
    option.integrator = mujoco.mjtIntegrator.mjINT_RK4
    option.timestep = DEFAULT_MAX_STEP
    option.gravity = np.asarray(robot.model.gravity.linear, dtype=float)
    disabled = mujoco.mjtDisableBit
    option.disableflags |= (
        disabled.mjDSBL_CONTACT
        | disabled.mjDSBL_CONSTRAINT
        | disabled.mjDSBL_SPRING
        | disabled.mjDSBL_DAMPER
        | disabled.mjDSBL_AUTORESET  # a diverged state stays non-finite, and is reported
    )
    try:
        model = spec.compile()
    except Exception as exc:
        raise InputError(
            f"MuJoCo cannot compile this robot: {exc}", source=robot.urdf_path
        ) from None
    mujoco_joint_indices(model, robot)  # checks joint count, names and types
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
