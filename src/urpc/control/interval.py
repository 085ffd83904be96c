"""The interval passivity controller of Giusti & Althoff (the paper's eqs. 4, 10 and Theorems 1-2).

With the tracking error ``e = q_d - q`` and the diagonal gain ``Kr``::

    qd_a  = qd_d  + Kr e,        qdd_a = qdd_d + Kr ed,        r = ed + Kr e            (6)
    u     = M0(q) qdd_a + C0(q, qd) qd_a + g0(q) - v                                    (4)
    v     = -(kappa(t) ||rho|| + phi(t)) r                                              (10)

``M0, C0, g0`` are the nominal model (``C`` the Christoffel factorization; with joint dynamics,
``M0`` includes the nominal armature and ``u`` adds the nominal friction along the reference,
``Dv0 qd_a + Fc0 sat(qd_a / v_s)``, :mod:`urpc.model.joint_dynamics`) and ``rho`` [N m] the
per-joint magnitude ``max(|lower_i|, |upper_i|)`` of an enclosure of the mismatch torque ``w``
over the parameter box (eq. 9), computed by a :class:`~urpc.bounds.BoundMethod` at every step.

* Disturbance bound **unknown** (Theorem 2): the enclosure is taken with ``d = 0`` and the gains
  grow with the dead-zone integral ``s(t) = integral_0^t f(||e||) dt`` [rad s], the controller's
  only state (``f(x) = 0`` if ``x < epsilon``, else ``x``)::

      phi(t) = phi_P + phi_I s(t),      kappa(t) = kappa_P + kappa_I s(t)

* Disturbance bound **known** (Theorem 1): the enclosure includes ``d`` and the gains are the
  constants ``phi_P``, ``kappa_P`` (no state). ``||r||`` is then ultimately bounded by
  ``sqrt(lambda_max / lambda_min) / kappa_P`` [rad/s].

When the bound method works on the Slotine-Li regressor, one ``Y_SL(q, qd, qd_a, qdd_a)`` per step
gives both the nominal torque ``Y_SL pi0`` and the enclosure, since
``M qdd_a + C qd_a + g = Y_SL pi`` (:mod:`urpc.model.regressor`).

**Sampled-data law** (``sample_period=T``, ``sampled_law="implicit"``; not in the paper). Under a
zero-order hold the explicit feedback ``v = -D r`` gives, per inertia mode, ``r+ = (1 - D T /
lambda) r``: unstable once ``D T > 2 lambda``, which the growing gain reaches on light plants. The
implicit (backward-Euler) discretization evaluates the feedback at the predicted next value of
``r`` (Acary & Brogliato 2010), with a sound lower bound ``M_L(q)`` of the inertia over the box
(:class:`~urpc.model.inertia_bounds.InertiaBounds`) as the prediction model::

    D = kappa ||rho|| + phi,       u = M0 qdd_a + C0 qd_a + g0 + D (M_L + D T 1)^{-1} M_L r

one CRBA and one symmetric solve per step. On every plant of the box (``M >= M_L``) the sampled
loop contracts for every gain, and as ``D -> infinity`` the feedback tends to the dead-beat
``M_L r / T``. Adaptation stops once ``phi`` reaches ``phi_max = 20 max_q lambda_max(M_U(q)) / T``
(anti-windup: beyond it a larger gain changes the feedback by less than 5 %). The discrete-time
argument and its ultimate bound are in ``docs/sampled-data.md`` and :mod:`urpc.control.certificate`.
``sampled_law="paper"`` keeps the paper's law unchanged under the hold (its reproduction).

Build it with :func:`urpc.control.synthesis.synthesize`, which validates the gains.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from ..bounds.base import BoundMethod
from ..errors import InputError
from ..model.inertia_bounds import InertiaBounds
from .base import Controller, Reference

#: ``phi_max = PHI_MAX_FACTOR * max_q lambda_max(M_U(q)) / T``: past it, the implicit feedback of
#: every mode is within ``1 / (1 + PHI_MAX_FACTOR)`` of its dead-beat limit, so adaptation stops.
PHI_MAX_FACTOR = 20.0


class IntervalPassivityController(Controller):
    """The paper's robust passivity-based law with an interval bound of the mismatch torque.

    Args:
        bound: The bound method (built for the robot and the parameter box); its
            ``disturbance_bound`` selects Theorem 1 (a number) or Theorem 2 (``None``).
        epsilon: Required tracking precision ``||e|| < epsilon`` [rad] (the dead zone of ``f``).
        kappa_P, kappa_I: Proportional [s/rad] and integral [1/rad^2] parts of ``kappa``.
        phi_P, phi_I: Proportional [N m s/rad] and integral [N m/rad^2] parts of ``phi``.
        Kr: Diagonal of ``Kr`` [1/s], length ``dof``.
        sample_period: Control period ``T`` [s] when the law runs sampled (zero-order hold);
            ``None``: continuous time, the paper's law.
        sampled_law: ``"implicit"`` (the sampled-data law of the module docstring) or
            ``"paper"`` (the paper's law unchanged under the hold); used with ``sample_period``.
        inertia_bounds: The :class:`~urpc.model.inertia_bounds.InertiaBounds` of the box, required
            by the implicit law.

    Attributes:
        adaptive: True for Theorem 2 (growing gains, one state), False for Theorem 1.
        implicit: True when the implicit sampled-data law runs (a period and ``"implicit"``).
        phi_max: The ceiling of ``phi`` [N m s/rad] where adaptation stops (implicit law), or
            ``inf``.
        last_rho_norm: ``||rho||`` [N m] of the latest :meth:`output` call (diagnostic cache).
    """

    name = "interval"
    #: Samples of actuation delay the law predicts over (:mod:`urpc.control.delay` for 1).
    delay = 0
    diagnostic_units = {"phi": "N m s/rad", "kappa": "s/rad"}

    def __init__(
        self,
        bound: BoundMethod,
        epsilon: float,
        *,
        kappa_P: float,
        kappa_I: float,
        phi_P: float,
        phi_I: float,
        Kr: np.ndarray,
        sample_period: float | None = None,
        sampled_law: str = "implicit",
        inertia_bounds: InertiaBounds | None = None,
    ):
        self.bound = bound
        self.robot = bound.robot
        self.dof = self.robot.dof
        self._dof_shape = (self.dof,)
        self.epsilon = float(epsilon)
        self.kappa_P, self.kappa_I = float(kappa_P), float(kappa_I)
        self.phi_P, self.phi_I = float(phi_P), float(phi_I)
        self.Kr = np.array(Kr, dtype=float).reshape(self.robot.dof)
        self.adaptive = bound.disturbance_bound is None
        self.n_states = 1 if self.adaptive else 0
        self.method = bound.name
        self.last_rho_norm = math.nan
        self.sample_period = None if sample_period is None else float(sample_period)
        self.sampled_law = sampled_law
        self.inertia_bounds = inertia_bounds
        self.implicit = self.sample_period is not None and sampled_law == "implicit"
        self.phi_max = math.inf
        if self.implicit:
            if inertia_bounds is None:
                raise ValueError("the implicit sampled law needs the box's inertia bounds")
            self._lower_robot = inertia_bounds.lower_robot
            self._identity = np.eye(self.robot.dof)
            self._stride = self.robot.dof + 1
            self.phi_max = max(
                self.phi_P,
                PHI_MAX_FACTOR * inertia_bounds.max_upper_eigenvalue / self.sample_period,
            )
        self._s_max = (self.phi_max - self.phi_P) / self.phi_I
        self._joints = bound.joints
        self._uses_regressor = bound.uses_regressor
        self._pi0 = np.asarray(self.robot.nominal_parameters, dtype=float)
        if self._uses_regressor:
            self._regressor = bound.regressor
            self._enclose_regressor = bound.enclose_regressor

    def __repr__(self) -> str:
        theorem = "Theorem 2, adaptive" if self.adaptive else "Theorem 1, constant gains"
        law = (
            ""
            if self.sample_period is None
            else f", {self.sampled_law} law at T={self.sample_period:g} s"
        )
        return (
            f"IntervalPassivityController({self.robot.name!r}, method={self.method!r}, "
            f"epsilon={self.epsilon:g}, {theorem}{law})"
        )

    def save(self, path):
        """Write this controller to ``path`` (JSON, :mod:`urpc.control.controller_file`);
        :func:`urpc.load_controller` reads it back, with bit-identical torques."""
        from .controller_file import save_controller

        return save_controller(self, path)

    def gains(self, state: np.ndarray) -> tuple[float, float]:
        """``(phi, kappa)`` for the state ``[s]`` (Theorem 2) or the constants (Theorem 1)."""
        if self.adaptive:
            s = float(state[0])
            return self.phi_P + self.phi_I * s, self.kappa_P + self.kappa_I * s
        return self.phi_P, self.kappa_P

    def output(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """Joint torque ``u`` [N m] of eq. (4) with (10), or the implicit sampled law."""
        try:
            if not (type(q) is type(qd) is type(reference.q) is np.ndarray):
                # Array-likes (lists) from a caller: convert once, off the simulator's path.
                q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
                reference = Reference(
                    *(np.asarray(x, dtype=float) for x in dataclasses.astuple(reference))
                )
            shape = self._dof_shape  # a one-entry vector would broadcast: refuse it
            if not (reference.q.shape == reference.qd.shape == reference.qdd.shape == shape):
                raise ValueError("the reference has the wrong size")
            Kr = self.Kr
            e = reference.q - q
            ed = reference.qd - qd
            Kr_e = Kr * e
            qd_a = reference.qd + Kr_e
            qdd_a = reference.qdd + Kr * ed
            r = ed + Kr_e
            joints = self._joints
            if self._uses_regressor:
                Y = self._regressor(q, qd, qd_a, qdd_a)
                nominal = Y @ self._pi0
                lower, upper = self._enclose_regressor(Y)
                if joints is not None:  # the regressor carries neither armature nor friction
                    self.bound.add_joint_terms(lower, upper, qd, qd_a, qdd_a, torque=nominal)
            else:
                robot = self.robot
                nominal = robot.M(q) @ qdd_a + robot.C(q, qd) @ qd_a + robot.g(q)  # with armature
                lower, upper = self.bound.enclose(q, qd, qd_a, qdd_a)
                if joints is not None:
                    nominal += joints.nominal_torque(qd_a, qdd_a, armature=False)
            # rho_i = max(|lower_i|, |upper_i|) = max(-lower_i, upper_i) since lower_i <= upper_i.
            rho = np.maximum(-lower, upper)
            rho_norm = math.sqrt(rho @ rho)
            self.last_rho_norm = rho_norm
            if self.adaptive:
                s = state[0]
                gain = (self.kappa_P + self.kappa_I * s) * rho_norm + self.phi_P + self.phi_I * s
            else:
                gain = self.kappa_P * rho_norm + self.phi_P
            if self.implicit:
                return nominal + self._sampled_feedback(q, gain, r)
            return nominal + gain * r
        except InputError:
            raise
        except (ValueError, TypeError, IndexError, AttributeError) as exc:
            # Only on failure (free on the fast path): say which vector has the wrong size.
            raise self.state_error(q, qd, reference) or exc from None

    def _sampled_feedback(self, q: np.ndarray, gain: float, r: np.ndarray) -> np.ndarray:
        """``D (M_L + D T 1)^{-1} M_L r = D (r - D T y)`` [N m] with ``(M_L + D T 1) y = r``: the
        implicit feedback from one CRBA (its upper triangle) and one Cholesky solve (LAPACK
        ``dposv``, which reads the upper triangle only)."""
        lower = self._lower_robot
        step = gain * self.sample_period
        shifted = pin.crba(lower.model, lower.data, lower.configuration(q))
        shifted.flat[:: self._stride] += step  # the diagonal (half the time of fancy indexing)
        _, y, info = dposv(shifted, r, lower=0)
        if info != 0:  # M_L + D T 1 is not positive definite: M_L is indefinite at q
            return implicit_feedback(positive_part(lower.M(q)), gain, step, r)
        return gain * (r - step * y)

    def state_derivative(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """``ds/dt = f(||e||)`` [rad] (Theorem 2); empty for Theorem 1."""
        if not self.adaptive:
            return np.zeros(0)
        try:
            e = reference.q - q
            if e.shape != self._dof_shape:  # q of one entry broadcasts: refuse it too
                raise ValueError("wrong size")
        except (ValueError, TypeError, AttributeError):
            raise self.state_error(q, qd, reference) or InputError(
                f"q and reference.q must be {self.dof} numbers", field="q"
            ) from None
        norm = math.sqrt(e @ e)
        growing = norm >= self.epsilon and state[0] < self._s_max
        return np.array([norm if growing else 0.0])

    def advance(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        reference: Reference,
        state: np.ndarray,
    ) -> np.ndarray:
        """The state one sample later, ``min(s + T f(||e||), s_max)`` with ``T`` the
        :attr:`sample_period` (forward Euler; ``s_max`` is where ``phi`` reaches
        :attr:`phi_max`)."""
        if not self.adaptive:
            return state
        try:
            e = reference.q - q
            if e.shape != self._dof_shape:  # q of one entry broadcasts: refuse it too
                raise ValueError("wrong size")
        except (ValueError, TypeError, AttributeError):
            raise self.state_error(q, qd, reference) or InputError(
                f"q and reference.q must be {self.dof} numbers", field="q"
            ) from None
        norm = math.sqrt(e @ e)
        if norm < self.epsilon or state[0] >= self._s_max:
            return state
        return np.array([min(state[0] + self.sample_period * norm, self._s_max)])

    def diagnostics(self, state: np.ndarray) -> dict[str, float]:
        """``phi`` [N m s/rad] and ``kappa`` [s/rad] at this state."""
        phi, kappa = self.gains(state)
        return {"phi": phi, "kappa": kappa}


#: Floor of the eigenvalues of :func:`positive_part`, relative to the largest one.
POSITIVE_FLOOR = 1e-3


def positive_part(inertia: np.ndarray, floor: float = POSITIVE_FLOOR) -> np.ndarray:
    """``inertia`` with its eigenvalues raised to at least ``floor * lambda_max`` [kg m^2].

    A box that is partly no rigid body (wide mass and CoM intervals with narrow inertias) can
    give a lower bound ``M_L`` that is not positive definite at some ``q``. The implicit feedback
    ``D (M_L + D T 1)^{-1} M_L r`` is then singular where ``D T = -lambda`` for a negative
    eigenvalue ``lambda`` and changes sign beyond: the gain the adaptation reaches blows the law
    up. On a mode the predicted inertia ``lambda_0`` only needs ``0 < lambda_0 <= lambda_true``
    for the loop factor ``1 - lambda_0 / lambda_true`` to contract, so a small positive floor in
    the directions where ``M_L`` fails is the cautious choice: the feedback there saturates at
    ``lambda_0 / T`` instead of diverging (the certificate reports such a box as not certified).
    """
    eigenvalues, vectors = np.linalg.eigh(inertia)
    top = float(eigenvalues[-1])
    least = floor * top if top > 0 else floor
    clamped = np.maximum(eigenvalues, least)
    return (vectors * clamped) @ vectors.T


def implicit_feedback(inertia: np.ndarray, gain: float, step: float, r: np.ndarray) -> np.ndarray:
    """``D (M + D T 1)^{-1} M r`` [N m] with ``D = gain`` and ``D T = step``, by a general
    solve (the fallback of the Cholesky path for an ``inertia`` made positive definite)."""
    return gain * np.linalg.solve(inertia + step * np.eye(len(r)), inertia @ r)
