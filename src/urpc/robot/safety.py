"""The safety layer between a control loop and a robot: what the arm is allowed to receive.

Per cycle, :meth:`SafetyLayer.check_state` first looks at the measured state and
:meth:`SafetyLayer.limit` then at the torque the controller asks for:

* **state faults** (the loop sends :meth:`SafetyLayer.safe_command` and stops): a non-finite
  ``q`` or ``qd``; a joint outside its position limits shrunk by ``position_margin``; a joint
  faster than ``(1 - velocity_margin)`` times its velocity limit;
* **torque** (the loop continues): a non-finite torque is a fault; otherwise each joint is clipped
  to its torque limit (the URDF's ``effort`` by default) and, when a rate limit is set, to
  ``tau_prev +- rate * period``.

Every intervention is counted by kind (:attr:`SafetyLayer.counts`) and logged with its time,
joint and values (:attr:`SafetyLayer.events`, the first :data:`MAX_EVENTS` in full). The safe
command is selectable: ``zero`` (no torque: the arm's own brakes or gravity take over) or
``damping`` (``-D qd``, clipped to the torque limits: a viscous brake that slows a moving arm).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..names import SAFE_MODES
from ..validation import number_in, per_joint, positive_number

#: Interventions logged in full (all are counted).
MAX_EVENTS = 1000
#: Kinds of intervention, in the order of the checks.
KINDS = (
    "non_finite_state",
    "position_limit",
    "velocity_limit",
    "stale_state",
    "non_finite_torque",
    "torque_limit",
    "torque_rate",
    "watchdog",
)
#: Kinds after which the loop stops.
FAULTS = ("non_finite_state", "position_limit", "velocity_limit", "non_finite_torque", "watchdog")


def _iterable(value) -> tuple:
    """``value``'s items, or ``(value,)`` when it has none (a number): for a type check."""
    try:
        return tuple(value)
    except TypeError:
        return (value,)


@dataclass(frozen=True)
class Intervention:
    """One intervention: at time ``t`` [s] (loop time), of ``kind`` (:data:`KINDS`), on
    ``joints`` (indices; empty when not joint-specific), with a readable ``detail``."""

    t: float
    kind: str
    joints: tuple[int, ...]
    detail: str

    def to_dict(self) -> dict[str, Any]:
        return {"t": self.t, "kind": self.kind, "joints": list(self.joints), "detail": self.detail}


class SafetyLayer:
    """Limits on what a loop may command, and the checks of the state it acts on.

    Args:
        torque_limit: Per-joint torque bound [N m or N], ``dof`` positive numbers.
        period: The control period [s] (for the rate limit).
        torque_rate_limit: Per-joint bound on the torque change [N m/s] (scalar or per joint),
            or ``None``: no rate limit.
        position_limits: ``(lower, upper)`` [rad or m] (infinite: unbounded), or ``None``.
        position_margin: Distance from the limits [rad or m] at which the loop stops.
        velocity_limit: Per-joint velocity bound [rad/s or m/s] (0 or non-finite: none), or
            ``None``.
        velocity_margin: Fraction of the velocity limit kept as margin, in ``[0, 1)``.
        safe_mode: ``zero`` or ``damping`` (:data:`SAFE_MODES`).
        damping: ``D`` of the damping brake [N m s/rad], scalar or per joint; default: the torque
            limit over the velocity limit (full torque at full speed), 1 where unlimited.
        joint_names: For messages.

    Raises:
        InputError: a limit that is not positive, a margin out of range, an unknown safe mode.
    """

    def __init__(
        self,
        torque_limit,
        period: float,
        *,
        torque_rate_limit=None,
        position_limits=None,
        position_margin: float = 0.02,
        velocity_limit=None,
        velocity_margin: float = 0.05,
        safe_mode: str = "damping",
        damping=None,
        joint_names=None,
    ):
        self.torque_limit = per_joint("torque_limit", torque_limit, None, "N m", finite=False)
        self.dof = n = len(self.torque_limit)
        if n == 0 or not np.all(self.torque_limit > 0):
            raise InputError(
                f"{self.torque_limit.tolist()}: every torque limit must be > 0 [N m], one per "
                "joint",
                field="torque_limit",
            )
        if joint_names is not None:
            if isinstance(joint_names, str) or not all(
                isinstance(name, str) for name in _iterable(joint_names)
            ):
                raise InputError(
                    f"{joint_names!r}: expected a list of {n} joint names (strings), or None",
                    field="joint_names",
                )
            joint_names = list(joint_names)
        self.period = positive_number("period", period, "a finite number > 0 [s]")
        self.rate_step = None
        if torque_rate_limit is not None:
            rate = per_joint("torque_rate_limit", torque_rate_limit, n, "N m/s", finite=False)
            if not np.all(rate > 0):
                raise InputError(f"{rate.tolist()}: must be > 0 [N m/s]", field="torque_rate_limit")
            self.rate_step = rate * self.period
        self.position_margin = number_in(
            "position_margin", position_margin, "a finite number >= 0 [rad]", lambda x: x >= 0
        )
        if position_limits is None:
            lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
        else:
            try:
                lower, upper = position_limits
            except (TypeError, ValueError):
                raise InputError(
                    f"{position_limits!r} is not a pair (lower, upper) of {n} numbers each",
                    field="position_limits",
                ) from None
            lower = per_joint("position_limits", lower, n, "rad", finite=False)
            upper = per_joint("position_limits", upper, n, "rad", finite=False)
        self.lower = lower + self.position_margin
        self.upper = upper - self.position_margin
        closed = np.flatnonzero(~(self.lower <= self.upper))
        if closed.size:
            j = int(closed[0])
            name = joint_names[j] if joint_names and len(joint_names) == n else f"joint {j + 1}"
            raise InputError(
                f"{name}: the limits [{lower[j]:g}, {upper[j]:g}] less the margin "
                f"{self.position_margin:g} leave no allowed position; give lower <= upper and a "
                "smaller position_margin",
                field="position_limits" if lower[j] > upper[j] else "position_margin",
            )
        self.velocity_margin = number_in(
            "velocity_margin", velocity_margin, "a number in [0, 1)", lambda x: 0 <= x < 1
        )
        if velocity_limit is None:
            limit = np.full(n, np.inf)
        else:
            limit = per_joint("velocity_limit", velocity_limit, n, "rad/s", finite=False)
            if np.any(limit < 0):
                raise InputError(
                    f"{limit.tolist()}: a velocity limit must be > 0 [rad/s] (0 or inf: none)",
                    field="velocity_limit",
                )
        limit = np.where(np.isfinite(limit) & (limit > 0), limit, np.inf)
        self.velocity_limit = limit
        self.velocity_bound = limit * (1.0 - self.velocity_margin)
        if safe_mode not in SAFE_MODES:
            raise InputError(
                f"unknown safe mode {safe_mode!r}; valid: {', '.join(SAFE_MODES)}",
                field="safe_mode",
            )
        self.safe_mode = safe_mode
        if damping is None:  # full torque at full speed; 1 where either is unlimited
            finite = np.isfinite(limit) & np.isfinite(self.torque_limit)
            damping = np.where(finite, self.torque_limit / np.where(finite, limit, 1.0), 1.0)
        self.damping = per_joint("damping", damping, n, "N m s/rad")
        if np.any(self.damping < 0):
            raise InputError(
                f"{self.damping.tolist()}: the brake's damping must be >= 0 [N m s/rad] (a "
                "negative one pushes the arm along its velocity)",
                field="damping",
            )
        if joint_names is not None and len(joint_names) != n:
            raise InputError(f"{len(joint_names)} names for {n} joints", field="joint_names")
        self.joint_names = (
            tuple(joint_names) if joint_names else tuple(f"joint {i + 1}" for i in range(n))
        )
        self.counts: Counter[str] = Counter()
        self.events: list[Intervention] = []
        self.last_torque = np.zeros(n)
        self.clipped = False

    @classmethod
    def for_robot(cls, robot, period: float, *, torque_limit=None, **options) -> SafetyLayer:
        """The layer for a :class:`~urpc.model.robot.Robot`: torque limits from the URDF's efforts
        (unless ``torque_limit`` is given), its position and velocity limits.

        Raises:
            InputError: ``robot`` is not a Robot; a joint without a usable effort limit and no
                ``torque_limit``.
        """
        from ..model.robot import Robot

        if not isinstance(robot, Robot):
            hint = f" (load it first: urpc.load_robot({robot!r}))" if isinstance(robot, str) else ""
            raise InputError(
                f"expected a Robot (urpc.load_robot(...), controller.robot), got "
                f"{type(robot).__name__}{hint}",
                field="robot",
            )
        if torque_limit is None:
            effort = robot.effort_limit
            missing = [
                robot.joint_names[j] for j in np.flatnonzero(~(np.isfinite(effort) & (effort > 0)))
            ]
            if missing:
                raise InputError(
                    f"joints {', '.join(missing)} have no effort limit in the URDF; give a "
                    "torque limit",
                    source=robot.urdf_path,
                    field="torque_limit",
                )
            torque_limit = effort
        torque_limit = per_joint("torque_limit", torque_limit, robot.dof, "N m", finite=False)
        return cls(
            torque_limit,
            period,
            position_limits=robot.position_limits,
            velocity_limit=robot.velocity_limit,
            joint_names=robot.joint_names,
            **options,
        )

    # ------------------------------------------------------------------ checks
    def check_state(self, t: float, q: np.ndarray, qd: np.ndarray) -> Intervention | None:
        """The first state fault at time ``t`` [s], logged, or ``None`` when the state is fine.

        Raises:
            InputError: ``q`` or ``qd`` is not ``dof`` numbers (a robot of another arm).
        """
        q, qd = self._vector("q", q), self._vector("qd", qd)
        # entry by entry: a dot product overflows for a finite 1e300, which is out of range,
        # not non-finite
        finite = np.isfinite(q) & np.isfinite(qd)
        if not finite.all():
            bad = tuple(int(j) for j in np.flatnonzero(~finite))
            return self._record(t, "non_finite_state", bad, f"q = {q.tolist()}, qd = {qd.tolist()}")
        outside = np.flatnonzero((q < self.lower) | (q > self.upper))
        if outside.size:
            j = int(outside[0])
            return self._record(
                t,
                "position_limit",
                tuple(int(k) for k in outside),
                f"{self.joint_names[j]} at {q[j]:.6g}, allowed [{self.lower[j]:.6g}, "
                f"{self.upper[j]:.6g}] (limits less a margin of {self.position_margin:g})",
            )
        fast = np.flatnonzero(np.abs(qd) > self.velocity_bound)
        if fast.size:
            j = int(fast[0])
            return self._record(
                t,
                "velocity_limit",
                tuple(int(k) for k in fast),
                f"{self.joint_names[j]} at {qd[j]:.6g}, allowed {self.velocity_bound[j]:.6g} "
                f"({1 - self.velocity_margin:g} of the limit {self.velocity_limit[j]:.6g})",
            )
        return None

    def stale(self, t: float, detail: str) -> Intervention:
        """Log a stale or missing state (the loop then sends the safe command)."""
        return self._record(t, "stale_state", (), detail)

    def limit(self, t: float, tau: np.ndarray) -> tuple[np.ndarray, Intervention | None]:
        """The torque the robot may receive for the controller's ``tau`` [N m], and a fault
        (a non-finite torque; the returned torque is then the safe command at rest).

        Raises:
            InputError: ``tau`` is not ``dof`` numbers.
        """
        tau = self._vector("tau", tau)
        if not np.isfinite(tau).all():  # not tau @ tau: a finite 1e300 is clipped, not a fault
            fault = self._record(t, "non_finite_torque", (), f"tau = {tau.tolist()}")
            return self.safe_command(np.zeros(self.dof)), fault
        limit = self.torque_limit
        out = np.minimum(np.maximum(tau, -limit), limit)
        clipped = out != tau
        self.clipped = bool(clipped.any())
        if self.clipped:
            joints = tuple(int(j) for j in np.flatnonzero(clipped))
            self._record(
                t,
                "torque_limit",
                joints,
                f"{tau[list(joints)].tolist()} clipped to +-{limit[list(joints)].tolist()}",
            )
        if self.rate_step is not None:
            previous = self.last_torque
            limited = np.minimum(
                np.maximum(out, previous - self.rate_step), previous + self.rate_step
            )
            changed = limited != out
            if changed.any():
                self.clipped = True
                joints = tuple(int(j) for j in np.flatnonzero(changed))
                self._record(
                    t,
                    "torque_rate",
                    joints,
                    f"change {(out - previous)[list(joints)].tolist()} above "
                    f"{self.rate_step[list(joints)].tolist()} per period",
                )
                out = limited
        self.last_torque = out
        return out, None

    def safe_command(self, qd: np.ndarray) -> np.ndarray:
        """The safe torque: zero, or the damping brake ``-D qd`` within the torque limits (zero
        where ``qd`` is not finite)."""
        qd = self._vector("qd", qd)
        if self.safe_mode == "zero":
            tau = np.zeros(self.dof)
        else:
            velocity = np.where(np.isfinite(qd), qd, 0.0)
            tau = np.clip(-self.damping * velocity, -self.torque_limit, self.torque_limit)
        self.last_torque = tau
        return tau

    def _vector(self, field: str, value) -> np.ndarray:
        """``value`` as the float vector of ``dof`` entries the checks need (a NaN stays: it is a
        fault the checks report, not a bad argument)."""
        try:
            vector = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{value!r} is not {self.dof} numbers", field=field) from None
        if vector.shape != (self.dof,):
            raise InputError(
                f"{field} has shape {vector.shape}; the safety layer guards {self.dof} joints "
                f"({', '.join(self.joint_names)}), so it needs ({self.dof},)",
                field=field,
            )
        return vector

    def watchdog(self, t: float, detail: str) -> Intervention:
        """Log the watchdog's trip."""
        return self._record(t, "watchdog", (), detail)

    # ------------------------------------------------------------------ record
    @property
    def total(self) -> int:
        return sum(self.counts.values())

    def summary(self) -> dict[str, Any]:
        return {
            "total": self.total,
            "counts": {kind: self.counts.get(kind, 0) for kind in KINDS},
            "torque_limit": self.torque_limit.tolist(),
            "torque_rate_limit": None
            if self.rate_step is None
            else (self.rate_step / self.period).tolist(),
            "safe_mode": self.safe_mode,
        }

    def _record(self, t: float, kind: str, joints: tuple[int, ...], detail: str) -> Intervention:
        event = Intervention(float(t), kind, joints, detail)
        self.counts[kind] += 1
        if len(self.events) < MAX_EVENTS:
            self.events.append(event)
        return event
