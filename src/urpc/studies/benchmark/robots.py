"""The robots and boxes of the benchmark figures, and the bound methods by name (registered ones and
variants)."""

from __future__ import annotations

from collections.abc import Callable

from ...bounds import METHODS, BoundMethod, make_bound
from ...bounds.vertex import VertexBound
from ...errors import InputError
from ...model.catalog import default_uncertainty
from ...model.robot import Robot, load_robot
from ...model.uncertainty import ParameterBox, load_uncertainty, parse_uncertainty

#: The robots of the figures; the Panda's fingers are locked (7 arm joints).
BENCHMARK_ROBOTS = ("rr_planar", "ur5", "panda")
_LOCKED = {"panda": ["panda_finger_joint1", "panda_finger_joint2"]}
#: Extra method variants, benchmarked next to the registered methods.
VARIANTS: dict[str, Callable[[Robot, ParameterBox], BoundMethod]] = {
    "vertex-plain": lambda robot, box: VertexBound(robot, box, exact_com=False),
}
#: Uncertainty of every link of the UR5 and Panda benchmark boxes (the uncertainty file format).
ALL_LINKS_ENTRY = {
    "mass": "10%",
    **{f"com_{axis}": "+-0.01" for axis in "xyz"},
    **{f"i{axis}{axis}": "10%" for axis in "xyz"},
}


def benchmark_robot(name: str) -> Robot:
    """A robot of the figures (the Panda with its fingers locked)."""
    return load_robot(name, locked_joints=_LOCKED.get(name, ()))


def benchmark_box(robot: Robot) -> ParameterBox:
    """The RR arm's shipped Table I box; else :data:`ALL_LINKS_ENTRY` on the child link of every
    joint (the link whose frame is the joint frame): ``N`` links for ``N`` joints."""
    if robot.name == "rr_planar":
        return load_uncertainty(default_uncertainty("rr_planar"), robot)
    links = {
        link.name: dict(ALL_LINKS_ENTRY)
        for link in robot.links
        if link.joint_index > 0 and link.placement.isIdentity() and link.inertia.mass > 0
    }
    return parse_uncertainty({"links": links}, robot)


def make_method(name: str, robot: Robot, box: ParameterBox) -> BoundMethod:
    """A registered method (:data:`urpc.bounds.METHODS`) or a :data:`VARIANTS` entry.

    Raises:
        InputError: unknown name (the message lists the valid ones).
    """
    if name in VARIANTS:
        return VARIANTS[name](robot, box)
    if name not in METHODS:
        valid = ", ".join([*METHODS, *VARIANTS])
        raise InputError(f"unknown bound method '{name}'; valid: {valid}", field="method")
    return make_bound(name, robot, box)
