"""The gain laws of the interval controller: the robust gain ``D = kappa ||rho|| + phi`` of the
paper's eq. (10), constant (Theorem 1) or adaptive (Theorem 2), with their certificate conditions.

* :class:`ConstantGains` (Theorem 1, disturbance bound **known**, included in ``rho``): the
  constants ``phi_P``, ``kappa_P``; no state. In continuous time ``||r||`` is ultimately bounded by
  ``sqrt(lambda_max / lambda_min) / kappa_P`` [rad/s].
* :class:`AdaptiveGains` (Theorem 2, disturbance bound **unknown**): the gains grow with the
  dead-zone integral ``s(t) = integral_0^t f(||e||) dt`` [rad s], the only state (``f(x) = 0`` if
  ``x < epsilon``, else ``x``), up to a ceiling ``phi_max`` set by the feedback law (anti-windup
  of the implicit law, :mod:`urpc.control.feedback`; ``inf`` otherwise)::

      phi(t) = phi_P + phi_I s(t),      kappa(t) = kappa_P + kappa_I s(t)

:class:`~urpc.control.interval.IntervalPassivityController` composes one of them with a feedback
law; the certificate asks it for its conditions (:meth:`GainLaw.conditions`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np

from .argument import Condition


class GainLaw(ABC):
    """The robust gain ``D`` [N m s/rad] of a step and its state (module docstring)."""

    #: True for Theorem 2 (growing gains, one state), False for Theorem 1.
    adaptive: ClassVar[bool]
    #: Length of the state vector.
    n_states: ClassVar[int]
    #: How the controller's ``repr`` names the law.
    description: ClassVar[str]

    @abstractmethod
    def gain(self, rho_norm: float, state: np.ndarray) -> float:
        """``D = kappa ||rho|| + phi`` [N m s/rad] for ``||rho|| = rho_norm`` [N m]."""

    @abstractmethod
    def gains(self, state: np.ndarray) -> tuple[float, float]:
        """``(phi, kappa)`` at this state."""

    @abstractmethod
    def state_derivative(self, e: np.ndarray, state: np.ndarray) -> np.ndarray:
        """Time derivative of the state for the tracking error ``e`` [rad]."""

    @abstractmethod
    def advance(self, e: np.ndarray, state: np.ndarray, period: float) -> np.ndarray:
        """The state one ``period`` [s] later, seen from the sample's error ``e`` [rad]."""

    @abstractmethod
    def settled_phi(self, ceiling: float) -> float:
        """The ``phi`` [N m s/rad] the sampled-data argument counts on once adaptation has
        stopped at ``ceiling`` (the feedback law's ``phi_max``)."""

    @abstractmethod
    def conditions(self) -> list[Condition]:
        """The gain conditions of the theorem."""

    @abstractmethod
    def continuous_time_bound(
        self, lambda_L: float, lambda_U: float, Kr: np.ndarray, epsilon: float
    ) -> tuple[float, list[Condition]]:
        """The continuous-time ultimate bound of ``||e||`` [rad] and its conditions, from the
        bounds ``lambda_L``, ``lambda_U`` [kg m^2] of the inertia's eigenvalues over the box."""

    def saturation_figures(self) -> dict[str, float]:
        """Figures of the adaptation for the certificate's report (none by default)."""
        return {}


class ConstantGains(GainLaw):
    """Theorem 1: ``D = kappa_P ||rho|| + phi_P``, no state."""

    adaptive = False
    n_states = 0
    description = "Theorem 1, constant gains"

    def __init__(self, kappa_P: float, phi_P: float):
        self.kappa_P, self.phi_P = kappa_P, phi_P

    def gain(self, rho_norm, state):
        return self.kappa_P * rho_norm + self.phi_P

    def gains(self, state):
        return self.phi_P, self.kappa_P

    def state_derivative(self, e, state):
        return np.zeros(0)

    def advance(self, e, state, period):
        return state

    def settled_phi(self, ceiling):
        return self.phi_P

    def conditions(self):
        specs = [
            ("Theorem 1: kappa_P >= 1", self.kappa_P, 1.0, "choose kappa_P >= 1"),
            ("Theorem 1: phi_P >= 1", self.phi_P, 1.0, "choose phi_P >= 1"),
        ]
        return [
            Condition(n, v >= lim, v, lim, f"{v:.3g} >= {lim:g}" if v >= lim else x)
            for n, v, lim, x in specs
        ]

    def continuous_time_bound(self, lambda_L, lambda_U, Kr, epsilon):
        """``||r|| <= sqrt(lambda_U / lambda_L) / kappa_P``, ``||e|| <= ||r|| / min(Kr)``."""
        floor = (
            float(math.sqrt(lambda_U / lambda_L) / self.kappa_P / np.min(Kr))
            if lambda_L > 0
            else math.inf
        )
        condition = Condition(
            "Theorem 1 ultimate bound below epsilon", floor <= epsilon, floor, epsilon,
            "raise kappa_P or Kr, or use Theorem 2 (disturbance: unknown)",
        )  # fmt: skip
        return floor, [condition]


class AdaptiveGains(GainLaw):
    """Theorem 2: ``D = (kappa_P + kappa_I s) ||rho|| + phi_P + phi_I s``, the state ``[s]``
    growing by ``f(||e||)`` until ``phi`` reaches ``phi_max``."""

    adaptive = True
    n_states = 1
    description = "Theorem 2, adaptive"

    def __init__(
        self,
        kappa_P: float,
        kappa_I: float,
        phi_P: float,
        phi_I: float,
        epsilon: float,
        phi_max: float,
    ):
        self.kappa_P, self.kappa_I = kappa_P, kappa_I
        self.phi_P, self.phi_I = phi_P, phi_I
        self.epsilon = epsilon
        #: The state where ``phi`` reaches ``phi_max`` (``inf`` without a ceiling).
        self.s_max = (phi_max - phi_P) / phi_I

    def gain(self, rho_norm, state):
        s = state[0]
        return (self.kappa_P + self.kappa_I * s) * rho_norm + self.phi_P + self.phi_I * s

    def gains(self, state):
        s = float(state[0])
        return self.phi_P + self.phi_I * s, self.kappa_P + self.kappa_I * s

    def state_derivative(self, e, state):
        """``ds/dt = f(||e||)`` [rad], 0 once ``s`` reaches ``s_max``."""
        norm = math.sqrt(e @ e)
        growing = norm >= self.epsilon and state[0] < self.s_max
        return np.array([norm if growing else 0.0])

    def advance(self, e, state, period):
        """``min(s + T f(||e||), s_max)`` (forward Euler)."""
        norm = math.sqrt(e @ e)
        if norm < self.epsilon or state[0] >= self.s_max:
            return state
        return np.array([min(state[0] + period * norm, self.s_max)])

    def settled_phi(self, ceiling):
        return ceiling

    def conditions(self):
        specs = [
            ("Theorem 2: kappa_I > 0", self.kappa_I, 0.0, "choose kappa_I > 0"),
            ("Theorem 2: phi_I > 0", self.phi_I, 0.0, "choose phi_I > 0"),
        ]
        return [
            Condition(n, v > lim, v, lim, f"{v:.3g} > {lim:g}" if v > lim else x)
            for n, v, lim, x in specs
        ]

    def continuous_time_bound(self, lambda_L, lambda_U, Kr, epsilon):
        """Theorem 2: ``||e||`` ends up below any ``epsilon`` (floor 0), no further condition."""
        return 0.0, []

    def saturation_figures(self):
        """``time_above_epsilon_before_saturation`` [s]: before the gains saturate,
        ``||e_k|| >= epsilon`` for at most ``s_max / epsilon`` seconds (each such sample adds
        at least ``T epsilon`` to ``s``)."""
        if not self.phi_I > 0:
            return {}
        return {"time_above_epsilon_before_saturation": self.s_max / self.epsilon}
