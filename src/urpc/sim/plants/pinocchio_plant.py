"""The reference plant: RK4 on accelerations from Pinocchio's articulated-body algorithm (which
adds the joints' armature to the inertia itself), the joints' viscous damping in every stage;
their Coulomb friction (regularized in the stiction band, :mod:`urpc.model.joint_dynamics`) acts
through an implicit step after each RK4 step."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...errors import SimulationError
from ...model.joint_dynamics import STICTION_VELOCITY, friction_shape
from ...model.robot import Robot
from .plant import DEFAULT_MAX_STEP, Plant


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
        self._friction = robot.has_joint_friction
        self._damping, self._coulomb = np.asarray(model.damping), np.asarray(model.friction)
        self._coulomb_any = bool(np.any(self._coulomb))
        self._guess: np.ndarray | None = None

    def _load_state(self) -> None:
        """Nothing to do: the state lives in ``self._q, self._qd`` (forget the friction guess)."""
        self._guess = None

    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        if self._friction:
            return self._advance_with_friction(tau, h, substeps)
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

    def _advance_with_friction(
        self, tau: np.ndarray, h: float, substeps: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each step: RK4 of the rigid dynamics (armature included) with the viscous damping
        ``Dv qd`` at every stage, as MuJoCo's RK4 does; then the Coulomb friction over the step,
        implicitly (:func:`implicit_friction`), its velocity change ``dv`` moving the position by
        ``h dv / 2`` (a constant force over the step). First order in the Coulomb friction
        (splitting), stable for any stiffness of its regularized law."""
        model, data, configuration, aba = self.robot.model, self._data, self._configuration, pin.aba
        damping, coulomb = self._damping, self._coulomb
        half, sixth = 0.5 * h, h / 6.0
        q, v = self._q, self._qd
        for _ in range(substeps):
            a1 = aba(model, data, configuration(q), v, tau - damping * v)
            v2 = v + half * a1
            a2 = aba(model, data, configuration(q + half * v), v2, tau - damping * v2)
            v3 = v + half * a2
            a3 = aba(model, data, configuration(q + half * v2), v3, tau - damping * v3)
            v4 = v + h * a3
            a4 = aba(model, data, configuration(q + h * v3), v4, tau - damping * v4)
            q = q + sixth * (v + 2.0 * (v2 + v3) + v4)
            v = v + sixth * (a1 + 2.0 * (a2 + a3) + a4)
            if self._coulomb_any:
                v_friction = implicit_friction(self.robot.M(q), v, h, coulomb, start=self._guess)
                self._guess = v_friction  # the next step's solution is near this one
                q = q + half * (v_friction - v)
                v = v_friction
        return q, v


def implicit_friction(
    M: np.ndarray,
    v: np.ndarray,
    h: float,
    coulomb: np.ndarray,
    start: np.ndarray | None = None,
) -> np.ndarray:
    """The velocity after ``h`` [s] of the joints' Coulomb friction alone, backward Euler: the
    ``x`` with ``M (x - v) + h Fc sat(x / v_s) = 0``, the minimizer of the strictly convex
    ``1/2 (x - v)^T M (x - v) + h sum_i Fc_i Phi(x_i)`` (``Phi' = sat(x / v_s)``, a Huber function), so it
    exists, is unique, and no stiffness of the law makes it unstable. Solved by Newton's method
    on the piecewise-linear monotone system with a backtracking line search on that objective
    (exact once the set of joints inside the stiction band settles, a few iterations), from
    ``start`` (the previous step's solution, which knows which joints stick) or ``v``.

    Raises:
        SimulationError: no convergence in 100 iterations.
    """
    x = v.copy() if start is None else start.copy()
    band = STICTION_VELOCITY

    def objective(y: np.ndarray) -> float:
        a = np.abs(y)
        huber = np.where(a < band, 0.5 * y * y / band, a - 0.5 * band)  # Phi / Fc, C^1
        return 0.5 * (y - v) @ M @ (y - v) + h * float(coulomb @ huber)

    value = objective(x)
    for _ in range(100):
        inside = np.abs(x) < band
        residual = M @ (x - v) + h * coulomb * friction_shape(x)
        jacobian = M + np.diag(np.where(inside, h * coulomb / band, 0.0))
        step = np.linalg.solve(jacobian, residual)
        if np.all(np.abs(step) <= 1e-15 + 1e-13 * np.abs(x)):
            return x - step
        # Newton's direction descends the convex objective; backtrack (Armijo) where the
        # piecewise-linear law would make the full step cycle across the band's edges.
        slope, t = float(residual @ step), 1.0
        while True:
            trial = x - t * step
            trial_value = objective(trial)
            if trial_value <= value - 1e-4 * t * slope or t < 1e-12:
                break
            t *= 0.5
        x, value = trial, trial_value
    raise SimulationError("the implicit joint-friction step did not converge in 100 iterations")
