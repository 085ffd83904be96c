"""The interface of every bound method: an enclosure ``[lower, upper]`` of the mismatch torque.

For a state ``(q, qd)`` and the reference signals ``(qd_a, qdd_a)`` of the controller, the
mismatch torque of the paper's eq. (7) is::

    w = (M - M0) qdd_a + (C - C0) qd_a + (g - g0) - d = Y_SL(q, qd, qd_a, qdd_a) (pi - pi0) - d

plus, when the joints have armature, damping or friction (:mod:`urpc.model.joint_dynamics`), the
joint terms ``(Ia - Ia0) qdd_a + Dv qd - Dv0 qd_a + f_c - Fc0 sat(qd_a / v_s)`` (the controller
compensates the nominal drive along the reference velocity ``qd_a``), which depend on
other parameters than the links' and are added exactly (:meth:`BoundMethod.add_joint_terms`).
The methods built on the regressor ``Y_SL`` share :class:`RegressorBound`.

A bound method returns ``lower, upper`` with ``lower_i <= w_i <= upper_i`` for every parameter
point of the box (and every ``||d|| <= beta_d`` when the disturbance bound is known, Theorem 1;
``d = 0`` when it is unknown, Theorem 2), and ``rho_i = max(|lower_i|, |upper_i|)`` (eq. 9).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from pathlib import Path
from typing import ClassVar

import numpy as np

from ..errors import InputError
from ..model.joint_dynamics import STICTION_VELOCITY, joint_terms
from ..model.regressor import placement_matrix
from ..model.robot import Robot
from ..model.uncertainty import ParameterBox

#: Relative inflation of the fast methods' enclosures, applied to the sum of absolute values of the
#: terms ``sum_j |Y_ij| p_j`` (it covers the rounding of every product and sum the methods compute
#: from ``Y_SL``: below ``n_terms * 2**-53`` relative, a few hundred terms stay below 1e-13).
ROUNDING_RELATIVE = 1e-9
#: Inflation per unit of the regressor's rounding envelope ``E``
#: (:attr:`~urpc.model.regressor.SlotineLiRegressor.envelope`) and of parameter magnitude:
#: ``ROUNDING_RECURSION E sum_j p_j`` over the columns a joint carries covers the rounding inside the
#: two regressor calls and their difference, which follows the size of the terms *before* the
#: subtraction (``|qd|^2`` at high joint rates), not of ``Y_SL``. Measured worst error of an entry:
#: 4.4 unit roundoffs (5e-16) times ``E`` (``docs/bounds.md`` section 7); 1e-12 is 2000 times that.
ROUNDING_RECURSION = 1e-12
#: Absolute inflation [N m], for terms that cancel to exactly zero.
ROUNDING_ABSOLUTE = 1e-12


class BoundMethod(ABC):
    """Encloses the mismatch torque ``w`` over a parameter box, at one state per call.

    Build once per robot and box (synthesis); call :meth:`enclose` or :meth:`rho` at every
    control step.

    Args:
        robot: The robot (payloads of ``box`` are attached at their nominal point if missing).
        box: The parameter box.
    """

    #: Name of the method, as chosen on the CLI and in scenario files.
    name: ClassVar[str]
    #: True for the methods built on ``Y_SL`` (:class:`RegressorBound`, with
    #: :meth:`~RegressorBound.enclose_regressor`).
    uses_regressor: ClassVar[bool] = False

    def __init__(self, robot: Robot, box: ParameterBox):
        check_robot_and_box(robot, box)
        self.robot = box.nominal_robot(robot)
        self.box = box
        self.disturbance_bound = box.disturbance_bound
        joints = box.joint_box(self.robot)
        #: The joint box when any joint has armature, damping or friction, else ``None``.
        self.joints = joints if joints.active else None
        self._joint_scratch = np.zeros(self.robot.dof)
        self._nominal_parameters = np.asarray(self.robot.nominal_parameters, dtype=float)

    @abstractmethod
    def enclose(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` [N m] enclosing ``w`` at this state, over the whole box."""

    @abstractmethod
    def torque_and_enclosure(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(tau0, lower, upper)`` [N m]: the nominal model's torque ``M0 qdd_a + C0 qd_a + g0``
        (drives included) and the enclosure of ``w`` at this state, in one call: what the
        interval law needs at each step."""

    def add_joint_terms(
        self,
        lower: np.ndarray,
        upper: np.ndarray,
        qd: np.ndarray,
        qd_a: np.ndarray,
        qdd_a: np.ndarray,
        torque: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Adds the enclosure of the joint terms (:meth:`~urpc.model.joint_dynamics.JointBox.
        enclose`) to ``lower, upper`` in place, and returns them; nothing without joint terms.
        :meth:`enclose_regressor` covers the links only. With ``torque``, the same compiled call
        also adds the nominal drive torque, armature included
        (:meth:`~urpc.model.joint_dynamics.JointBox.nominal_torque`), to it in place."""
        joints = self.joints
        if joints is not None:
            joint_terms(
                np.asarray(qd, dtype=float), np.asarray(qd_a, dtype=float),
                np.asarray(qdd_a, dtype=float), joints.nominal, joints.lower, joints.upper,
                STICTION_VELOCITY, 0.0 if torque is None else 1.0,
                self._joint_scratch if torque is None else torque, lower, upper,
            )  # fmt: skip
        return lower, upper

    def rho(self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray) -> np.ndarray:
        """``rho_i = max(|lower_i|, |upper_i|)`` [N m], the paper's eq. (9)."""
        lower, upper = self.enclose(q, qd, qd_a, qdd_a)
        # lower <= upper, so max(|lower|, |upper|) = max(-lower, upper).
        return np.maximum(-lower, upper)

    def _add_disturbance(
        self, lower: np.ndarray, upper: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Theorem 1: a known bound ``||d|| <= beta_d`` adds ``[-beta_d, beta_d]`` per joint."""
        if self.disturbance_bound:
            lower = lower - self.disturbance_bound
            upper = upper + self.disturbance_bound
        return lower, upper


class RegressorBound(BoundMethod):
    """A bound method built on the Slotine-Li regressor: ``w = Y_SL (pi - pi0)`` enclosed from
    ``Y_SL`` at the state (the vertex and hull methods); one ``Y_SL`` per step serves the
    nominal torque and the enclosure."""

    uses_regressor: ClassVar[bool] = True

    def enclose(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` [N m] enclosing ``w`` at this state, over the whole box."""
        regressor = self.regressor
        lower, upper = self.enclose_regressor(regressor(q, qd, qd_a, qdd_a), regressor.envelope)
        return self.add_joint_terms(lower, upper, qd, qd_a, qdd_a)

    def torque_and_enclosure(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As :meth:`BoundMethod.torque_and_enclosure`: one ``Y_SL`` serves both, and its
        rounding envelope is the one of this very evaluation (passed explicitly, so the answer
        does not depend on earlier calls)."""
        regressor = self.regressor
        Y = regressor(q, qd, qd_a, qdd_a)
        nominal = Y @ self._nominal_parameters
        lower, upper = self.enclose_regressor(Y, regressor.envelope)
        if self.joints is not None:  # the regressor carries neither armature nor friction
            self.add_joint_terms(lower, upper, qd, qd_a, qdd_a, torque=nominal)
        return nominal, lower, upper

    @property
    def regressor(self):
        """The :class:`~urpc.model.regressor.SlotineLiRegressor` of the nominal robot (shared)."""
        if not hasattr(self, "_regressor"):
            from ..model.regressor import SlotineLiRegressor

            self._regressor = SlotineLiRegressor(self.robot)
        return self._regressor

    @abstractmethod
    def enclose_regressor(
        self, Y: np.ndarray, envelope: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` from a Slotine-Li regressor ``Y`` (shape ``dof x 10 dof``): the
        link parameters' part of ``w`` (add :meth:`add_joint_terms` for the joints').

        Args:
            Y: ``Y_SL`` at the state.
            envelope: The rounding envelope of the state
                (:meth:`~urpc.model.regressor.SlotineLiRegressor.state_envelope`); by default the
                one of :attr:`regressor`'s last call, which must then have returned ``Y``.
        """

    def _envelope(self, Y: np.ndarray, envelope: float | None) -> float:
        return self.regressor.envelope_of(Y) if envelope is None else float(envelope)


def check_robot_and_box(robot: object, box: object) -> None:
    """Typed errors for a robot or a box of the wrong type (a file name given for a box).

    Raises:
        InputError: naming the argument and what is expected.
    """
    if not isinstance(robot, Robot):
        raise InputError(
            f"expected a Robot (urpc.load_robot(...)), got {type(robot).__name__} {robot!r:.60}",
            field="robot",
        )
    check_box(box)


def check_box(box: object) -> None:
    """An :class:`~urpc.errors.InputError` naming ``box`` unless it is a :class:`ParameterBox`."""
    if not isinstance(box, ParameterBox):
        hint = (
            f"; load it first: urpc.load_uncertainty({str(box)!r}, robot)"
            if isinstance(box, str | Path)
            else ""
        )
        raise InputError(
            f"expected a ParameterBox (urpc.load_uncertainty(path, robot)), got "
            f"{type(box).__name__} {box!r:.60}{hint}",
            field="box",
        )


def link_body_placement(robot: Robot, link: str) -> tuple[int, np.ndarray]:
    """Where a link's parameters enter ``Y_SL``: the body index ``b`` (its columns are
    ``10 b : 10 b + 10``) and the matrix ``A`` with ``pi_body = A pi_link`` (the identity when
    the link frame is the joint frame, as for the child link of a URDF joint)."""
    inertial = robot.link(link)
    if inertial.joint_index == 0:
        raise ValueError(f"link '{link}' is fixed to the base and has no regressor")
    return inertial.joint_index - 1, placement_matrix(inertial.placement)


def envelope_weights(robot: Robot, magnitude: np.ndarray) -> np.ndarray:
    """``K_i = ROUNDING_RECURSION sum_j p_j`` per joint ``i`` [N m per unit envelope], over the
    regressor columns ``j`` of the bodies joint ``i`` carries (the others are exactly zero in its
    row); ``magnitude`` holds ``p_j`` per column (``10`` per body, body coordinates)."""
    model = robot.model
    per_body = np.asarray(magnitude, dtype=float).reshape(-1, 10).sum(axis=1)
    weights = np.zeros(robot.dof)
    for body in range(1, model.njoints):
        for joint in model.supports[body]:
            if joint > 0:
                weights[model.joints[joint].idx_v] += per_body[body - 1]
    return ROUNDING_RECURSION * weights
