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

The robust gain and the feedback are two small objects the controller composes:

* the **gain law** (:mod:`urpc.control.gain_laws`), chosen by the bound method's
  ``disturbance_bound``: Theorem 2 (bound **unknown**; the enclosure is taken with ``d = 0`` and
  the gains grow with the dead-zone integral ``s``, the controller's only state) or Theorem 1
  (bound **known** and included in the enclosure; constant gains ``phi_P``, ``kappa_P``, no
  state);
* the **feedback law** (:mod:`urpc.control.feedback`), chosen by ``sample_period`` and
  ``sampled_law``: ``D r`` in continuous time (the paper's law), the same law held under a
  zero-order hold (``sampled_law="paper"``), or the implicit sampled-data law
  ``D (M_L + D T 1)^{-1} M_L r`` (``sampled_law="implicit"``; not in the paper), which also sets
  the ceiling ``phi_max`` where adaptation stops.

Each law carries its part of the certificate (:func:`urpc.control.certificate.certify` asks them).

When the bound method works on the Slotine-Li regressor, one ``Y_SL(q, qd, qd_a, qdd_a)`` per step
gives both the nominal torque ``Y_SL pi0`` and the enclosure, since
``M qdd_a + C qd_a + g = Y_SL pi`` (:mod:`urpc.model.regressor`).

Build it with :func:`urpc.control.synthesis.synthesize`, which validates the gains.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..bounds.base import BoundMethod
from ..errors import InputError
from ..model.inertia_bounds import InertiaBounds
from .base import Controller, Reference
from .feedback import FeedbackLaw, ImplicitFeedback, feedback_law
from .gain_laws import AdaptiveGains, ConstantGains, GainLaw


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
        sampled_law: ``"implicit"`` (the sampled-data law of :mod:`urpc.control.feedback`) or
            ``"paper"`` (the paper's law unchanged under the hold); used with ``sample_period``.
        inertia_bounds: The :class:`~urpc.model.inertia_bounds.InertiaBounds` of the box, required
            by the implicit law.

    Attributes:
        gain_law: The :class:`~urpc.control.gain_laws.GainLaw` (Theorem 1 or 2).
        feedback: The :class:`~urpc.control.feedback.FeedbackLaw` (continuous, held or
            implicit).
        phi_max: The ceiling of ``phi`` [N m s/rad] where adaptation stops (implicit law), or
            ``inf``.
        last_rho_norm: ``||rho||`` [N m] of the latest :meth:`output` call (diagnostic cache).

    Raises:
        ValueError: an unknown ``sampled_law``; the implicit law without ``inertia_bounds``.
    """

    name = "interval"
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
        self.method = bound.name
        self.last_rho_norm = math.nan
        self.sampled_law = sampled_law
        self.inertia_bounds = inertia_bounds
        period = None if sample_period is None else float(sample_period)
        self._feedback = feedback_law(period, sampled_law, inertia_bounds)
        self.phi_max = self._feedback.phi_ceiling(self.phi_P)
        if isinstance(self._feedback, ImplicitFeedback):  # D capped where adaptation stops
            self._feedback.gain_cap = self.phi_max
        if bound.disturbance_bound is None:
            self._gain_law: GainLaw = AdaptiveGains(
                self.kappa_P, self.kappa_I, self.phi_P, self.phi_I, self.epsilon, self.phi_max
            )
        else:
            self._gain_law = ConstantGains(self.kappa_P, self.phi_P)
        self.n_states = self._gain_law.n_states
        # The two laws' step methods, bound once (the control step's path).
        self._gain, self._torque = self._gain_law.gain, self._feedback.torque
        self._torque_and_enclosure = bound.torque_and_enclosure

    @property
    def gain_law(self) -> GainLaw:
        return self._gain_law

    @property
    def feedback(self) -> FeedbackLaw:
        return self._feedback

    @property
    def sample_period(self) -> float | None:
        """The feedback law's period [s]; ``None``: continuous time."""
        return self._feedback.sample_period

    @property
    def adaptive(self) -> bool:
        """True for Theorem 2 (growing gains, one state), False for Theorem 1."""
        return self._gain_law.adaptive

    @property
    def implicit(self) -> bool:
        """True when the implicit sampled-data law runs (a period and ``"implicit"``)."""
        return isinstance(self._feedback, ImplicitFeedback)

    def __repr__(self) -> str:
        T = self.sample_period
        law = "" if T is None else f", {self._feedback.name} law at T={T:g} s"
        return (
            f"IntervalPassivityController({self.robot.name!r}, method={self.method!r}, "
            f"epsilon={self.epsilon:g}, {self._gain_law.description}{law})"
        )

    def save(self, path):
        """Write this controller to ``path`` (JSON, :mod:`urpc.control.controller_file`);
        :func:`urpc.load_controller` reads it back, with bit-identical torques."""
        from .controller_file import save_controller

        return save_controller(self, path)

    def gains(self, state: np.ndarray) -> tuple[float, float]:
        """``(phi, kappa)`` for the state ``[s]`` (Theorem 2) or the constants (Theorem 1)."""
        return self._gain_law.gains(state)

    def check_state(self, state, field: str = "controller_state0") -> np.ndarray:
        """As :meth:`Controller.check_state`; the adaptive law's integral ``s`` (Theorem 2)
        must also be ``>= 0``: it only grows from 0, and a negative one makes the gain negative."""
        vector = super().check_state(state, field)
        adaptive = vector[: self._gain_law.n_states]
        if np.any(adaptive < 0):
            raise InputError(
                f"the gain integral s = {adaptive.tolist()} must be >= 0 (Theorem 2's s grows "
                "from 0; phi = phi_P + phi_I s)",
                field=field,
            )
        return vector

    def output(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """Joint torque ``u`` [N m] of eq. (4) with the gain law's ``D`` and the feedback law's
        torque for it."""
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
            nominal, lower, upper = self._torque_and_enclosure(q, qd, qd_a, qdd_a)
            # rho_i = max(|lower_i|, |upper_i|) = max(-lower_i, upper_i) since lower_i <= upper_i.
            rho = np.maximum(-lower, upper)
            rho_norm = math.sqrt(rho @ rho)
            self.last_rho_norm = rho_norm
            return nominal + self._torque(q, self._gain(rho_norm, state), r)
        except InputError:
            raise
        except (ValueError, TypeError, IndexError, AttributeError) as exc:
            # Only on failure (free on the fast path): say which vector has the wrong size.
            raise self.state_error(q, qd, reference) or exc from None

    def state_derivative(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """``ds/dt = f(||e||)`` [rad] (Theorem 2); empty for Theorem 1."""
        return self._gain_law.state_derivative(self._error(q, qd, reference), state)

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
        return self._gain_law.advance(self._error(q, qd, reference), state, self.sample_period)

    def _error(self, q, qd, reference: Reference) -> np.ndarray:
        """``e = q_d - q`` [rad], refused with one error naming the vector unless it has the
        law's number of joints (a one-entry ``q`` would broadcast)."""
        try:
            e = reference.q - q
            if e.shape != self._dof_shape:
                raise ValueError("wrong size")
        except (ValueError, TypeError, AttributeError):
            raise self.state_error(q, qd, reference) or InputError(
                f"q and reference.q must be {self.dof} numbers", field="q"
            ) from None
        return e

    def diagnostics(self, state: np.ndarray) -> dict[str, float]:
        """``phi`` [N m s/rad] and ``kappa`` [s/rad] at this state."""
        phi, kappa = self.gains(state)
        return {"phi": phi, "kappa": kappa}
