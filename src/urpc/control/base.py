"""The controller interface: a torque law with explicit internal state.

A controller is built once (synthesis) and run many times. Its internal state (for example the
integral of the paper's dead-zone ``f(||e||)``) is an explicit vector, so that the same law runs
in continuous time (the state is integrated with the plant by the ODE solver) and sampled (the
simulator advances it once per sample period with :meth:`Controller.advance`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np

from ..trajectories import Reference

__all__ = ["Controller", "Reference"]


class Controller(ABC):
    """A joint-torque law ``u = output(t, q, qd, reference, state)`` [N m].

    ``state`` has length :attr:`n_states` (0 for static laws); its time derivative is
    :meth:`state_derivative`. Controllers must not keep hidden mutable state between calls except
    caches and timing counters, so that a controller can be reset and reused.
    """

    #: Name used on the CLI and in result files.
    name: ClassVar[str]
    #: Length of the internal state vector.
    n_states: int = 0

    def initial_state(self) -> np.ndarray:
        """The internal state at ``t = 0``."""
        return np.zeros(self.n_states)

    @abstractmethod
    def output(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """Joint torque ``u`` [N m] at time ``t`` [s]."""

    def state_derivative(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """Time derivative of the internal state."""
        return np.zeros(self.n_states)

    def advance(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        reference: Reference,
        state: np.ndarray,
        sample_period: float,
    ) -> np.ndarray:
        """The state one sample period later, seen from the samples only (forward Euler)."""
        if self.n_states == 0:
            return state
        return state + sample_period * self.state_derivative(t, q, qd, reference, state)

    def diagnostics(self, state: np.ndarray) -> dict[str, float]:
        """Named scalars of the internal state worth logging (e.g. ``phi``, ``kappa``)."""
        return {}
