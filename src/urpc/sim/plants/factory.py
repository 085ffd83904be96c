"""Plants by backend name."""

from __future__ import annotations

import inspect
from typing import Any

from ...errors import InputError
from ...model.robot import Robot
from ...names import PLANT_BACKENDS
from .mujoco_plant import MujocoPlant
from .pinocchio_plant import PinocchioPlant
from .plant import Plant, PlantKind

#: Plant backend name (:data:`urpc.names.PLANT_BACKENDS`) -> class.
PLANTS: dict[str, type[Plant]] = dict(
    zip(PLANT_BACKENDS, (PinocchioPlant, MujocoPlant), strict=True)
)


def make_plant(kind: PlantKind | str, robot: Robot, **options: Any) -> Plant:
    """Build a plant of backend ``kind`` (``"pinocchio"`` or ``"mujoco"``) for ``robot``.

    Args:
        kind: Backend name, a key of :data:`PLANTS`.
        robot: The true plant (a robot with the true parameters).
        **options: Passed to the backend (``max_step`` [s]).

    Raises:
        InputError: an unknown kind or option, ``mujoco`` not installed, a robot MuJoCo cannot
            represent.
    """
    try:
        cls = PLANTS[kind]
    except (KeyError, TypeError):
        raise InputError(
            f"unknown plant {kind!r}; valid: {', '.join(PLANTS)}", field="plant"
        ) from None
    valid = [p for p in inspect.signature(cls.__init__).parameters if p not in ("self", "robot")]
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise InputError(
            f"unknown option(s) {', '.join(unknown)} for the {kind} plant; valid: {', '.join(valid)}",
            field="plant",
        )
    return cls(robot, **options)
