"""Where robots and their shipped data come from: built-in descriptions, example-robot-data URDFs.

A robot *source* is either a path to a URDF file, the name of a built-in robot (a folder of
``robots/`` holding ``<name>.urdf``), or the name of a URDF shipped by example-robot-data (its file
stem, e.g. ``panda`` or ``ur5_robot``; ``ur5``, ``ur3`` and ``ur10`` are accepted as short names).
Floating-base robots of example-robot-data (legged robots, humanoids, aerial and mobile robots) are
known by name only to be refused: urpc controls fixed-base arms.

Shipped data live in ``robots/<name>/`` for a robot known by name (also for example-robot-data
arms such as ``ur5`` and ``panda``): ``uncertainty.yaml`` (its box), ``true_parameters.yaml`` (a
true plant), other parameter points and ``scenarios/*.yaml``. :func:`shipped_file` finds them by
name, so that ``load_uncertainty("rr_planar", robot)`` works from any folder.
"""

from __future__ import annotations

import functools
import importlib.metadata
import importlib.resources
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, did_you_mean, no_file

#: Short names for example-robot-data URDFs whose file stem is not the usual name.
ALIASES = {"ur5": "ur5_robot", "ur3": "ur3_robot", "ur10": "ur10_robot"}

_ERD_ROBOTS = "cmeel.prefix/share/example-robot-data/robots"

#: example-robot-data description folders of floating-base robots (legged robots, humanoids,
#: aerial robots, mobile bases: example-robot-data's own loaders give them a free-flyer root).
#: urpc controls fixed-base arms, so these are listed as not supported and refused by name.
FLOATING_BASE_FOLDERS = frozenset(
    {
        "a1_description",
        "alex_description",
        "alexander_description",
        "anymal_b_simple_description",
        "anymal_c_simple_description",
        "b1_description",
        "bolt_description",
        "borinot_description",
        "centauro_description",
        "g1_description",
        "go1_description",
        "go2_description",
        "hector_description",
        "hextilt_description",
        "human_description",
        "hyq_description",
        "icub_description",
        "iris_description",
        "laikago_description",
        "pr2_description",
        "quadruped_description",
        "romeo_description",
        "simple_humanoid_description",
        "solo_description",
        "talos_data",
        "tiago_description",
        "tiago_pro_description",
    }
)
#: URDFs inside those folders that describe a fixed-base part (a single arm).
FIXED_BASE_EXCEPTIONS = frozenset({"talos_left_arm"})


@dataclass(frozen=True)
class RobotEntry:
    """One robot that ``load_robot`` can find by name."""

    name: str
    urdf: Path
    origin: str  # "built-in", "example-robot-data" or "file"
    files: tuple[Path, ...] = ()  # the other files shipped next to a built-in robot
    floating_base: bool = False  # a legged, humanoid, aerial or mobile robot: not supported


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
            folder = Path(text[len(_ERD_ROBOTS) :].lstrip("/")).parts[0]
            floating = folder in FLOATING_BASE_FOLDERS and path.stem not in FIXED_BASE_EXCEPTIONS
            robots.setdefault(
                path.stem, RobotEntry(path.stem, path, "example-robot-data", (), floating)
            )
    for alias, stem in ALIASES.items():
        if stem in robots:
            robots[alias] = RobotEntry(alias, robots[stem].urdf, "example-robot-data")
    return dict(sorted(robots.items()))


#: The file name of a robot's default box; other boxes are ``uncertainty_<what>.yaml``.
BOX = "uncertainty.yaml"


def shipped_data(name: str) -> dict[str, list[Path]]:
    """What ``robots/<name>/`` ships for a robot known by name: ``"uncertainty"`` (the boxes,
    ``uncertainty.yaml`` first, then ``uncertainty_<what>.yaml``),
    ``"parameter_points"`` (true plants, ``true_parameters.yaml`` first) and ``"scenarios"``.
    Empty lists for a robot that ships nothing (or for a name that is not a folder)."""
    folder = builtin_root() / name
    if not folder.is_dir():
        return {"uncertainty": [], "parameter_points": [], "scenarios": []}
    boxes = sorted(folder.glob("uncertainty*.yaml"), key=lambda p: (p.name != BOX, p.name))
    points = sorted(
        (p for p in folder.glob("*.yaml") if not p.name.startswith("uncertainty")),
        key=lambda p: (p.name != "true_parameters.yaml", p.name),
    )
    return {
        "uncertainty": boxes,
        "parameter_points": points,
        "scenarios": sorted(folder.glob("scenarios/*.yaml")),
    }


def shipped_file(source: str | Path, default: str, what: str = "file") -> Path:
    """The file behind ``source``: a path as is, or a shipped file found by name.

    ``source`` may be a path (returned unchanged when it exists or looks like a YAML path), a
    robot name (``"rr_planar"`` -> ``robots/rr_planar/<default>``) or a robot name and a file stem
    (``"ur5/heavy_payload"`` -> ``robots/ur5/heavy_payload.yaml``).

    Args:
        source: Path or shipped name.
        default: File of ``robots/<name>/`` meant by a bare robot name (``"uncertainty.yaml"``).
        what: What the file is, for the error message (``"uncertainty box"``).

    Raises:
        InputError: a robot name that ships no such file (the message says how to write one,
            or lists what the robot ships); a name that is neither a file nor a known robot.
    """
    path = Path(source).expanduser()
    text = path.as_posix()
    if path.exists() or path.suffix.lower() in (".yaml", ".yml", ".json"):
        return path
    parts = text.split("/")
    if len(parts) > 2 or not all(parts):
        return path  # a path that does not exist: the loader reports it
    robot = parts[0]
    stem = default.removesuffix(".yaml") if len(parts) == 1 else parts[1]
    candidate = builtin_root() / robot / f"{stem}.yaml"
    if candidate.is_file():
        return candidate
    known = {*builtin_robots(), *example_robot_data_robots()}
    if robot not in known:
        shipped = sorted(n for n in known if any(shipped_data(n).values()))
        raise InputError(
            f"no such file, and '{robot}' is not a robot known by name; give a path or the "
            f"name of a robot that ships its {what}: " + did_you_mean(robot, shipped),
            source=text,
        )
    files = [p.stem for p in shipped_data(robot)["parameter_points"]]
    if stem == "uncertainty":
        hint = f"write one with 'urpc init {robot} --out box.yaml' and give its path"
    elif files:
        hint = f"it ships: {', '.join(f'{robot}/{f}' for f in files)}"
    else:
        hint = "give a file path"
    raise InputError(f"robot '{robot}' ships no {what} '{stem}.yaml'; {hint}", source=text)


def uncertainty_schema() -> Path | None:
    """The JSON Schema of uncertainty files, for editors: ``docs/schemas/uncertainty.schema.json``,
    installed with the package as ``urpc._schemas`` (``None`` if it is missing)."""
    try:
        path = Path(str(importlib.resources.files("urpc._schemas"))) / "uncertainty.schema.json"
    except ModuleNotFoundError:
        return None
    return path if path.is_file() else None


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
            raise InputError(no_file(path, f"robot file '{text}'"), field="robot")
        return RobotEntry(path.stem, path.resolve(), "file")
    builtin = builtin_robots()
    if text in builtin:
        return builtin[text]
    erd = example_robot_data_robots()
    if text in erd and erd[text].floating_base:
        raise InputError(
            f"'{text}' is a floating-base robot (legged, humanoid, aerial or mobile), which urpc "
            "does not support: it controls fixed-base arms ('urpc robots' lists them); to study "
            f"its joints as a fixed-base tree anyway, give the URDF path {erd[text].urdf}",
            field="robot",
        )
    if text in erd:
        return erd[text]
    supported = [n for n, e in erd.items() if not e.floating_base]
    raise InputError(
        f"unknown robot '{text}': give a URDF path or a known name; "
        + did_you_mean(text, [*builtin, *supported]),
        field="robot",
    )
