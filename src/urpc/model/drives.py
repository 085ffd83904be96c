"""The drive of an actuator module: its joint's armature, viscous damping and Coulomb friction.

An actuator module file may carry ``drive:`` (:class:`urpc.formats.uncertainty.JointEntry`, the
keys of a ``joints:`` entry of the uncertainty format). A module has no URDF to take nominal
values from, so a field's nominal is its ``nominal:`` value, else the middle of its interval
(which must then be absolute), and a field given neither is 0 (no such term). When modules are
assembled, each drive becomes the ``joints:`` entry of its joint (:func:`drive_entry`: absolute
intervals and every nominal written out, so the box read back is the module's) and the URDF
joint's ``<dynamics damping friction>`` (the nominal, for other readers of the URDF such as
MuJoCo; a URDF has no armature). As for any robot, the loaded assembly is rigid and its box's
``joints:`` section puts the drives into the nominal model and the plants.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..formats.uncertainty import JOINT_FIELDS, JointEntry
from .joint_dynamics import JOINT_UNITS


@dataclass(frozen=True, eq=False)
class Drive:
    """The resolved drive of one actuator module.

    Attributes:
        nominal, lower, upper: ``(3,)`` arrays in :data:`JOINT_FIELDS` order: armature
            [kg m^2], viscous damping [N m s/rad], Coulomb friction [N m].
    """

    nominal: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        for name in ("nominal", "lower", "upper"):
            value = np.array(getattr(self, name), dtype=float).reshape(3)
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def armature(self) -> float:
        """Nominal armature [kg m^2]."""
        return float(self.nominal[0])

    @property
    def damping(self) -> float:
        """Nominal viscous damping [N m s/rad]."""
        return float(self.nominal[1])

    @property
    def friction(self) -> float:
        """Nominal Coulomb friction [N m]."""
        return float(self.nominal[2])

    def entry(self) -> dict[str, Any]:
        """The ``joints:`` entry of the uncertainty format: ``[lo, hi]`` of every uncertain field
        and ``nominal:`` of all three (plain floats, for the YAML writer)."""
        entry: dict[str, Any] = {
            key: [float(self.lower[k]), float(self.upper[k])]
            for k, key in enumerate(JOINT_FIELDS)
            if self.upper[k] > self.lower[k]
        }
        entry["nominal"] = {key: float(self.nominal[k]) for k, key in enumerate(JOINT_FIELDS)}
        return entry

    def describe(self) -> dict[str, Any]:
        """JSON-ready: per field its nominal and interval, with the unit in the key."""
        return {
            f"{key} [{JOINT_UNITS[key]}]": {
                "nominal": float(self.nominal[k]),
                "interval": [float(self.lower[k]), float(self.upper[k])],
            }
            for k, key in enumerate(JOINT_FIELDS)
        }


def resolve_drive(entry: JointEntry, source: str | None, field: str = "drive") -> Drive:
    """The :class:`Drive` of a module file's ``drive:`` entry.

    Raises:
        InputError: a relative interval with no ``nominal:``, a negative lower end (every joint
            parameter is ``>= 0``), a nominal outside its interval; naming ``source`` and the
            field (``drive.friction``).
    """
    given = {} if entry.nominal is None else entry.nominal.values()
    nominal, lower, upper = np.zeros(3), np.zeros(3), np.zeros(3)
    for k, key in enumerate(JOINT_FIELDS):
        interval = getattr(entry, key)
        center = given.get(key)
        if interval is None:
            nominal[k] = lower[k] = upper[k] = 0.0 if center is None else center
            continue
        name = f"{field}.{key}"
        if center is None and not interval.absolute:
            raise InputError(
                f"{interval.text} is relative, but the drive gives no nominal {key}: give "
                f"'nominal: {{{key}: ...}}' [{JOINT_UNITS[key]}] or an absolute interval [lo, hi]",
                source,
                name,
            )
        try:
            if center is None:
                lo, hi = interval.around(None)
                center = 0.5 * (lo + hi)
            lo, hi = interval.around(center)
        except ValueError as exc:
            raise InputError(str(exc), source, name) from None
        if lo < 0:
            raise InputError(
                f"{key} interval [{lo:.6g}, {hi:.6g}] {JOINT_UNITS[key]} has a negative lower end; "
                f"a joint's {key} is >= 0",
                source,
                name,
            )
        if not lo <= center <= hi:
            raise InputError(
                f"the nominal {key} {center:.6g} lies outside the box [{lo:.6g}, {hi:.6g}] "
                f"{JOINT_UNITS[key]}; widen the interval or change nominal: {{{key}: ...}}",
                source,
                name,
            )
        nominal[k], lower[k], upper[k] = center, lo, hi
    return Drive(nominal, lower, upper)
