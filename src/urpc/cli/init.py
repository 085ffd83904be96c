"""``urpc init``: write a starting uncertainty box for any fixed-base arm."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from ..errors import InputError
from .common import (
    EXIT_OK,
    add_command,
    add_json_argument,
    add_new_file_arguments,
    add_robot_positional,
    count,
    names,
    non_negative_float,
    print_json,
)

DEFAULT_MASS = "10%"
DEFAULT_COM = 0.01
DEFAULT_INERTIA = "20%"


def _escaped(text: str) -> str:
    """``text`` for an argparse help string, where ``%`` starts a format."""
    return text.replace("%", "%%")


def register(commands) -> None:
    p = add_command(
        commands,
        "init",
        run_init,
        help="write a starting uncertainty box for a robot (every moving link, ready to edit)",
        description="Write an uncertainty file (docs/uncertainty-format.md) for ROBOT: every "
        "moving link with a mass gets its URDF mass +- MASS, center of mass +- COM and inertia "
        "entries +- INERTIA (narrowed per link where a wider box would hold non-physical "
        "inertias), each with a comment giving the URDF value and the interval. The file is "
        "accepted as is by 'urpc check', 'urpc simulate --robot ROBOT --uncertainty FILE' and "
        "scenario files; edit it to state what you know.",
        epilog="Example: urpc init ur10 --out box.yaml --payload tool0:3 && "
        "urpc simulate --robot ur10 --uncertainty box.yaml",
    )
    add_robot_positional(p)
    add_new_file_arguments(p)
    p.add_argument(
        "--mass",
        type=percentage,
        default=percentage(DEFAULT_MASS),
        metavar="PCT",
        help=f"relative half-width of every link mass, e.g. 10%% (default {_escaped(DEFAULT_MASS)})",
    )
    p.add_argument(
        "--com",
        type=non_negative_float,
        default=DEFAULT_COM,
        metavar="M",
        help=f"half-width of every center-of-mass coordinate [m] (default {DEFAULT_COM})",
    )
    p.add_argument(
        "--inertia",
        type=percentage,
        default=percentage(DEFAULT_INERTIA),
        metavar="PCT",
        help="relative half-width of every inertia entry about the center of mass, e.g. 20%% "
        f"(default {_escaped(DEFAULT_INERTIA)})",
    )
    p.add_argument(
        "--payload",
        type=payload,
        metavar="LINK:KG",
        help="add a payload of mass [0, KG] fixed to LINK, e.g. tool0:3",
    )
    p.add_argument(
        "--lock",
        type=names,
        default=[],
        metavar="JOINTS",
        help="comma-separated joints to lock (at 0), as given to check and simulate",
    )
    add_json_argument(p)


def percentage(text: str) -> float:
    """``"10%"`` -> 0.1 (argparse type): a relative half-width in [0 %, 100 %)."""
    number = text.strip().removeprefix("+-").removesuffix("%")
    if not text.strip().endswith("%"):
        raise argparse.ArgumentTypeError(f"'{text}' must be a percentage, e.g. 10%")
    try:
        value = float(number)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a percentage, e.g. 10%") from None
    if not (math.isfinite(value) and 0.0 <= value < 100.0):
        raise argparse.ArgumentTypeError(f"'{text}' must lie in [0%, 100%)")
    return value / 100.0


def payload(text: str) -> tuple[str, float]:
    """``"tool0:3"`` -> ``("tool0", 3.0)`` (argparse type): a link and a mass > 0 [kg]."""
    link, _, mass = text.rpartition(":")
    try:
        value = float(mass)
    except ValueError:
        value = math.nan
    if not link or not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(
            f"'{text}' must be LINK:KG with a mass > 0 [kg], e.g. tool0:3"
        )
    return link, value


def run_init(args) -> int:
    from ..model.box_template import BoxTemplateSettings, box_template, link_templates
    from ..model.catalog import uncertainty_schema
    from ..model.robot import load_robot
    from ..model.uncertainty import parse_uncertainty

    out = check_new_file(args.out, args.force, " such as box.yaml")
    robot = load_robot(args.robot, locked_joints=args.lock)
    link, mass = args.payload if args.payload is not None else (None, None)
    settings = BoxTemplateSettings(args.mass, args.com, args.inertia, link, mass)
    schema = uncertainty_schema()
    text = box_template(
        robot,
        settings,
        robot_source=str(args.robot),
        locked_joints=tuple(args.lock),
        schema=None if schema is None else _schema_reference(schema, out),
    )
    import yaml

    try:  # what check will read
        box = parse_uncertainty(yaml.safe_load(text), robot, source=str(out))
    except InputError as exc:  # the box the options give is refused: name them, write nothing
        raise InputError(
            f"the box that --mass, --com, --inertia and --payload give is refused ({exc.detail}); "
            f"{out} was not written",
            field=exc.field,
        ) from None
    write_new_file(out, text, overwrite=args.force)
    templates = link_templates(robot, settings)
    summary = {
        "out": str(out),
        "robot": robot.name,
        "urdf": str(robot.urdf_path),
        "links": [t.link for t in templates if t.inertia_relative is not None],
        "exact_links": {t.link: t.note for t in templates if t.inertia_relative is None},
        "narrowed_inertia": {
            t.link: t.inertia_relative
            for t in templates
            if t.inertia_relative is not None and t.inertia_relative < settings.inertia_relative
        },
        "payload": None if link is None else {"link": link, "mass": [0.0, mass]},
        "uncertain_parameters": box.n_uncertain,
    }
    if args.json:
        print_json(summary)
        return EXIT_OK
    print(
        f"wrote {out}: {count(box.n_uncertain, 'uncertain parameter')} in "
        f"{count(len(summary['links']), 'link')} of {robot.name}"
        + ("" if link is None else f" and a payload at {link}")
    )
    for name, width in summary["narrowed_inertia"].items():
        print(
            f"  {name}: inertia +-{100 * width:.3g} % (not {100 * args.inertia:.3g} %): "
            "a wider box holds non-physical inertias"
        )
    for name, note in summary["exact_links"].items():
        print(f"  {name}: left exact, {note}")
    lock = f" --lock {','.join(args.lock)}" if args.lock else ""
    print(f"next: urpc check {args.robot}{lock} --uncertainty {out}")
    print(f"      urpc simulate --robot {args.robot}{lock} --uncertainty {out}")
    return EXIT_OK


def check_new_file(path: Path, overwrite: bool, example: str = "") -> Path:
    """``path``, checked before any work as the file a command writes: not an existing file
    (unless ``overwrite``), not a folder (``example``: a file name to suggest instead).

    Raises:
        InputError: naming the file.
    """
    if path.exists() and not overwrite:
        raise InputError("the file exists; give --force to overwrite it", source=path)
    if path.is_dir():
        raise InputError(f"is a folder; give a file name{example}", source=path)
    return path


def write_new_file(path: Path, text: str, overwrite: bool = False) -> None:
    """Write ``text`` to ``path`` atomically (a temporary file in the same folder, then a
    rename), refusing an existing ``path`` unless ``overwrite``.

    Raises:
        InputError: the file exists (without ``overwrite``), or cannot be written.
    """
    import tempfile

    folder = path.parent if str(path.parent) else Path(".")
    try:
        descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=folder)
    except OSError as exc:
        raise InputError(f"cannot write into {folder} ({exc.strerror})", source=path) from None
    try:
        with os.fdopen(descriptor, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.chmod(temporary, 0o666 & ~_umask())
        if overwrite:
            os.replace(temporary, path)
        else:
            _link_new(temporary, path)
    except FileExistsError:
        raise InputError("the file exists; give --force to overwrite it", source=path) from None
    except OSError as exc:
        raise InputError(f"cannot write the file ({exc.strerror})", source=path) from None
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)


def _link_new(temporary: str, path: Path) -> None:
    """Give ``temporary`` the name ``path`` unless ``path`` exists (FileExistsError)."""
    try:
        os.link(temporary, path)  # atomic and never clobbers
    except FileExistsError:
        raise
    except OSError:  # a file system without hard links
        if path.exists():
            raise FileExistsError(path) from None
        os.replace(temporary, path)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _schema_reference(schema: Path, out: Path) -> str:
    """How the file at ``out`` names ``schema`` (``<tree>/docs/schemas/...``): a relative path when
    ``out`` lies in the same source tree (as the shipped files do), else a file URI."""
    folder = out.resolve().parent
    if folder.is_relative_to(schema.parents[2]):
        return Path(os.path.relpath(schema, folder)).as_posix()
    return schema.as_uri()
