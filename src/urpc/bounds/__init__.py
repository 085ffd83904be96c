"""Bound methods for the mismatch torque ``w`` over a parameter box (the interval layer).

``make_bound(name, robot, box)`` builds one by name; ``METHODS`` lists them.
"""

from __future__ import annotations

from ..errors import InputError
from ..model.robot import Robot
from ..model.uncertainty import ParameterBox
from ..names import BOUND_METHODS
from .base import BoundMethod, RegressorBound, check_box
from .hull import HullBound
from .rigorous import RigorousBound
from .vertex import VertexBound

#: Bound method name (:data:`urpc.names.BOUND_METHODS`) -> class.
METHODS: dict[str, type[BoundMethod]] = dict(
    zip(BOUND_METHODS, (HullBound, VertexBound, RigorousBound), strict=True)
)


def make_bound(name: str, robot: Robot, box: ParameterBox) -> BoundMethod:
    """Build the bound method ``name`` for ``robot`` and ``box``.

    Raises:
        InputError: unknown method name (the message lists the valid ones).
    """
    try:
        cls = METHODS[name]
    except KeyError:
        raise InputError(
            f"unknown bound method '{name}'; valid: {', '.join(METHODS)}", field="method"
        ) from None
    return cls(robot, box)


def default_method(box: ParameterBox) -> str:
    """The designed default: ``vertex`` when a link box is physical, else ``hull`` (exact).

    Raises:
        InputError: ``box`` is not a :class:`~urpc.model.uncertainty.ParameterBox`.
    """
    check_box(box)
    if any(b.kind == "physical" for b in box.uncertain_links) and "vertex" in METHODS:
        return "vertex"
    return "hull"


__all__ = ["METHODS", "BoundMethod", "RegressorBound", "default_method", "make_bound"]
