"""The uncertainty box of a modular arm: the modules' boxes, payload and drives in one document.

Each moving module's box applies unchanged to its link ``m<i>_<module>`` (whose frame is the
module frame); modules before the first actuator are fixed to the world and left out. A payload
module becomes the ``payload:`` entry on the :data:`TCP_LINK` link, its box mapped into the TCP
frame. An actuator's drive becomes the ``joints:`` entry of its joint (``joint<k>``), absolute
intervals and nominal values written out (:meth:`urpc.model.drives.Drive.entry`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from .assembly_urdf import PAYLOAD_NAME, SNAP, TCP_LINK, Part, snapped
from .modules import Module
from .parameter_box import PHYSICAL_FIELDS


def uncertainty_document(
    chain: Sequence[Module],
    parts: Sequence[Part],
    name: str,
    disturbance: float | None,
    description: str | None,
) -> dict[str, Any]:
    """The combined uncertainty document (the uncertainty format, plain values) of a validated
    chain: each moving module's box on its link, a payload module as the ``payload:`` entry on
    :data:`TCP_LINK`, each actuator's drive as the ``joints:`` entry of its joint."""
    document: dict[str, Any] = {
        "robot": name,
        "description": description or "assembly of " + ", ".join(m.name for m in chain),
        "disturbance": "unknown" if disturbance is None else float(disturbance),
        "links": {},
    }
    moving = False  # modules before the first actuator are fixed to the world: not in the box
    for module, part in zip(chain, parts, strict=True):
        moving = moving or module.kind == "actuator"
        if module.kind == "payload":
            document["payload"] = _payload_entry(module)
        elif moving and module.uncertainty:
            document["links"][part.link] = _plain(module.uncertainty)
        if module.drive is not None:
            document.setdefault("joints", {})[part.joint] = module.drive.entry()
    return document


def _payload_entry(module: Module) -> dict[str, Any]:
    """The ``payload:`` entry of a payload module: its box mapped into the TCP frame.

    The payload frame sits at ``P^-1`` in the TCP frame (``P`` its input frame). With ``R, t``
    that pose, ``c_tcp = R c + t`` and ``I_tcp = R I R^T``: every physical coordinate is an affine
    function of the module's, and the box is mapped entry by entry (exact when ``R`` is a signed
    permutation, the interval hull otherwise).
    """
    pose = module.proximal.placement.inverse()
    linear, offset = _physical_map(pose)
    box = module.box
    positive, negative = np.maximum(linear, 0.0), np.minimum(linear, 0.0)
    lower = positive @ box.lower + negative @ box.upper + offset
    upper = positive @ box.upper + negative @ box.lower + offset
    nominal = linear @ box.nominal + offset
    entry: dict[str, Any] = {"name": PAYLOAD_NAME, "link": TCP_LINK}
    for k, key in enumerate(PHYSICAL_FIELDS):
        if upper[k] > lower[k]:
            entry[key] = [float(lower[k]), float(upper[k])]
        elif nominal[k] != 0.0:
            entry[key] = float(nominal[k])
    entry["nominal"] = {key: float(nominal[k]) for k, key in enumerate(PHYSICAL_FIELDS)}
    return entry


def _physical_map(pose: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    """``(L, b)`` with ``p' = L p + b`` the physical coordinates of a body moved by ``pose``."""
    R = snapped(pose.rotation)
    linear = np.zeros((10, 10))
    linear[0, 0] = 1.0
    linear[1:4, 1:4] = R
    # Inertia components in PHYSICAL_FIELDS order (xx, xy, yy, xz, yz, zz) as matrix entries.
    entries = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))
    for j, (a, b) in enumerate(entries):
        unit = np.zeros((3, 3))
        unit[a, b] = unit[b, a] = 1.0
        rotated = R @ unit @ R.T
        linear[4:, 4 + j] = [rotated[r, c] for r, c in entries]
    offset = np.zeros(10)
    offset[1:4] = np.where(np.abs(pose.translation) < SNAP, 0.0, pose.translation)
    return snapped(linear), offset


def _plain(value: Any) -> Any:
    """A copy made of plain dicts, lists, strings and floats (for the YAML writer)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value
