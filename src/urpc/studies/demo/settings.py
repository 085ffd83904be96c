"""The demo's default settings, and what a configuration may be (an assembly name or file, a
module list, or a mapping) with its name and output folder."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

#: The shipped assemblies the reconfiguration demo runs, in order.
DEFAULT_CONFIGURATIONS = ("arm_3dof", "arm_4dof", "arm_4dof_vacuum")
#: The tool-change demo: the gripper arm grasps a heavier object.
TOOL_CHANGE = ("arm_4dof", "arm_4dof_3kg")
#: Required tracking precision ``||q_d - q|| < epsilon`` [rad].
EPSILON = 1e-2
#: Control period [s] (1 kHz, zero-order hold).
SAMPLE_PERIOD = 1e-3
#: Radius [N m] of the ball the input disturbance is drawn from at every sample, unknown to the
#: controller: of the order of the friction of harmonic-drive joints of this size, on top of the
#: drives' own Coulomb friction and damping (in the box and drawn in the plant).
DISTURBANCE_BOUND = 2.0
#: Simulated time of one configuration [s].
DURATION = 8.0
#: How many times the synthesis of a configuration is repeated to time it (the median is kept).
TIMING_REPEATS = 5

#: A configuration: a shipped assembly name, an assembly file, a list of module names, or a
#: mapping ``{"name": ..., "modules": [...]}``.
ConfigurationLike = str | Path | Sequence[str] | Mapping[str, Any]


def configuration_name(configuration: ConfigurationLike) -> str:
    """A name for a configuration before it is composed (for folders and messages)."""
    if isinstance(configuration, Path):
        return configuration.stem
    if isinstance(configuration, str):
        return Path(configuration).stem
    if isinstance(configuration, Mapping):
        return str(configuration.get("name", "assembly"))
    return "assembly"


def configuration_folders(
    out: Path | None, configurations: Sequence[ConfigurationLike]
) -> list[Path | None]:
    """``out/<name>`` per configuration (``out/<k>_<name>`` when names repeat)."""
    if out is None:
        return [None] * len(configurations)
    names = [configuration_name(c) for c in configurations]
    if len(set(names)) < len(names):
        names = [f"{k + 1}_{name}" for k, name in enumerate(names)]
    return [out / name for name in names]
