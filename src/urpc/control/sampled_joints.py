"""The joints' armature, damping and Coulomb friction in the sampled-data floor
(:mod:`urpc.control.cells`, docs/sampled-data.md "Joint dynamics")."""

from __future__ import annotations

import numpy as np

from ..model.ball_arithmetic import Jet
from ..model.joint_dynamics import JointBox


class JointTerms:
    """The joints' part of the mismatch in the argument (docs/sampled-data.md, joint dynamics).

    ``w_joint = (Ia - Ia0) qdd_a + Dv qd - Dv0 qd_a + f_c - Fc0 sat(qd_a / v_s)`` splits into: the
    smooth terms at ``r = 0`` (``qd = qd_a``), at most ``c_i = dIa_i |qdd_a,i| + dDv_i |qd_a,i|``
    per component (``dX_i`` the largest ``|X - X0|`` over the box), which join ``w``; the plant's
    damping acting on ``r = qd_a - qd``, ``-Dv r``, counted as a perturbation
    ``||M^-1/2 Dv M^-1/2|| <= max Dv_hi / lambda_L`` added to ``b`` (it dissipates energy, so
    this is conservative); and the Coulomb term, at most ``Fc_hi,i + Fc0_i`` in magnitude at any
    instant (sticking, reversals), counted with the disturbance: ``||Fc_hi + Fc0||``.

    Args:
        joints: The bound's joint box, or ``None`` (rigid joints: every term is zero).
    """

    def __init__(self, joints: JointBox | None):
        self.box = joints
        if joints is None:
            self.armature = self.viscous = np.zeros(0)
            self.damping = self.coulomb = 0.0
            return
        spread = np.maximum(joints.upper - joints.nominal, joints.nominal - joints.lower)
        self.armature, self.viscous = spread[0], spread[1]
        #: ``max_i Dv_hi,i`` [N m s/rad]: the plant's damping on ``r``.
        self.damping = float(joints.upper[1].max())
        #: ``||Fc_hi + Fc0||`` [N m]: the Coulomb mismatch, counted as disturbance.
        self.coulomb = float(np.linalg.norm(joints.upper[2] + joints.nominal[2]))

    def mismatch(self, qd_a: Jet, qdd_a: Jet) -> tuple[np.ndarray, np.ndarray] | None:
        """The drives' smooth mismatch at ``r = 0`` per component and its rate [N m, N m/s]
        over the cells' boxes of ``qd_a``, ``qdd_a`` (jets); ``None`` for rigid joints."""
        if self.armature.size == 0:
            return None
        speed, acceleration = qd_a.val.magnitude, qdd_a.val.magnitude
        value = self.armature * acceleration + self.viscous * speed
        rate = self.armature * qdd_a.dot.magnitude + self.viscous * qd_a.dot.magnitude
        return value, rate

    def plant_torque(self, qd_a: Jet, qdd_a: Jet) -> np.ndarray | float:
        """``|Ia qdd_a + Dv qd_a + f_c|`` [N m] of every drive of the box at ``r = 0``."""
        if self.box is None:
            return 0.0
        upper = self.box.upper
        return upper[0] * qdd_a.val.magnitude + upper[1] * qd_a.val.magnitude + upper[2]

    def plant_torque_per_error(self, Kr: np.ndarray) -> np.ndarray | float:
        """How much :meth:`plant_torque` grows per unit ``||e||`` [N m/rad] at ``r = 0``, where
        ``qd_a = qd_d + Kr e`` and ``qdd_a = qdd_d - Kr^2 e``: ``Ia Kr^2 + Dv Kr`` per joint
        (exact: the magnitudes are affine in the tube's radius)."""
        if self.box is None:
            return 0.0
        upper = self.box.upper
        return upper[0] * Kr * Kr + upper[1] * Kr

    def nominal_torque_rate(self, qd_a: Jet, qdd_a: Jet) -> np.ndarray | float:
        """The rate [N m/s] of the nominal drives' torque ``Ia0 qdd_a + Dv0 qd_a``."""
        if self.box is None:
            return 0.0
        nominal = self.box.nominal
        return nominal[0] * qdd_a.dot.magnitude + nominal[1] * qd_a.dot.magnitude
