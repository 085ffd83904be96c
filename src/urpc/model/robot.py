"""Robot models: a URDF loaded into Pinocchio, with nominal M, C, g and per-link inertial data.

All rigid-body math is Pinocchio's. This module adds what the controller needs on top:

* joint coordinates as *angles* (a continuous joint, two numbers ``cos, sin`` in Pinocchio, is one
  angle here), so every vector handed to a controller has length ``dof = model.nv``;
* the inertial data of every URDF link, kept separately even when Pinocchio merges links joined by
  fixed joints into one body, so that an uncertainty box can be stated per URDF link;
* copies with other link inertias or an attached payload (the "true plant").
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError, did_you_mean
from ..native import captured_stderr
from .catalog import resolve_robot

# inertia_problem: also imported from here by uncertainty, modular and studies.scenario.
from .inertia import inertia_problem  # noqa: F401
from .link_inertial import LinkInertial, body_inertia
from .urdf import check_mimic_joints, lock_joints, read_urdf_inertials

#: Pinocchio joint models accepted (fixed joints are merged away by the URDF parser).
_SUPPORTED = {
    "JointModelRX": "revolute",
    "JointModelRY": "revolute",
    "JointModelRZ": "revolute",
    "JointModelRevoluteUnaligned": "revolute",
    "JointModelRUBX": "continuous",
    "JointModelRUBY": "continuous",
    "JointModelRUBZ": "continuous",
    "JointModelRevoluteUnboundedUnaligned": "continuous",
    "JointModelPX": "prismatic",
    "JointModelPY": "prismatic",
    "JointModelPZ": "prismatic",
    "JointModelPrismaticUnaligned": "prismatic",
}


class Robot:
    """A fixed-base robot arm: a Pinocchio model plus per-link inertial data.

    Use :func:`load_robot` to make one. Vectors ``q`` [rad or m], ``qd`` [rad/s or m/s] have
    length :attr:`dof`. ``M``, ``C``, ``g`` are the joint-space inertia matrix [kg m^2], the
    Christoffel-consistent Coriolis matrix (``Mdot - 2 C`` is skew) and the gravity torque [N m].

    Attributes:
        model: The Pinocchio model (treat it as read-only; use :meth:`with_link_inertias`).
        name: Robot name (the URDF's, or the built-in name).
        urdf_path: The URDF the model was built from.
        links: Inertial data of every URDF link attached to a moving or fixed body.
    """

    def __init__(
        self,
        model: pin.Model,
        links: Sequence[LinkInertial],
        name: str,
        urdf_path: Path,
        locked_joints: Mapping[str, float] | None = None,
        urdf_dynamics: np.ndarray | None = None,
    ):
        self.model = model
        self.data = model.createData()
        self.name = name
        self.urdf_path = Path(urdf_path)
        self.links = tuple(links)
        self.locked_joints = dict(locked_joints or {})
        #: ``(2, dof)``: the URDF's ``<dynamics damping friction>`` per joint (0 where absent).
        #: Not part of the dynamics until an uncertainty box's ``joints:`` section says so
        #: (:func:`~urpc.model.joint_dynamics.resolve_joint_box`); they are its nominal values.
        self.urdf_dynamics = (
            np.zeros((2, model.nv)) if urdf_dynamics is None else np.array(urdf_dynamics, float)
        )
        self._link_by_name = {link.name: link for link in self.links}
        kinds = []
        for j in range(1, model.njoints):
            shortname = model.joints[j].shortname()
            if shortname not in _SUPPORTED:
                raise InputError(
                    f"joint '{model.names[j]}' has type {shortname}; urpc supports fixed-base arms "
                    "with revolute, continuous and prismatic joints",
                    source=urdf_path,
                    field=f"joint.{model.names[j]}",
                )
            kinds.append(_SUPPORTED[shortname])
        self.joint_kinds = tuple(kinds)
        self._continuous = [
            (model.joints[j].idx_q, model.joints[j].idx_v)
            for j in range(1, model.njoints)
            if _SUPPORTED[model.joints[j].shortname()] == "continuous"
        ]
        self._simple = not self._continuous
        self._lower_indices = np.tril_indices(model.nv, -1)

    # ----------------------------------------------------------------------------- description
    @property
    def dof(self) -> int:
        """Number of joint coordinates (angles or positions) seen by controllers."""
        return self.model.nv

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.model.names[j] for j in range(1, self.model.njoints))

    @property
    def link_names(self) -> tuple[str, ...]:
        return tuple(link.name for link in self.links)

    @property
    def moving_link_names(self) -> tuple[str, ...]:
        """Links carried by a joint (their inertia enters the dynamics)."""
        return tuple(link.name for link in self.links if link.joint_index > 0)

    @property
    def position_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper joint limits [rad or m]; continuous joints are unbounded (inf)."""
        lower = np.full(self.dof, -np.inf)
        upper = np.full(self.dof, np.inf)
        for j in range(1, self.model.njoints):
            joint = self.model.joints[j]
            if joint.nq == joint.nv:
                lower[joint.idx_v] = self.model.lowerPositionLimit[joint.idx_q]
                upper[joint.idx_v] = self.model.upperPositionLimit[joint.idx_q]
        return lower, upper

    @property
    def velocity_limit(self) -> np.ndarray:
        """Joint velocity limits from the URDF [rad/s or m/s]."""
        return np.asarray(self.model.velocityLimit).copy()

    @property
    def effort_limit(self) -> np.ndarray:
        """Joint effort limits from the URDF [N m or N]."""
        return np.asarray(self.model.effortLimit).copy()

    def link(self, name: str) -> LinkInertial:
        """Inertial data of a URDF link by name."""
        try:
            return self._link_by_name[name]
        except KeyError:
            raise InputError(
                f"unknown link '{name}' of robot '{self.name}'; "
                + did_you_mean(name, self.link_names),
                source=self.urdf_path,
            ) from None

    @property
    def nominal_parameters(self) -> np.ndarray:
        """Stacked standard parameters of the moving bodies, ``10 * dof``-vector (Pinocchio order,
        body ``j`` about its joint frame), the column order of Pinocchio's regressors."""
        return np.concatenate(
            [self.model.inertias[j].toDynamicParameters() for j in range(1, self.model.njoints)]
        )

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, dof={self.dof}, joints={list(self.joint_names)})"

    # ----------------------------------------------------------------------------- dynamics
    def configuration(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio configuration vector (length ``model.nq``) for joint angles ``q`` (length
        ``dof``): continuous joints become ``(cos, sin)``."""
        if self._simple:
            return q
        config = np.empty(self.model.nq)
        q_idx, v_idx = self._v_to_q_index()
        config[q_idx] = q[v_idx]
        for idx_q, idx_v in self._continuous:
            config[idx_q] = np.cos(q[idx_v])
            config[idx_q + 1] = np.sin(q[idx_v])
        return config

    def _v_to_q_index(self) -> tuple[np.ndarray, np.ndarray]:
        if not hasattr(self, "_v_to_q"):
            q_idx, v_idx = [], []
            for j in range(1, self.model.njoints):
                joint = self.model.joints[j]
                if joint.nq == joint.nv:
                    q_idx.extend(range(joint.idx_q, joint.idx_q + joint.nq))
                    v_idx.extend(range(joint.idx_v, joint.idx_v + joint.nv))
            self._v_to_q = (np.array(q_idx, dtype=int), np.array(v_idx, dtype=int))
        return self._v_to_q

    def angles(self, configuration: np.ndarray) -> np.ndarray:
        """Joint angles (length ``dof``) of a Pinocchio configuration (inverse of
        :meth:`configuration`)."""
        if self._simple:
            return np.asarray(configuration, dtype=float).copy()
        q = np.empty(self.dof)
        q_idx, v_idx = self._v_to_q_index()
        q[v_idx] = configuration[q_idx]
        for idx_q, idx_v in self._continuous:
            q[idx_v] = np.arctan2(configuration[idx_q + 1], configuration[idx_q])
        return q

    def M(self, q: np.ndarray) -> np.ndarray:
        """Joint-space inertia matrix ``M(q)`` [kg m^2], symmetric, ``dof x dof``, the joints'
        armature included (Pinocchio adds ``model.armature`` to the diagonal)."""
        # Pinocchio fills the upper triangle of a fresh array; mirror it (cached indices: this is
        # on the control step's hot path with the implicit sampled-data law).
        try:
            M = pin.crba(self.model, self.data, self.configuration(q))
        except (ValueError, TypeError, IndexError) as exc:
            raise self._state_error(exc, q=q) from None
        lower = self._lower_indices
        M[lower] = M.T[lower]
        return M

    def C(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Christoffel-consistent Coriolis matrix ``C(q, qd)`` [kg m^2/s] (``Mdot - 2C`` skew)."""
        try:
            config = self.configuration(q)
            return pin.computeCoriolisMatrix(self.model, self.data, config, qd).copy()
        except (ValueError, TypeError, IndexError) as exc:
            raise self._state_error(exc, q=q, qd=qd) from None

    def g(self, q: np.ndarray) -> np.ndarray:
        """Generalized gravity torque ``g(q)`` [N m or N]."""
        try:
            config = self.configuration(q)
            return pin.computeGeneralizedGravity(self.model, self.data, config).copy()
        except (ValueError, TypeError, IndexError) as exc:
            raise self._state_error(exc, q=q) from None

    def inverse_dynamics(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """``M(q) qdd + C(q, qd) qd + g(q)`` [N m or N] (Pinocchio RNEA)."""
        try:
            return pin.rnea(self.model, self.data, self.configuration(q), qd, qdd).copy()
        except (ValueError, TypeError, IndexError) as exc:
            raise self._state_error(exc, q=q, qd=qd, qdd=qdd) from None

    def forward_dynamics(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Joint accelerations [rad/s^2 or m/s^2] under torque ``tau`` (Pinocchio ABA)."""
        try:
            return pin.aba(self.model, self.data, self.configuration(q), qd, tau).copy()
        except (ValueError, TypeError, IndexError) as exc:
            raise self._state_error(exc, q=q, qd=qd, tau=tau) from None

    def _state_error(self, exc: Exception, **vectors) -> Exception:
        """Once a dynamics call failed: the InputError naming the vector of the wrong size or
        type (instead of Pinocchio's multi-line C++ message), else ``exc``."""
        from .regressor import state_vector_error

        return state_vector_error(self, **vectors) or exc

    # ----------------------------------------------------------------------------- copies
    def with_link_inertias(self, inertias: Mapping[str, pin.Inertia]) -> Robot:
        """A copy whose named links have other inertias (each in its link frame).

        This is how a "true plant" is made: the same kinematics, other inertial parameters.
        """
        for name in inertias:
            self.link(name)  # raises on an unknown name
        links = [
            LinkInertial(lk.name, lk.joint_index, lk.placement, inertias.get(lk.name, lk.inertia))
            for lk in self.links
        ]
        return self._rebuilt(links)

    def with_payload(self, name: str, link: str, inertia: pin.Inertia) -> Robot:
        """A copy with an extra rigid body ``name`` fixed to ``link`` (inertia in that link's
        frame). The payload is then a link like any other (it can be uncertain)."""
        if name in self._link_by_name:
            raise InputError(f"a link named '{name}' already exists on robot '{self.name}'")
        parent = self.link(link)
        payload = LinkInertial(name, parent.joint_index, parent.placement, inertia)
        return self._rebuilt([*self.links, payload])

    @property
    def joint_parameters(self) -> np.ndarray:
        """``(3, dof)``: armature [kg m^2], viscous damping [N m s/rad] and Coulomb friction
        [N m] of every joint in the dynamics (:mod:`urpc.model.joint_dynamics`): zero for a
        loaded robot (rigid), set by an uncertainty box's ``joints:`` section
        (:meth:`ParameterBox.nominal_robot`, :meth:`ParameterBox.plant`)."""
        model = self.model
        return np.array([model.armature, model.damping, model.friction], dtype=float)

    @property
    def has_joint_friction(self) -> bool:
        """Whether any joint has viscous damping or Coulomb friction."""
        return bool(np.any(self.model.damping) or np.any(self.model.friction))

    def with_joint_parameters(self, values: np.ndarray) -> Robot:
        """A copy whose joints have other armature, damping and friction (``(3, dof)``, rows as
        :attr:`joint_parameters`); ``M(q)`` of the copy includes the armature."""
        values = np.asarray(values, dtype=float).reshape(3, self.dof)
        model = self.model.copy()
        model.armature, model.damping, model.friction = (v.copy() for v in values)
        return Robot(
            model, self.links, self.name, self.urdf_path, self.locked_joints, self.urdf_dynamics
        )

    def _rebuilt(self, links: Sequence[LinkInertial]) -> Robot:
        model = self.model.copy()
        for j in range(model.njoints):
            model.inertias[j] = body_inertia(links, j)
        return Robot(
            model, links, self.name, self.urdf_path, self.locked_joints, self.urdf_dynamics
        )


def _locked_joints(locked_joints, urdf) -> dict[str, float | None]:
    """``locked_joints`` as names -> position (``None``: the joint's default), or one error
    naming the argument (a single name given as a text, a position that is no number)."""
    field = "locked_joints"
    if isinstance(locked_joints, str | bytes):
        raise InputError(
            f"{locked_joints!r} is a text; give a list of joint names ([{locked_joints!r}]) or "
            "a mapping of names to positions",
            source=urdf,
            field=field,
        )
    if isinstance(locked_joints, Mapping):
        locked = {}
        for name, value in locked_joints.items():
            try:
                position = float(value)
            except (TypeError, ValueError):
                position = math.nan
            if isinstance(value, str | bytes | bool) or not math.isfinite(position):
                raise InputError(
                    f"{value!r} is not a finite position [rad or m] for joint {name!r}",
                    source=urdf,
                    field=f"{field}.{name}",
                )
            locked[str(name)] = position
        return locked
    try:
        return {str(name): None for name in locked_joints}
    except TypeError:
        raise InputError(
            f"{locked_joints!r} is not a list of joint names or a mapping of names to positions",
            source=urdf,
            field=field,
        ) from None


def load_robot(
    source: str | Path, locked_joints: Sequence[str] | Mapping[str, float] = ()
) -> Robot:
    """Load a fixed-base robot arm from a URDF path, a built-in name or an example-robot-data name.

    Args:
        source: A URDF file, a built-in robot (``rr_planar``) or an example-robot-data URDF name
            (``ur5``, ``panda``, ...); ``urpc robots`` lists the names.
        locked_joints: Joints to lock (removed from the model), by name; a mapping gives the
            locked position [rad or m] (an angle for a continuous joint), a sequence locks them
            at 0. A position outside the joint's limits is refused, not clipped.

    Raises:
        InputError: unknown robot, malformed URDF, unsupported joint type, a closed kinematic
            loop, a mimic joint that is not locked with the joint it mimics, unknown locked joint
            or a lock position outside the joint's limits, non-physical inertia in the URDF.
    """
    entry = resolve_robot(source)
    urdf_links = read_urdf_inertials(entry.urdf)
    try:  # urdfdom prints its own lines on stderr: urpc says it in its one error line
        with captured_stderr() as parser_output:
            model = pin.buildModelFromUrdf(str(entry.urdf))
    except Exception as exc:  # Pinocchio raises plain RuntimeError/ValueError on bad XML
        said = parser_output.first_line
        raise InputError(
            f"Pinocchio cannot parse this URDF: {exc}"
            + (f" (the URDF parser: {said})" if said else ""),
            source=entry.urdf,
        ) from None
    locked = _locked_joints(locked_joints, entry.urdf)
    if locked:
        model, locked = lock_joints(model, locked, entry.urdf)
    check_mimic_joints(entry.urdf, locked)
    if model.nv == 0:
        raise InputError("the robot has no moving joint", source=entry.urdf, field="joint")
    links = []
    for frame in model.frames:
        if frame.type == pin.FrameType.BODY and frame.name in urdf_links:
            links.append(
                LinkInertial(frame.name, frame.parentJoint, frame.placement, urdf_links[frame.name])
            )
    name = entry.name if entry.origin != "file" else (model.name or entry.name)
    # The URDF's <dynamics>: kept as nominal values for a box's joints: section, out of the
    # dynamics otherwise (a rigid arm unless the box says what its drives are).
    urdf_dynamics = np.array([model.damping, model.friction], dtype=float)
    model.damping[:] = 0.0
    model.friction[:] = 0.0
    robot = Robot(model, links, name, entry.urdf, locked, urdf_dynamics)
    _check_bodies(robot)
    return robot


def _check_bodies(robot: Robot) -> None:
    """Every joint must move some mass, otherwise ``M(q)`` is singular."""
    model = robot.model
    M = robot.M(robot.angles(pin.neutral(model)))
    try:
        np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        diagonal = np.diag(M)
        j = int(np.argmin(diagonal))
        raise InputError(
            f"joint '{robot.joint_names[j]}' moves no mass or inertia, so M(q) is singular: give the "
            "links it carries an <inertial> with positive mass and inertia",
            source=robot.urdf_path,
            field=f"joint.{robot.joint_names[j]}",
        ) from None
