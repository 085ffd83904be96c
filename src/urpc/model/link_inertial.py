"""The inertial data of one URDF link (:class:`LinkInertial`), kept per link even where Pinocchio
merges links joined by fixed joints into one body, and the body inertia they add up to."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class LinkInertial:
    """Inertial data of one URDF link, and where Pinocchio attached it.

    Attributes:
        name: URDF link name.
        joint_index: Index of the Pinocchio joint whose body carries the link (0: the fixed base).
        placement: Pose of the link frame in that joint's frame.
        inertia: Spatial inertia of the link expressed in the link frame (mass [kg], center of
            mass in the link frame [m], rotational inertia about the center of mass [kg m^2]).
    """

    name: str
    joint_index: int
    placement: pin.SE3
    inertia: pin.Inertia

    @property
    def parameters(self) -> np.ndarray:
        """The 10 standard parameters in the link frame, Pinocchio order
        ``[m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]`` (about the link origin)."""
        return np.asarray(self.inertia.toDynamicParameters()).copy()


def body_inertia(links: Sequence[LinkInertial], joint_index: int) -> pin.Inertia:
    """The spatial inertia of Pinocchio's joint ``joint_index``'s body: the sum of the links it
    carries, each moved to the joint frame."""
    total = pin.Inertia.Zero()
    for link in links:
        if link.joint_index == joint_index:
            total += link.placement.act(link.inertia)
    return total
