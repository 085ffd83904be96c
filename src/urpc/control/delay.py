"""The interval law with one sample of actuation delay (``delay: 1``): it predicts one period
ahead.

On most torque interfaces the torque computed from the sample at ``t_k`` reaches the motors at
``t_{k+1}``, while the torque computed at ``t_{k-1}`` is the one acting over ``[t_k, t_{k+1})``. The
law computed at ``t_k`` therefore acts on the state at ``t_{k+1}``, which it predicts from the sample
and the torque already on its way, with the nominal model (armature included)::

    qdd_k     = M0(q_k)^-1 (u_{k-1} - C0(q_k, qd_k) qd_k - g0(q_k) - f0(qd_k))    (one ABA)
    q_{k+1}^  = q_k + T qd_k + T^2/2 qdd_k,       qd_{k+1}^ = qd_k + T qdd_k

(``f0(qd) = Dv0 qd + Fc0 sat(qd / v_s)``, the nominal joint drives' damping and friction, when
the box has drives) and evaluates the interval law (implicit or paper,
:mod:`urpc.control.feedback`) at ``(t_k + T, q_{k+1}^, qd_{k+1}^)`` against the reference one
period ahead, extrapolated from the
reference at ``t_k`` by its Taylor polynomial (``q_d + T qd_d + T^2/2 qdd_d``, ``qd_d + T qdd_d``,
``qdd_d``; the error is ``T^3/6`` and ``T^2/2`` times the reference's jerk: 8e-9 rad and 2.5e-5 rad/s
for the paper's trajectory at 1 kHz). The prediction's error (the mismatch over one period, and
the feedback through the nominal model instead of the plant's) is bounded by the certificate's
own argument for this law (:mod:`urpc.control.delay_bound`, docs/sampled-data.md §7).
The adaptation integrates ``f(||e_k||)`` of the measured error, as without delay.

The controller's state is ``[s, u_{k-1}]`` (the gain integral of Theorem 2, when adaptive, then
the torque in flight), so the simulator's and the loop's ``output``/``advance`` calls carry it
explicitly; ``advance`` reuses the torque ``output`` just computed for the same sample (a cache
keyed by the time and the state object) instead of computing it twice.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..model.joint_dynamics import friction_torque
from ..trajectories import Reference
from .interval import IntervalPassivityController


class DelayedIntervalController(IntervalPassivityController):
    """:class:`~urpc.control.interval.IntervalPassivityController` for a one-sample actuation
    delay (see the module docstring); build it with ``urpc.synthesize(..., delay=1)``.

    Attributes:
        delay: 1 [samples].
    """

    delay = 1

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if self.sample_period is None:
            raise ValueError("a delayed law needs a sample period")
        self._adaptive_states = self.n_states
        self.n_states = self._adaptive_states + self.robot.dof
        self._cache: tuple[float, int, np.ndarray] | None = None

    def __repr__(self) -> str:
        return super().__repr__()[:-1] + ", delay=1 sample)"

    def initial_state(self) -> np.ndarray:
        """``[s = 0, u_{-1} = 0]``: no torque in flight before the first sample."""
        return np.zeros(self.n_states)

    def predict(
        self, q: np.ndarray, qd: np.ndarray, torque: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The nominal model's ``(q, qd)`` one period after ``(q, qd)`` under ``torque`` held
        (its joint drives included: the damping and Coulomb friction at ``qd`` take their part
        of the torque, as the law's compensation of them at ``qd_a`` expects)."""
        T = self.sample_period
        joints = self.bound.joints
        if joints is not None:
            torque = torque - friction_torque(joints.nominal[1], joints.nominal[2], qd)
        qdd = self.robot.forward_dynamics(q, qd, torque)
        return q + T * qd + (0.5 * T * T) * qdd, qd + T * qdd

    def output(self, t, q, qd, reference, state):
        """The torque for the period after the next one [N m]: the law at the predicted state."""
        try:
            q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
            if not (q.shape == qd.shape == self._dof_shape and len(state) == self.n_states):
                raise ValueError("wrong size")
        except (TypeError, ValueError) as exc:  # name the caller's vector, not the prediction's
            raise (
                self.state_error(q, qd, reference)
                or InputError(
                    f"the state has {len(state)} entries; this law's has {self.n_states} (the "
                    "gain integral, then the torque in flight): use controller.initial_state()",
                    field="state",
                )
            ) from exc
        k = self._adaptive_states
        T = self.sample_period
        q_next, qd_next = self.predict(q, qd, state[k:])
        rq, rqd, rqdd = (
            np.asarray(x, dtype=float) for x in (reference.q, reference.qd, reference.qdd)
        )
        ahead = Reference(rq + T * rqd + (0.5 * T * T) * rqdd, rqd + T * rqdd, rqdd)
        try:
            torque = super().output(t + T, q_next, qd_next, ahead, state[:k])
        except InputError as exc:  # a non-finite sample: name the caller's vector
            raise self.state_error(q, qd, reference) or exc from None
        self._cache = (t, id(state), torque)
        return torque

    def advance(self, t, q, qd, reference, state):
        """``[s_{k+1}, u_k]``: the gain integral advanced on the measured error, and the torque
        of this sample, now in flight."""
        k = self._adaptive_states
        cache = self._cache
        if cache is not None and cache[0] == t and cache[1] == id(state):
            torque = cache[2]
        else:
            torque = self.output(t, q, qd, reference, state)
        adaptive = super().advance(t, q, qd, reference, state[:k])
        return np.concatenate([adaptive, torque])

    def state_derivative(self, t, q, qd, reference, state):
        raise NotImplementedError("a delayed law runs sampled only")
