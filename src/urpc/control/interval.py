"""The interval passivity controller of Giusti & Althoff (the paper's eqs. 4, 10 and Theorems 1-2).

With the tracking error ``e = q_d - q`` and the diagonal gain ``Kr``::

    qd_a  = qd_d  + Kr e,        qdd_a = qdd_d + Kr ed,        r = ed + Kr e            (6)
    u     = M0(q) qdd_a + C0(q, qd) qd_a + g0(q) - v                                    (4)
    v     = -(kappa(t) ||rho|| + phi(t)) r                                              (10)

``M0, C0, g0`` are the nominal model (``C`` the Christoffel factorization) and ``rho`` [N m] the
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

**Sampled-data gain limit** (optional; not in the paper). Under a zero-order hold of period ``T``
the feedback ``v = -D r`` with ``D = kappa ||rho|| + phi`` discretizes, per eigen-mode ``i`` of the
inertia matrix, to ``r+ = (1 - D T / lambda_i) r``: the sampled loop is unstable once
``D T / lambda_i > 2``. ``rho`` is dominated by the heavy proximal joints while the lightest mode
is often a wrist, so on a real arm at 1 kHz the paper's law can diverge although its
continuous-time guarantee holds. With ``sample_period=T`` the controller applies::

    v = -V diag(min(D, lambda_i / T)) V^T r,         M0(q) = V diag(lambda_i) V^T

i.e. the gain of each mode is capped at the dead-beat value ``lambda_i / T`` of the nominal model
(half the stability limit, which leaves a factor-2 margin on the true plant's inertia:
stable while the true modal inertia exceeds ``lambda_i / 2``). Modes whose cap exceeds ``D`` get
exactly the paper's law, and ``T -> 0`` recovers it everywhere. Where the cap is active the
continuous-time argument of Theorem 2 does not apply (it does not apply to a sampled loop anyway).

Build it with :func:`urpc.control.synthesis.synthesize`, which validates the gains.
"""

from __future__ import annotations

import math

import numpy as np

from ..bounds.base import BoundMethod
from .base import Controller, Reference


class IntervalPassivityController(Controller):
    """The paper's robust passivity-based law with an interval bound of the mismatch torque.

    Args:
        bound: The bound method (built for the robot and the parameter box); its
            ``disturbance_bound`` selects Theorem 1 (a number) or Theorem 2 (``None``).
        epsilon: Required tracking precision ``||e|| < epsilon`` [rad] (the dead zone of ``f``).
        kappa_P, kappa_I: Proportional [s/rad] and integral [1/rad^2] parts of ``kappa``.
        phi_P, phi_I: Proportional [N m s/rad] and integral [N m/rad^2] parts of ``phi``.
        Kr: Diagonal of ``Kr`` [1/s], length ``dof``.
        sample_period: Control period ``T`` [s] for the sampled-data gain limit (module docstring);
            ``None`` applies the paper's law unchanged.

    Attributes:
        adaptive: True for Theorem 2 (growing gains, one state), False for Theorem 1.
        last_rho_norm: ``||rho||`` [N m] of the latest :meth:`output` call (diagnostic cache).
    """

    name = "interval"

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
    ):
        self.bound = bound
        self.robot = bound.robot
        self.epsilon = float(epsilon)
        self.kappa_P, self.kappa_I = float(kappa_P), float(kappa_I)
        self.phi_P, self.phi_I = float(phi_P), float(phi_I)
        self.Kr = np.array(Kr, dtype=float).reshape(self.robot.dof)
        self.adaptive = bound.disturbance_bound is None
        self.n_states = 1 if self.adaptive else 0
        self.method = bound.name
        self.last_rho_norm = math.nan
        self.sample_period = None if sample_period is None else float(sample_period)
        self._uses_regressor = bound.uses_regressor
        self._pi0 = np.asarray(self.robot.nominal_parameters, dtype=float)
        if self._uses_regressor:
            self._regressor = bound.regressor
            self._enclose_regressor = bound.enclose_regressor

    def __repr__(self) -> str:
        theorem = "Theorem 2, adaptive" if self.adaptive else "Theorem 1, constant gains"
        limit = "" if self.sample_period is None else f", gain limit at T={self.sample_period:g} s"
        return (
            f"IntervalPassivityController({self.robot.name!r}, method={self.method!r}, "
            f"epsilon={self.epsilon:g}, {theorem}{limit})"
        )

    def gains(self, state: np.ndarray) -> tuple[float, float]:
        """``(phi, kappa)`` for the state ``[s]`` (Theorem 2) or the constants (Theorem 1)."""
        if self.adaptive:
            s = float(state[0])
            return self.phi_P + self.phi_I * s, self.kappa_P + self.kappa_I * s
        return self.phi_P, self.kappa_P

    def output(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """Joint torque ``u`` [N m] of eq. (4) with (10)."""
        Kr = self.Kr
        e = reference.q - q
        ed = reference.qd - qd
        Kr_e = Kr * e
        qd_a = reference.qd + Kr_e
        qdd_a = reference.qdd + Kr * ed
        r = ed + Kr_e
        if self._uses_regressor:
            Y = self._regressor(q, qd, qd_a, qdd_a)
            nominal = Y @ self._pi0
            lower, upper = self._enclose_regressor(Y)
        else:
            robot = self.robot
            nominal = robot.M(q) @ qdd_a + robot.C(q, qd) @ qd_a + robot.g(q)
            lower, upper = self.bound.enclose(q, qd, qd_a, qdd_a)
        # rho_i = max(|lower_i|, |upper_i|) = max(-lower_i, upper_i) since lower_i <= upper_i.
        rho = np.maximum(-lower, upper)
        rho_norm = math.sqrt(rho @ rho)
        self.last_rho_norm = rho_norm
        if self.adaptive:
            s = state[0]
            gain = (self.kappa_P + self.kappa_I * s) * rho_norm + self.phi_P + self.phi_I * s
        else:
            gain = self.kappa_P * rho_norm + self.phi_P
        if self.sample_period is not None:
            return nominal + self._sampled_feedback(q, gain, r)
        return nominal + gain * r

    def _sampled_feedback(self, q: np.ndarray, gain: float, r: np.ndarray) -> np.ndarray:
        """``V diag(min(gain, lambda_i / T)) V^T r`` with ``M0(q) = V diag(lambda_i) V^T``."""
        inertias, modes = np.linalg.eigh(self.robot.M(q))
        modal_gain = np.minimum(gain, inertias / self.sample_period)
        return modes @ (modal_gain * (modes.T @ r))

    def state_derivative(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """``ds/dt = f(||e||)`` [rad] (Theorem 2); empty for Theorem 1."""
        if not self.adaptive:
            return np.zeros(0)
        e = reference.q - q
        norm = math.sqrt(e @ e)
        return np.array([norm if norm >= self.epsilon else 0.0])

    def advance(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        reference: Reference,
        state: np.ndarray,
        sample_period: float,
    ) -> np.ndarray:
        """The state one sample later, ``s + T f(||e||)`` (forward Euler, as the base class)."""
        if not self.adaptive:
            return state
        e = reference.q - q
        norm = math.sqrt(e @ e)
        return np.array([state[0] + sample_period * norm]) if norm >= self.epsilon else state

    def diagnostics(self, state: np.ndarray) -> dict[str, float]:
        """``phi`` [N m s/rad] and ``kappa`` [s/rad] at this state."""
        phi, kappa = self.gains(state)
        return {"phi": phi, "kappa": kappa}
