"""Joint dynamics: reflected rotor inertia (armature), viscous damping and Coulomb friction.

A geared joint ``i`` adds to the rigid-body dynamics::

    (M(q) + diag(Ia)) qdd + C(q, qd) qd + g(q) + Dv qd + f_c = tau + d

with the armature ``Ia_i`` [kg m^2, or kg for a prismatic joint], the viscous coefficient
``Dv_i`` [N m s/rad] and the Coulomb (dry) friction ``f_c,i``, set-valued at rest::

    f_c,i = Fc_i sign(qd_i)  if qd_i != 0,        f_c,i in [-Fc_i, Fc_i]  if qd_i = 0 (sticking)

The robot carries them in its Pinocchio model (``model.armature``, ``model.damping``,
``model.friction``): Pinocchio's CRBA, RNEA and ABA add the armature to the joint-space inertia
themselves; damping and friction are :func:`friction_torque`, which the plants subtract. A
loaded robot is rigid; an uncertainty box's ``joints:`` section (:func:`resolve_joint_box`) gives
it its drives. The controller compensates the nominal drive along the reference velocity
``qd_a`` (:meth:`JointBox.nominal_torque`; ``docs/joint-dynamics.md`` says why).

**Stiction band.** The simulated plants cannot integrate the set-valued law exactly; the
Pinocchio plant regularizes it as ``f_c,i = Fc_i sat(qd_i / v_s)`` with the stiction band
``v_s = STICTION_VELOCITY``: identical to the set-valued law for ``|qd_i| >= v_s``, and where
that law sticks the regularized joint creeps at ``|qd_i| < v_s`` instead (a joint held by a net
torque ``tau_i``, ``|tau_i| < Fc_i``, settles at ``qd_i = v_s tau_i / Fc_i``). Every bound
of the mismatch covers both: inside the band the friction is anywhere in ``[-Fc_i, Fc_i]``
(:meth:`JointBox.enclose`), which is the set-valued law's own range at rest.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np

from ..errors import InputError, did_you_mean
from ..formats.uncertainty import JOINT_FIELDS, JointEntry

if TYPE_CHECKING:
    from .robot import Robot

#: Units of the joint parameters (revolute joints; prismatic: :data:`PRISMATIC_JOINT_UNITS`).
JOINT_UNITS = {"armature": "kg m^2", "damping": "N m s/rad", "friction": "N m"}
#: Units of a prismatic joint's parameters.
PRISMATIC_JOINT_UNITS = {"armature": "kg", "damping": "N s/m", "friction": "N"}
#: The stiction band ``v_s`` [rad/s or m/s]: below it a joint may be sticking (module docstring).
STICTION_VELOCITY = 1e-3
#: Relative and absolute inflation of :meth:`JointBox.enclose` for the rounding of its few
#: products and sums (each below one unit roundoff 1.1e-16 relative to the largest term).
_ROUNDING_RELATIVE = 1e-12
_ROUNDING_ABSOLUTE = 1e-15


def friction_shape(qd: np.ndarray, band: float = STICTION_VELOCITY) -> np.ndarray:
    """``sat(qd / v_s)``: the regularized ``sign(qd)`` of the plants and of the nominal
    compensation (``-1`` to ``1``, linear inside the stiction band)."""
    return np.clip(np.asarray(qd, dtype=float) / band, -1.0, 1.0)


def friction_torque(damping: np.ndarray, friction: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """``Dv qd + Fc sat(qd / v_s)`` [N m]: the torque the joints' viscous and (regularized)
    Coulomb friction exert against the motion."""
    return damping * qd + friction * friction_shape(qd)


@dataclass(frozen=True, eq=False)
class JointBox:
    """Intervals on the joint parameters of every joint (rows :data:`JOINT_FIELDS`, one column
    per joint coordinate; exact parameters have ``lower == upper``).

    Attributes:
        joint_names: The robot's joint names, one per column.
        nominal, lower, upper: ``(3, dof)`` arrays: armature [kg m^2], damping [N m s/rad],
            friction [N m] (kg, N s/m, N for prismatic joints).
    """

    joint_names: tuple[str, ...]
    nominal: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        for name in ("nominal", "lower", "upper"):
            value = np.array(getattr(self, name), dtype=float).reshape(3, len(self.joint_names))
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @classmethod
    def exact(cls, joint_names: tuple[str, ...], values: np.ndarray) -> JointBox:
        """A box with no width: every joint parameter known (``values``, shape ``(3, dof)``)."""
        return cls(tuple(joint_names), values, values, values)

    @property
    def dof(self) -> int:
        return len(self.joint_names)

    @property
    def uncertain(self) -> np.ndarray:
        """``(3, dof)`` boolean mask of the parameters with a non-zero width."""
        return self.upper > self.lower

    @property
    def armature(self) -> np.ndarray:
        """Nominal armature [kg m^2]."""
        return self.nominal[0]

    @property
    def damping(self) -> np.ndarray:
        """Nominal viscous coefficient [N m s/rad]."""
        return self.nominal[1]

    @property
    def friction(self) -> np.ndarray:
        """Nominal Coulomb friction [N m]."""
        return self.nominal[2]

    @property
    def active(self) -> bool:
        """Whether any joint term is non-zero anywhere in the box (else every joint is rigid)."""
        return bool(np.any(self.upper != 0.0) or np.any(self.lower != 0.0))

    def name(self, row: int, column: int) -> str:
        """``joint.field`` of one parameter."""
        return f"{self.joint_names[column]}.{JOINT_FIELDS[row]}"

    def nominal_torque(self, qd_a: np.ndarray, qdd_a: np.ndarray, armature: bool) -> np.ndarray:
        """The controller's compensation of the nominal joint terms [N m], along the reference
        velocity ``qd_a``: ``Dv0 qd_a + Fc0 sat(qd_a / v_s)``, plus ``Ia0 qdd_a`` when
        ``armature`` (a nominal torque from the link regressor, which carries no armature)."""
        torque = friction_torque(self.damping, self.friction, qd_a)
        return torque + self.armature * qdd_a if armature else torque

    def enclose(
        self, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` [N m] enclosing the joint part of the mismatch torque (the plant's
        drive torque minus the controller's compensation along the reference)::

            w_joint = (Ia - Ia0) qdd_a + Dv qd - Dv0 qd_a + f_c - Fc0 sat(qd_a / v_s)

        for every joint parameter of the box and every friction the set-valued law (or the
        plants' regularization inside the stiction band) allows at ``qd``. Each parameter enters
        one joint's row once, so the interval sum is the exact range (up to rounding)."""
        lower, upper = np.zeros(self.dof), np.zeros(self.dof)
        joint_terms(
            np.asarray(qd, dtype=float), np.asarray(qd_a, dtype=float),
            np.asarray(qdd_a, dtype=float), self.nominal, self.lower, self.upper,
            STICTION_VELOCITY, 0.0, np.zeros(self.dof), lower, upper,
        )  # fmt: skip
        return lower, upper


@numba.njit(cache=True)
def joint_terms(
    qd, qd_a, qdd_a, nominal, lower, upper, band, armature, out_torque, out_lower, out_upper
):  # pragma: no cover
    """Adds :meth:`JointBox.nominal_torque` (with ``Ia0 qdd_a`` times ``armature``, 0 or 1) to
    ``out_torque`` and the enclosure of :meth:`JointBox.enclose` to ``out_lower, out_upper``
    (compiled: one call per control step for both)."""
    for i in range(qd.size):
        a, v, va = qdd_a[i], qd[i], qd_a[i]
        shape = min(1.0, max(-1.0, va / band))
        out_torque[i] += armature * nominal[0, i] * a + nominal[1, i] * va + nominal[2, i] * shape
        # (Ia - Ia0) a and Dv v - Dv0 va: an interval times a number, minus a number.
        p = (lower[0, i] - nominal[0, i]) * a
        q = (upper[0, i] - nominal[0, i]) * a
        r = lower[1, i] * v
        s = upper[1, i] * v
        damping = nominal[1, i] * va
        lo = min(p, q) + min(r, s) - damping
        hi = max(p, q) + max(r, s) - damping
        magnitude = abs(p) + abs(q) + abs(r) + abs(s) + abs(damping)
        # Coulomb: f_c in sign(v) [Fc_lo, Fc_hi] outside the band, anywhere in [-Fc_hi, Fc_hi]
        # inside it; minus the compensation Fc0 sat(va / band).
        compensation = nominal[2, i] * shape
        if v >= band:
            f_lo, f_hi = lower[2, i], upper[2, i]
        elif v <= -band:
            f_lo, f_hi = -upper[2, i], -lower[2, i]
        else:
            f_lo, f_hi = -upper[2, i], upper[2, i]
        lo += f_lo - compensation
        hi += f_hi - compensation
        magnitude += abs(f_lo) + abs(f_hi) + abs(compensation)
        slack = _ROUNDING_RELATIVE * magnitude + _ROUNDING_ABSOLUTE
        out_lower[i] += lo - slack
        out_upper[i] += hi + slack


# ============================================================================ from the file
def resolve_joint_box(
    entries: Mapping[str, JointEntry], robot: Robot, source: str | None
) -> JointBox:
    """The :class:`JointBox` of the ``joints:`` section of an uncertainty file for ``robot``
    (joints not listed stay exact at the URDF's ``<dynamics>`` damping and friction, armature 0).

    Nominal values: the entry's ``nominal:``, else the URDF's (``<dynamics>`` damping and
    friction, :attr:`Robot.urdf_dynamics`; armature 0) when it lies in the interval, else the
    middle of the interval (which must then be absolute).

    Raises:
        InputError: an unknown or locked joint, a relative interval with no nominal, a nominal
            outside its interval, a negative lower end (every joint parameter is ``>= 0``);
            naming ``source`` and the field.
    """
    values = robot.joint_parameters
    values[1:] = robot.urdf_dynamics
    nominal, lower, upper = values.copy(), values.copy(), values.copy()
    names = robot.joint_names
    for name, entry in entries.items():
        prefix = f"joints.{name}"
        if name not in names:
            locked = name in robot.locked_joints
            raise InputError(
                f"joint '{name}' is locked, so it has no drive dynamics"
                if locked
                else f"unknown joint '{name}'; " + did_you_mean(name, names),
                source=source,
                field=prefix,
            )
        column = names.index(name)
        given = {} if entry.nominal is None else entry.nominal.values()
        for row, key in enumerate(JOINT_FIELDS):
            interval = getattr(entry, key)
            center = given.get(key, values[row, column])
            if interval is None:
                nominal[row, column] = lower[row, column] = upper[row, column] = center
                continue
            fieldname = f"{prefix}.{key}"
            try:
                if key not in given and interval.absolute:
                    lo, hi = interval.around(None)
                    center = center if lo <= center <= hi else 0.5 * (lo + hi)
                lo, hi = interval.around(center)
            except ValueError as exc:
                raise InputError(str(exc), source=source, field=fieldname) from None
            if interval.vanishes_at(center):
                where = (
                    "nominal:"
                    if key in given
                    else "the default: URDFs carry no armature"
                    if key == "armature"
                    else "the URDF's <dynamics>, or none"
                )
                raise InputError(
                    f"{interval.text} of a nominal {key} of 0 (from {where}) is no width at all: "
                    f"the {key} would be exactly 0; give an absolute interval, e.g. {key}: "
                    f"[0, 1] {JOINT_UNITS[key]}, or a nonzero nominal: {{{key}: ...}}",
                    source=source,
                    field=fieldname,
                )
            if lo < 0:
                raise InputError(
                    f"{key} interval [{lo:.6g}, {hi:.6g}] {JOINT_UNITS[key]} has a negative lower "
                    f"end; a joint's {key} is >= 0",
                    source=source,
                    field=fieldname,
                )
            if not lo <= center <= hi:
                raise InputError(
                    f"the nominal {key} {center:.6g} lies outside the box [{lo:.6g}, {hi:.6g}]; "
                    f"widen the interval or give nominal: {{{key}: ...}}",
                    source=source,
                    field=fieldname,
                )
            nominal[row, column], lower[row, column], upper[row, column] = center, lo, hi
    return JointBox(names, nominal, lower, upper)
