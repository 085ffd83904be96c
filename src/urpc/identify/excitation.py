"""Exciting trajectories: Fourier series inside the joint limits that keep the stacked regressor
well conditioned, and the identifiable parameter combinations.

:class:`FourierTrajectory` (a :class:`~urpc.trajectories.Trajectory`, so ``urpc.simulate``
can track it) is, per joint ``i``::

    q_i(t) = q0_i + sum_l  a_il sin(l w t) + b_il cos(l w t)          (l = 1..L, w = 2 pi f)

periodic with period ``1/f``, with exact bounds of every derivative,
``|q_i^(p)| <= sum_l (l w)^p sqrt(a_il^2 + b_il^2)`` (used as the jerk and snap bounds of
:mod:`urpc.identify.data` when the positions are differentiated numerically). :func:`excite`
chooses the coefficients by minimizing the condition number of the column-normalized stacked
regressor of the identifiable columns (scipy's Powell method from seeded random starts); each
candidate is scaled per joint so that the bounds above keep it inside the position limits (minus a
margin), below a fraction of the velocity limits and below an acceleration limit: the limits hold
at every time, not only at the sampled ones.

**Identifiable combinations.** QR with column pivoting of the stacked regressor gives its rank
``r`` and ``r`` independent ("base") columns; every other column is a combination of them, so the
data determine only the base parameters plus those combinations (:func:`identifiable`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import scipy.linalg
import scipy.optimize

from ..errors import InputError
from ..formats.uncertainty import BARYCENTRIC_FIELDS
from ..model.regressor import link_regressor_map
from ..model.robot import Robot
from ..trajectories import Trajectory


class FourierTrajectory(Trajectory):
    """``q0 + sum_l a_l sin(l w t) + b_l cos(l w t)`` per joint (module docstring).

    Args:
        home: ``(n,)`` offsets ``q0`` [rad].
        a, b: ``(n, L)`` coefficients [rad].
        frequency: Base frequency ``f`` [Hz].
    """

    kind = "fourier"

    def __init__(self, home, a, b, frequency: float):
        self.home = np.asarray(home, dtype=float).reshape(-1)
        self.a = np.asarray(a, dtype=float).reshape(self.home.size, -1)
        self.b = np.asarray(b, dtype=float).reshape(self.a.shape)
        self.frequency = float(frequency)
        self.dof = self.home.size

    @property
    def omega(self) -> np.ndarray:
        return 2 * np.pi * self.frequency * np.arange(1, self.a.shape[1] + 1)

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        phase = t[..., None, None] * self.omega  # (..., 1, L)
        s, c = np.sin(phase), np.cos(phase)
        w = self.omega
        q = self.home + np.sum(self.a * s + self.b * c, axis=-1)
        qd = np.sum(w * (self.a * c - self.b * s), axis=-1)
        qdd = np.sum(-(w**2) * (self.a * s + self.b * c), axis=-1)
        return q, qd, qdd

    def derivative_bound(self, order: int) -> np.ndarray:
        """``(n,)`` bound of ``|q^(order)|`` over all time (``order >= 1``; 0: ``|q - q0|``)."""
        return np.sum(self.omega**order * np.hypot(self.a, self.b), axis=1)

    def jerk_bound(self, start, stop):
        """``sum_l (l w)^3 hypot(a_l, b_l)`` per joint, for all time (so the certificate can
        cover an excitation run); rounded up."""
        peak = self.derivative_bound(3) * (1 + 1e-12)
        return np.broadcast_to(peak, np.shape(start) + (self.dof,))

    def fingerprint(self) -> dict:
        return {"home": self.home, "a": self.a, "b": self.b, "frequency": self.frequency}

    def __repr__(self) -> str:
        return f"FourierTrajectory(dof={self.dof}, harmonics={self.a.shape[1]}, f={self.frequency})"


@dataclass
class Excitation:
    """The result of :func:`excite`.

    Attributes:
        trajectory: The optimized trajectory.
        condition: Condition number of the column-normalized stacked regressor of the base
            columns at the sampled times.
        rank: Its rank (the number of identifiable combinations).
        columns: Names of the regressor's columns (``body.m``, ``body.h_x``, ...).
        base: Names of the independent columns.
        combinations: For each dependent column, its expression in the base columns (text).
        jerk, snap: ``(n,)`` exact bounds of ``|q'''|`` and ``|q''''|`` [rad/s^3, rad/s^4].
    """

    trajectory: FourierTrajectory
    condition: float
    rank: int
    columns: list[str]
    base: list[str]
    combinations: list[str]
    jerk: np.ndarray
    snap: np.ndarray


def regressor_columns(robot: Robot, payload: str | None) -> tuple[np.ndarray | None, list[str]]:
    """The map from the body regressor to the identified columns, and their names: every moving
    body's 10 standard parameters, or (payload mode) those of a body fixed to ``payload``."""
    if payload is None:
        names = []
        for j in range(1, robot.model.njoints):
            names += [f"{robot.model.names[j]}.{f}" for f in BARYCENTRIC_FIELDS]
        return None, names
    if payload not in robot.moving_link_names:
        raise InputError(
            f"no moving link '{payload}' to carry the payload; valid: "
            + ", ".join(robot.moving_link_names),
            field="payload",
        )
    B = link_regressor_map(robot, [payload])
    return B, [f"payload@{payload}.{f}" for f in BARYCENTRIC_FIELDS]


def stacked_regressor(
    robot: Robot, trajectory: Trajectory, times: np.ndarray, B=None
) -> np.ndarray:
    """Rows of Pinocchio's joint torque regressor at the trajectory's samples, stacked."""
    model, data = robot.model, robot.model.createData()
    q, qd, qdd = trajectory.evaluate(np.asarray(times, dtype=float))
    rows = []
    for k in range(len(times)):
        Y = np.asarray(
            pin.computeJointTorqueRegressor(model, data, robot.configuration(q[k]), qd[k], qdd[k])
        ).reshape(robot.dof, -1)
        rows.append(Y if B is None else Y @ B)
    return np.vstack(rows)


def identifiable(W: np.ndarray, names: list[str], tolerance: float = 1e-8):
    """``(rank, base names, combination texts)`` of a stacked regressor (module docstring)."""
    norms = np.linalg.norm(W, axis=0)
    used = norms > tolerance * max(float(norms.max(initial=0.0)), 1e-300)
    Wn = np.zeros_like(W)
    Wn[:, used] = W[:, used] / norms[used]
    _, R, order = scipy.linalg.qr(Wn, mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(R))
    rank = int(np.sum(diagonal > tolerance * max(float(diagonal.max(initial=0.0)), 1e-300)))
    base = sorted(order[:rank])
    rest = [k for k in order[rank:] if used[k]]
    combinations = []
    if rest:
        beta, *_ = np.linalg.lstsq(W[:, base], W[:, rest], rcond=None)
        for column, k in enumerate(rest):
            terms = [
                f"{beta[i, column]:+.4g} {names[b]}"
                for i, b in enumerate(base)
                if abs(beta[i, column]) > 1e-9
            ]
            combinations.append(f"{names[k]} enters only as {' '.join(terms) or '0'}")
    unused = [names[k] for k in range(len(names)) if not used[k]]
    combinations += [f"{name} does not enter the dynamics" for name in unused]
    return rank, [names[k] for k in base], combinations, base


def excite(
    robot: Robot,
    *,
    payload: str | None = None,
    harmonics: int = 4,
    frequency: float = 0.1,
    samples: int = 80,
    velocity_fraction: float = 0.5,
    acceleration_limit: float = 3.0,
    position_margin: float = 0.1,
    starts: int = 3,
    evaluations: int = 400,
    seed: int = 0,
) -> Excitation:
    """An exciting :class:`FourierTrajectory` for ``robot`` (module docstring).

    Args:
        robot: The robot.
        payload: Excite only the parameters of a payload fixed to this link.
        harmonics: ``L``, the number of harmonics.
        frequency: Base frequency [Hz] (the period is ``1/frequency``).
        samples: Times per period at which the regressor is stacked during the optimization.
        velocity_fraction: Fraction of the URDF velocity limits allowed.
        acceleration_limit: Bound of ``|qdd|`` [rad/s^2].
        position_margin: Distance kept from the position limits [rad].
        starts, evaluations: Random starts and evaluations per start of the optimizer.
        seed: Seed of the random starts.
    """
    for name, value in (("harmonics", harmonics), ("samples", samples), ("starts", starts)):
        if not isinstance(value, int) or value < 1:
            raise InputError(f"{name} must be an integer >= 1, got {value!r}", field=name)
    if not (math.isfinite(frequency) and frequency > 0):
        raise InputError(f"frequency must be > 0 [Hz], got {frequency!r}", field="frequency")
    n, L = robot.dof, harmonics
    lower, upper = robot.position_limits
    lower = np.where(np.isfinite(lower), lower, -np.pi)
    upper = np.where(np.isfinite(upper), upper, np.pi)
    home = 0.5 * (lower + upper)
    room = np.maximum(0.5 * (upper - lower) - position_margin, 0.0)
    velocity = robot.velocity_limit
    velocity = np.where(velocity > 0, velocity, 1.0) * velocity_fraction
    omega = 2 * np.pi * frequency * np.arange(1, L + 1)
    times = np.arange(samples) / (samples * frequency)
    B, names = regressor_columns(robot, payload)
    rng = np.random.default_rng(seed)

    def trajectory(theta: np.ndarray) -> FourierTrajectory:
        a, b = theta[: n * L].reshape(n, L), theta[n * L :].reshape(n, L)
        r = np.hypot(a, b)
        scale = np.ones(n)
        for limit, power in ((room, 0), (velocity, 1), (acceleration_limit, 2)):
            used = np.sum(omega**power * r, axis=1)
            scale = np.minimum(scale, np.where(used > 0, limit / np.maximum(used, 1e-300), 1.0))
        return FourierTrajectory(home, a * scale[:, None], b * scale[:, None], frequency)

    probe = trajectory(rng.normal(size=2 * n * L))
    W = stacked_regressor(robot, probe, times, B)
    rank, base_names, _, base = identifiable(W, names)

    def cost(theta: np.ndarray) -> float:
        W = stacked_regressor(robot, trajectory(theta), times, B)[:, base]
        norms = np.linalg.norm(W, axis=0)
        if np.any(norms == 0):
            return 1e12
        singular = np.linalg.svd(W / norms, compute_uv=False)
        return float(np.log(singular[0] / max(singular[-1], 1e-300)))

    best, best_cost = None, math.inf
    for _ in range(starts):
        start = rng.normal(size=2 * n * L)
        found = scipy.optimize.minimize(
            cost, start, method="Powell", options={"maxfev": evaluations, "xtol": 1e-3}
        )
        if found.fun < best_cost:
            best, best_cost = found.x, float(found.fun)
    result = trajectory(best)
    W = stacked_regressor(robot, result, times, B)
    rank, base_names, combinations, base = identifiable(W, names)
    return Excitation(
        trajectory=result,
        condition=float(math.exp(best_cost)),
        rank=rank,
        columns=names,
        base=base_names,
        combinations=combinations,
        jerk=result.derivative_bound(3),
        snap=result.derivative_bound(4),
    )
