"""Where robots come from: built-in descriptions and example-robot-data URDFs.

A robot *source* is either a path to a URDF file, the name of a built-in robot (a folder of
``robots/`` holding ``<name>.urdf``), or the name of a URDF shipped by example-robot-data (its file
stem, e.g. ``panda`` or ``ur5_robot``; ``ur5``, ``ur3`` and ``ur10`` are accepted as short names).
"""

from __future__ import annotations

import functools
import importlib.metadata
import importlib.resources
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, did_you_mean

#: Short names for example-robot-data URDFs whose file stem is not the usual name.
ALIASES = {"ur5": "ur5_robot", "ur3": "ur3_robot", "ur10": "ur10_robot"}

_ERD_ROBOTS = "cmeel.prefix/share/example-robot-data/robots"


@dataclass(frozen=True)
class RobotEntry:
    """One robot that ``load_robot`` can find by name."""

    name: str
    urdf: Path
    origin: str  # "built-in" or "example-robot-data"
    files: tuple[Path, ...] = ()  # the other files shipped next to a built-in robot


def builtin_root() -> Path:
    """The folder holding the built-in robots (``robots/`` of the source tree)."""
    return Path(str(importlib.resources.files("urpc._robots")))


@functools.cache
def builtin_robots() -> dict[str, RobotEntry]:
    """Built-in robots: each folder of ``robots/`` with a ``<folder>.urdf`` inside."""
    robots = {}
    for folder in sorted(builtin_root().iterdir()):
        urdf = folder / f"{folder.name}.urdf"
        if folder.is_dir() and urdf.is_file():
            others = tuple(sorted(p for p in folder.iterdir() if p.suffix == ".yaml"))
            robots[folder.name] = RobotEntry(folder.name, urdf, "built-in", others)
    return robots


@functools.cache
def example_robot_data_robots() -> dict[str, RobotEntry]:
    """URDFs shipped by the installed example-robot-data distribution, by file stem.

    The files are found from the distribution's own file list (example-robot-data 6.x installs
    them under ``cmeel.prefix/share/example-robot-data/robots``), never from a hard-coded path.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return {}
    robots = {}
    for file in dist.files or ():
        text = str(file)
        if text.startswith(_ERD_ROBOTS) and text.endswith(".urdf"):
            path = Path(str(dist.locate_file(file)))
            robots.setdefault(path.stem, RobotEntry(path.stem, path, "example-robot-data"))
    for alias, stem in ALIASES.items():
        if stem in robots:
            robots[alias] = RobotEntry(alias, robots[stem].urdf, "example-robot-data")
    return dict(sorted(robots.items()))


def default_uncertainty(source: str | Path) -> Path | None:
    """The uncertainty file shipped for a robot known by name (``robots/<name>/uncertainty.yaml``,
    also for example-robot-data arms such as ``ur5`` and ``panda``), or ``None``."""
    text = str(source)
    if "/" in text or text.endswith((".urdf", ".xml")):
        return None
    path = builtin_root() / text / "uncertainty.yaml"
    return path if path.is_file() else None


def resolve_robot(source: str | Path) -> RobotEntry:
    """Find the URDF behind a robot source (a path or a known name).

    Raises:
        InputError: the path does not exist or the name is unknown (the message lists names).
    """
    text = str(source)
    path = Path(text).expanduser()
    if path.suffix.lower() in (".urdf", ".xml") or path.exists() or "/" in text:
        if not path.is_file():
            raise InputError(f"robot file '{text}' does not exist", field="robot")
        return RobotEntry(path.stem, path.resolve(), "file")
    builtin = builtin_robots()
    if text in builtin:
        return builtin[text]
    erd = example_robot_data_robots()
    if text in erd:
        return erd[text]
    raise InputError(
        f"unknown robot '{text}': give a URDF path or a known name; "
        + did_you_mean(text, [*builtin, *erd]),
        field="robot",
    )
