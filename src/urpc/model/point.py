"""A parameter point: the parameters of one true plant inside (or near) a
:class:`~urpc.model.parameter_box.ParameterBox`, typed.

A :class:`ParameterPoint` holds, per link or payload, the 10 coordinates of that body (in the kind
of its box: physical or barycentric, physical for a body without a box), and optionally the
``(3, dof)`` joint parameters (armature, damping, friction rows). It is read-only: its arrays
cannot be written, and ``dataclasses.replace(point, links=...)`` gives a changed copy.

Older code passed a point as a ``dict`` of link name -> coordinates with the joint parameters
under the key :data:`JOINTS` (``"<joints>"``); every function taking a point still accepts that
form (:meth:`ParameterPoint.coerce`), and :meth:`ParameterPoint.as_dict` gives it back.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError, did_you_mean

if TYPE_CHECKING:
    from .parameter_box import ParameterBox

#: The key of the joint parameters in the older ``dict`` form of a point; angle brackets cannot
#: start a URDF link name.
JOINTS = "<joints>"


@dataclass(frozen=True, eq=False, repr=False)
class ParameterPoint:
    """One point of a parameter box, the parameters of a true plant (:meth:`ParameterBox.plant`
    builds that robot): what the point does not name stays nominal.

    Attributes:
        links: Link or payload name -> its 10 coordinates (the kind of its box, in the order of
            ``box.link_box(name).fields``; physical for a body without a box), read-only.
        joints: The ``(3, dof)`` joint parameters (armature, damping, friction rows), or
            ``None``: the drives stay nominal.

    ``ParameterPoint(links, joints)`` checks the shapes (10 finite numbers per body; 3 rows of
    finite numbers); :meth:`for_box` also checks the names and the number of joints against a
    box. Points compare equal when they name the same bodies with the same numbers.

    Raises:
        InputError: a name that is no string or is :data:`JOINTS` (field ``links``), coordinates
            of another shape or not finite (field ``point.NAME``, or ``point.<joints>``).
    """

    links: Mapping[str, np.ndarray]
    joints: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.links, Mapping):
            raise InputError(
                f"links must map link or payload names to coordinates, got "
                f"{type(self.links).__name__}",
                field="links",
            )
        links = {}
        for name, values in self.links.items():
            if not isinstance(name, str) or not name or name == JOINTS:
                raise InputError(
                    f"{name!r} is no link or payload name; the joint parameters go in joints=",
                    field="links",
                )
            links[name] = _read_only(point_values(values, name, (10,)))
        object.__setattr__(self, "links", MappingProxyType(links))
        if self.joints is not None:
            rows = np.shape(self.joints)
            dof = rows[1] if len(rows) == 2 and rows[0] == 3 else None
            shape = (3, dof) if dof else (3, "dof")
            object.__setattr__(self, "joints", _read_only(point_values(self.joints, JOINTS, shape)))

    @classmethod
    def for_box(
        cls,
        box: ParameterBox,
        links: Mapping[str, Any] | None = None,
        joints: Any = None,
    ) -> ParameterPoint:
        """A point of ``box``: ``links`` may name the bodies the box bounds, and, when the box
        knows its robot, that robot's other moving links (exact for the controller); ``joints``
        has one column per joint.

        Raises:
            InputError: an unknown name (field ``links.NAME``, with the valid names), or the
                shapes of :class:`ParameterPoint`.
        """
        links = {} if links is None else links
        valid = [b.link for b in box.links]
        dof = None if box.joints is None else box.joints.dof
        if box.robot is not None:
            robot = box.nominal_robot(box.robot)
            valid += [name for name in robot.moving_link_names if name not in valid]
            dof = robot.dof
        for name in links:
            if name not in valid:
                raise InputError(
                    f"unknown link '{name}'; " + did_you_mean(name, valid),
                    box.source,
                    f"links.{name}",
                )
        if joints is not None and dof is not None:
            point_values(joints, JOINTS, (3, dof))
        return cls(links, joints)

    @classmethod
    def coerce(cls, point: ParameterPoint | Mapping[str, Any], dof: int | None = None):
        """``point`` as a :class:`ParameterPoint`: itself, or the older ``dict`` form (link name
        -> coordinates, :data:`JOINTS` -> the joint parameters) converted; with ``dof``, its
        joint parameters must be ``(3, dof)``.

        Raises:
            InputError: not a point (field ``point``), or the shapes of :class:`ParameterPoint`.
        """
        if isinstance(point, ParameterPoint):
            if point.joints is not None and dof is not None:
                point_values(point.joints, JOINTS, (3, dof))
            return point
        if not isinstance(point, Mapping):
            raise InputError(
                f"expected a ParameterPoint (box.sample(rng), urpc.load_parameter_point(...)) "
                f"or a dict of link name -> coordinates, got {type(point).__name__}",
                field="point",
            )
        joints = point.get(JOINTS)
        if joints is not None and dof is not None:
            joints = point_values(joints, JOINTS, (3, dof))
        return cls({k: v for k, v in point.items() if k != JOINTS}, joints)

    def as_dict(self) -> dict[str, np.ndarray]:
        """The older form: link name -> a writable copy of its coordinates, and :data:`JOINTS`
        -> the joint parameters when the point has them."""
        form = {name: values.copy() for name, values in self.links.items()}
        if self.joints is not None:
            form[JOINTS] = self.joints.copy()
        return form

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ParameterPoint):
            return NotImplemented
        if self.links.keys() != other.links.keys() or (self.joints is None) != (
            other.joints is None
        ):
            return False
        same = all(np.array_equal(v, other.links[k]) for k, v in self.links.items())
        return same and (self.joints is None or np.array_equal(self.joints, other.joints))

    def __hash__(self) -> int:
        links = tuple(sorted((k, tuple(v.tolist())) for k, v in self.links.items()))
        joints = None if self.joints is None else tuple(self.joints.ravel().tolist())
        return hash((links, joints))

    def __repr__(self) -> str:
        links = ", ".join(f"{k!r}: {_listed(v)}" for k, v in self.links.items())
        joints = "None" if self.joints is None else _listed(self.joints)
        return f"ParameterPoint(links={{{links}}}, joints={joints})"

    # The older dict form, read for one release: point[name], name in point, get, keys, values,
    # items (the dict of as_dict(), with a DeprecationWarning).
    def __getitem__(self, name: str) -> np.ndarray:
        return self._legacy(f"point[{name!r}]")[name]

    def __contains__(self, name: object) -> bool:
        return name in self._legacy(f"{name!r} in point")

    def get(self, name: str, default: Any = None) -> Any:
        return self._legacy(f"point.get({name!r})").get(name, default)

    def keys(self):
        return self._legacy("point.keys()").keys()

    def values(self):
        return self._legacy("point.values()").values()

    def items(self):
        return self._legacy("point.items()").items()

    def _legacy(self, use: str) -> dict[str, np.ndarray]:
        warnings.warn(
            f"{use}: a parameter point is a ParameterPoint, no longer a dict; read point.links "
            f"(link name -> coordinates) and point.joints (for {JOINTS!r}), or point.as_dict()",
            DeprecationWarning,
            stacklevel=3,
        )
        return self.as_dict()


def point_values(values: Any, name: str, shape: tuple) -> np.ndarray:
    """The coordinates of one entry of a parameter point as floats of ``shape``.

    Raises:
        InputError: not numbers, another shape, or a non-finite entry (field ``point.NAME``).
    """
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        array = None
    if array is None or array.shape != shape or not np.isfinite(array).all():
        what = (
            f"{shape[0]} finite numbers" if len(shape) == 1 else f"finite numbers of shape {shape}"
        )
        raise InputError(
            f"{values!r} must be {what} (the coordinates of its box, in the order of "
            "box.link_box(name).fields; 'joints': armature, damping and friction rows)",
            field=f"point.{name}",
        )
    return array


def _read_only(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=float)  # a copy: the caller's array stays its own
    array.flags.writeable = False
    return array


def _listed(array: np.ndarray) -> str:
    """``[10, 0.525, 1.66667]`` (6 significant digits; rows of a 2-D array nested)."""
    if array.ndim > 1:
        return "[" + ", ".join(_listed(row) for row in array) + "]"
    return "[" + ", ".join(f"{value:.6g}" for value in array) + "]"
