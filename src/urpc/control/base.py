"""The controller interface: a torque law with explicit internal state and its own period.

A controller is built once (synthesis) and run many times. Its internal state (for example the
integral of the paper's dead-zone ``f(||e||)``) is an explicit vector, so that the same law runs
in continuous time (the state is integrated with the plant by the ODE solver) and sampled (the
simulator advances it once per sample period with :meth:`Controller.advance`).

The controller owns its sample period: :attr:`Controller.sample_period` is the period it was
built for (``None``: continuous time), and :func:`urpc.simulate` runs it at that period, so the
period is stated once, at synthesis.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import InputError
from ..trajectories import Reference
from ..validation import positive_number
from ..wording import count

if TYPE_CHECKING:
    from ..model.robot import Robot

__all__ = ["Controller", "Reference", "actuation_delay_of", "sample_period_of"]


class Controller(ABC):
    """A joint-torque law ``u = output(t, q, qd, reference, state)`` [N m].

    ``state`` has length :attr:`n_states` (0 for static laws); its time derivative is
    :meth:`state_derivative`. Controllers must not keep hidden mutable state between calls except
    caches and timing counters, so that a controller can be reset and reused.

    What callers (the simulator, the certificate, the reports) read, declared here with the
    defaults of a law that has none of them:

    Attributes:
        name: Name used on the CLI and in result files.
        n_states: Length of the internal state vector.
        dof: Number of joints the law commands; ``None`` for a law that fits any arm.
        robot: The model the law was built for; ``None`` for a law that uses no model (r-alpha).
        sample_period: Control period ``T`` [s] the law runs at under a zero-order hold;
            ``None``: continuous time.
        epsilon: Required precision ``||e|| < epsilon`` [rad] the law is built for; ``None`` when
            it has none (the simulation then needs one).
        Kr: Diagonal gain [1/s] of the sliding variable ``r = ed + Kr e`` (a scalar or ``dof``
            values), the direction an ``against`` disturbance pushes against; 1 for laws
            without one.
        diagnostic_units: Name -> unit of the scalars :meth:`diagnostics` returns (e.g.
            ``{"phi": "N m s/rad"}``), recorded by the simulator as named series; empty for
            laws with nothing to log.
        delay: Samples of actuation delay the law predicts over (0: its torque acts over the
            period of its own sample; 1: :class:`~urpc.control.delay.DelayedIntervalController`).
    """

    name: ClassVar[str]
    diagnostic_units: ClassVar[dict[str, str]] = {}
    n_states: int = 0
    dof: int | None = None
    robot: Robot | None = None
    sample_period: float | None = None
    epsilon: float | None = None
    Kr: float | np.ndarray = 1.0
    delay: int = 0

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
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """The state one :attr:`sample_period` later, seen from the samples only (forward
        Euler)."""
        if self.n_states == 0:
            return state
        return state + self.sample_period * self.state_derivative(t, q, qd, reference, state)

    def check_state(self, state, field: str = "controller_state0") -> np.ndarray:
        """``state`` as a valid internal state (:attr:`n_states` finite numbers), for a caller
        that sets one (``urpc.simulate(..., controller_state0=...)``).

        Raises:
            InputError: another length, or a value the law never reaches (``field`` named).
        """
        from ..validation import finite_vector

        return finite_vector(field, state, self.n_states)

    def diagnostics(self, state: np.ndarray) -> dict[str, float]:
        """The scalars named in :attr:`diagnostic_units` at this state (e.g. ``phi``,
        ``kappa``)."""
        return {}

    def state_error(self, q, qd, reference) -> InputError | None:
        """The error naming the first of ``q``, ``qd`` and the reference's ``q``, ``qd``, ``qdd``
        that is not :attr:`dof` finite numbers (or a reference that is no :class:`Reference`),
        else ``None``. Called only once a law has failed (free on the control step's path)."""
        if not all(hasattr(reference, name) for name in ("q", "qd", "qdd")):
            return InputError(
                f"expected a Reference (q, qd, qdd), got {type(reference).__name__}",
                field="reference",
            )
        dof = self.dof if self.dof is not None else getattr(self.robot, "dof", None)
        vectors = {"q": q, "qd": qd}
        vectors.update({f"reference.{n}": getattr(reference, n) for n in ("q", "qd", "qdd")})
        for name, value in vectors.items():
            try:
                array = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                return InputError(f"{value!r} is not a vector of {dof} numbers", field=name)
            if dof is not None and array.shape != (dof,):
                who = f"{self.robot.name} has" if self.robot is not None else "the law commands"
                return InputError(
                    f"{name} has shape {array.shape}, but {who} {dof} joints", field=name
                )
            if not np.isfinite(array).all():
                return InputError(f"{name} = {array} is not finite", field=name)
        return None


def sample_period_of(value: float | None) -> float | None:
    """A controller's ``sample_period`` argument checked: ``None`` (continuous time) or a finite
    number > 0 [s].

    Raises:
        InputError: not a number, or not finite and > 0 (field ``sample_period``).
    """
    if value is None:
        return None
    return positive_number("sample_period", value, "a finite number > 0 [s] or None")


def actuation_delay_of(controller: Controller, value: Any = None) -> int:
    """The actuation delay [samples] with which a plant applies ``controller``'s torques: the
    torque computed from the sample at ``t_k`` acts over ``[t_{k+d}, t_{k+d+1})``.

    ``value`` is checked: an integer >= 0 (an integral float such as ``1.0`` too). ``None`` gives
    the delay the law itself predicts over (``controller.delay``: 1 for
    :class:`~urpc.control.delay.DelayedIntervalController`, 0 for every other law), so that a
    delayed law meets the delay it was built for unless told otherwise. A continuous-time
    controller (``sample_period`` ``None``) has no samples to count: only 0.

    Raises:
        InputError: not an integer >= 0, or a delay of a continuous-time run (field
            ``actuation_delay``).
    """
    if value is None:
        return int(controller.delay)
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise InputError(
            f"{value!r} is not a number of samples; expected an integer >= 0 (0: a torque acts "
            "over the period of its sample, 1: over the next one)",
            field="actuation_delay",
        )
    if value > 0 and controller.sample_period is None:
        raise InputError(
            f"a delay of {count(value, 'sample')} needs samples: the controller runs in "
            "continuous time; synthesize it with a sample_period, or give 0",
            field="actuation_delay",
        )
    return int(value)
