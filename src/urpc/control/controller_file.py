"""A synthesized interval controller in a file: ``controller.save(path)``,
``urpc.load_controller(path)``.

The format is one JSON document (no pickle), version :data:`VERSION`::

    {"format": "urpc-controller", "version": 1,
     "robot": {"name": "ur5", "urdf": "/abs/path/ur5.urdf", "urdf_sha256": "...",
               "locked_joints": {"joint": 0.0 | null}},
     "box": {"source": "/abs/path/uncertainty.yaml", "document": {...the box file, parsed...}},
     "law": {"epsilon": 0.01, "method": "vertex", "kappa_P": 2, "kappa_I": 1, "phi_P": 1,
             "phi_I": 1e6, "Kr": [...], "sample_period": 0.001, "sampled_law": "implicit",
             "delay": 0},
     "check": {"nominal_parameters": [...], "joint_parameters": [...]}}

Loading rebuilds the robot (by its shipped name when the name resolves to the same URDF,
else by the URDF path), parses the embedded box and synthesizes again with the saved gains:
synthesis is deterministic, so the loaded controller's torque equals the original's bit for bit
(``tests/test_robot_controller_file.py``). Floats are written with ``repr`` precision (JSON's
shortest round trip), so every number comes back exact. The URDF's SHA-256 and the controller
model's nominal parameters are checked: a URDF or box changed since the controller was saved is
refused, not silently used.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, no_file

FORMAT = "urpc-controller"
VERSION = 1


def save_controller(
    controller, path: str | Path, *, overwrite: bool = True, label: str | None = None
) -> Path:
    """Write ``controller`` (an :class:`~urpc.control.interval.IntervalPassivityController`) to
    ``path`` (JSON), atomically; missing folders are created. ``overwrite=False`` refuses an
    existing file; ``label`` names the path in errors (``"--save-controller arm.json"``).

    Raises:
        InputError: a controller whose box was not read from a file (nothing to rebuild it from),
            that is not an interval controller or that is continuous-time (a robot runs
            sampled); a path that is a folder, lies under a file, or exists (``overwrite=False``).
    """
    check_controller_path(path, overwrite=overwrite, create_folders=True, label=label)
    from .interval import IntervalPassivityController

    if not isinstance(controller, IntervalPassivityController):
        raise InputError(
            f"only interval controllers can be saved, not {type(controller).__name__}",
            field="controller",
        )
    box = controller.bound.box
    if box.document is None and (box.source is None or not Path(box.source).is_file()):
        raise InputError(
            "the controller's box was not read from a file or a document (load_uncertainty, "
            "parse_uncertainty); build it from one to save the controller",
            field="box",
        )
    if controller.sample_period is None:
        raise InputError(
            "a continuous-time controller cannot run on a robot (docs/robot.md): synthesize it "
            "with a sample_period (urpc.synthesize(..., sample_period=1e-3)) and save that",
            field="sample_period",
        )
    robot = controller.robot
    import yaml

    # The document the box was parsed from (a loaded controller's embedded copy included);
    # a box without one (built otherwise) is read back from its file.
    document = (
        box.document if box.document is not None else yaml.safe_load(Path(box.source).read_text())
    )
    payload: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "robot": {
            "name": robot.name,
            "urdf": str(Path(robot.urdf_path).resolve()),
            "urdf_sha256": _sha256(robot.urdf_path),
            "locked_joints": dict(robot.locked_joints),
        },
        "box": {
            "source": None if box.source is None else str(Path(box.source).resolve()),
            "document": document,
        },
        "law": {
            "epsilon": controller.epsilon,
            "method": controller.method,
            "kappa_P": controller.kappa_P,
            "kappa_I": controller.kappa_I,
            "phi_P": controller.phi_P,
            "phi_I": controller.phi_I,
            "Kr": controller.Kr.tolist(),
            "sample_period": controller.sample_period,
            "sampled_law": controller.sampled_law,
            "delay": int(controller.delay),
        },
        "check": {
            "nominal_parameters": np.asarray(robot.nominal_parameters, dtype=float).tolist(),
            "joint_parameters": np.asarray(robot.joint_parameters, dtype=float).tolist(),
        },
    }
    path = Path(path)
    text = json.dumps(payload, indent=1, allow_nan=False)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, staging = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    except OSError as exc:
        raise InputError(f"cannot write the file ({exc.strerror})", label or path) from None
    try:
        with os.fdopen(handle, "w") as stream:
            stream.write(text + "\n")
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(staging, 0o666 & ~mask)
        if overwrite:
            os.replace(staging, path)
        else:
            _link_new(staging, path)
    except FileExistsError:
        raise InputError("the file exists; give --force to overwrite it", label or path) from None
    except OSError as exc:
        raise InputError(f"cannot write the file ({exc.strerror})", label or path) from None
    finally:
        Path(staging).unlink(missing_ok=True)
    return path


def _link_new(staging: str, path: Path) -> None:
    """Give ``staging`` the name ``path`` unless ``path`` exists (FileExistsError)."""
    try:
        os.link(staging, path)  # atomic, and never replaces a file written meanwhile
    except FileExistsError:
        raise
    except OSError:  # a file system without hard links
        if path.exists():
            raise FileExistsError(path) from None
        os.replace(staging, path)


def check_controller_path(
    path: str | Path,
    *,
    overwrite: bool = True,
    create_folders: bool = False,
    label: str | None = None,
) -> Path:
    """``path``, checked before any work as the file a controller is saved to: not a folder,
    not under a file, not an existing file unless ``overwrite``, in an existing folder unless
    ``create_folders``. ``label`` names it in the error (default: the path).

    Raises:
        InputError: what is in the way, and what to give instead.
    """
    _check_path_type(path)
    path = Path(path).expanduser()
    where = label or str(path)
    if path.is_dir():
        raise InputError("is a folder; give a file name such as arm.json", where)
    if path.exists() and not overwrite:
        raise InputError("the file exists; give --force to overwrite it", where)
    folder = path.absolute().parent
    while not folder.exists():
        if not create_folders:
            raise InputError(
                f"the folder {path.absolute().parent} does not exist; create it first", where
            )
        folder = folder.parent
    if not folder.is_dir():
        raise InputError(f"{folder} is a file, not a folder; give a path in a folder", where)
    return path


def _check_path_type(path) -> None:
    if not isinstance(path, str | Path) or not str(path):
        raise InputError(
            f"expected the controller file's path (a str or Path such as 'arm.json'), got "
            f"{path!r:.60}",
            field="path",
        )


def load_controller(path: str | Path):
    """The controller saved in ``path`` by :func:`save_controller`, synthesized again.

    Raises:
        InputError: a missing or malformed file, another format or version, a URDF that is
            missing or changed, a box that no longer gives the saved model.
    """
    from ..model.catalog import resolve_robot
    from ..model.robot import load_robot
    from ..model.uncertainty import parse_uncertainty
    from .synthesis import synthesize

    _check_path_type(path)
    path = Path(path)
    if not path.is_file():
        raise InputError(no_file(path, "controller file"), path)
    try:
        payload, repeated = _parsed(path.read_text())
    except (OSError, ValueError, RecursionError) as exc:  # RecursionError: nested too deep
        raise InputError(f"not a JSON controller file ({exc})", path) from None
    if repeated is not None:
        raise InputError(
            "appears more than once in its object; JSON would keep the last one without a word, "
            "so remove the others (or save the controller again)",
            path,
            repeated,
        )
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise InputError(f"not a urpc controller file (format is not '{FORMAT}')", path, "format")
    version = payload.get("version")
    if type(version) is not int or version != VERSION:  # not True, not 1.0: the integer 1
        raise InputError(
            f"version {_shown(version)}; this urpc reads version {VERSION} (the integer {VERSION})",
            path,
            "version",
        )
    robot_entry, box_entry, law, check = _checked(payload, path)
    name, urdf = robot_entry["name"], Path(robot_entry["urdf"])
    locked = robot_entry.get("locked_joints") or {}
    if law["sample_period"] is None:
        raise InputError(
            "null: the controller is continuous-time and a robot runs sampled; synthesize it "
            "with a sample_period (urpc.synthesize(..., sample_period=1e-3)) and save it again",
            path,
            "law.sample_period",
        )
    try:
        shipped = resolve_robot(name).urdf.resolve()
    except InputError:
        shipped = None
    if shipped is not None and (shipped == urdf.resolve() or not urdf.is_file()):
        source: str | Path = name
    elif urdf.is_file():
        source = urdf
    else:
        raise InputError(
            f"the robot's URDF {urdf} does not exist and '{name}' is not a shipped robot",
            path,
            "robot.urdf",
        )
    try:
        urdf_file = Path(resolve_robot(source).urdf)
    except InputError as exc:
        raise InputError(exc.detail, path, "robot.urdf") from None
    digest = _sha256(urdf_file)
    if digest != robot_entry["urdf_sha256"]:
        raise InputError(
            f"the URDF {urdf_file} changed since the controller was saved "
            "(SHA-256 differs); synthesize and save it again",
            path,
            "robot.urdf_sha256",
        )
    positions = {k: v for k, v in locked.items() if v is not None}
    try:
        base = load_robot(source, positions if len(positions) == len(locked) else list(locked))
    except InputError as exc:
        raise InputError(exc.detail, path, _inner("robot", exc.field)) from None
    try:
        box = parse_uncertainty(box_entry["document"], base, source=box_entry.get("source"))
    except InputError as exc:
        raise InputError(
            exc.detail + _embedded(box_entry.get("source")),
            path,
            _inner("box.document", exc.field),
        ) from None
    try:
        controller = synthesize(
            base,
            box,
            law["epsilon"],
            method=law["method"],
            kappa_P=law["kappa_P"],
            kappa_I=law["kappa_I"],
            phi_P=law["phi_P"],
            phi_I=law["phi_I"],
            Kr=np.asarray(law["Kr"], dtype=float),
            sample_period=law["sample_period"],
            sampled_law=law["sampled_law"],
            delay=law.get("delay", 0),
        )
    except InputError as exc:
        raise InputError(exc.detail, path, _inner("law", exc.field)) from None
    if not _same(controller.robot.nominal_parameters, check["nominal_parameters"]) or not _same(
        controller.robot.joint_parameters, check["joint_parameters"]
    ):
        raise InputError(
            "the robot and box rebuilt from this file do not give the saved controller's model "
            "(nominal parameters differ); synthesize and save it again",
            path,
            "check",
        )
    return controller


def _parsed(text: str) -> tuple[Any, str | None]:
    """The JSON document in ``text`` and the dotted path (``law.Kr``) of a key that appears more
    than once in one of its objects (``json.loads`` keeps the last value without a word), or
    ``None``."""
    repeated: list[tuple[dict, str]] = []

    def build(pairs):
        obj = dict(pairs)
        if len(obj) != len(pairs):
            seen: set[str] = set()
            key = next(k for k, _ in pairs if k in seen or seen.add(k))
            repeated.append((obj, key))
        return obj

    payload = json.loads(text, object_pairs_hook=build)
    if not repeated:
        return payload, None
    target, key = repeated[0]
    stack: list[tuple[Any, str]] = [(payload, "")]
    while stack:  # where that object sits (iterative: a document may nest deeply)
        value, prefix = stack.pop()
        if value is target:
            return payload, _inner(prefix, key) if prefix else key
        if isinstance(value, dict):
            items = value.items()
        elif isinstance(value, list):
            items = ((str(i), item) for i, item in enumerate(value))
        else:
            continue
        stack.extend((item, _inner(prefix, k) if prefix else k) for k, item in items)
    return payload, key


def _inner(prefix: str, field: str | None) -> str:
    """``prefix.field`` (or ``prefix`` alone): a field of an embedded entry, as a path in the
    controller file."""
    return f"{prefix}.{field}" if field else prefix


def _embedded(source: Any) -> str:
    return f" (in the embedded copy of {source})" if source else ""


# Each entry of a controller file: (field, what it must be, test, required).
_NUMBER = "a number"


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_numbers(value: Any) -> bool:
    return isinstance(value, list) and all(_is_number(v) for v in value)


_ENTRIES: dict[str, list[tuple[str, str, Any, bool]]] = {
    "robot": [
        ("name", "a text (the robot's name)", lambda v: isinstance(v, str), True),
        ("urdf", "a text (the URDF's path)", lambda v: isinstance(v, str), True),
        ("urdf_sha256", "a text (the URDF's SHA-256)", lambda v: isinstance(v, str), True),
        (
            "locked_joints",
            'an object mapping joint names to positions or null ({"joint1": 0.0})',
            lambda v: (
                v is None
                or (isinstance(v, dict) and all(x is None or _is_number(x) for x in v.values()))
            ),
            False,
        ),
    ],
    "box": [
        (
            "source",
            "a text (the box file's path) or null",
            lambda v: v is None or isinstance(v, str),
            False,
        ),
        (
            "document",
            "an object (the parsed uncertainty file)",
            lambda v: isinstance(v, dict),
            True,
        ),
    ],
    "law": [
        ("epsilon", _NUMBER, _is_number, True),
        ("method", "a text (a bound method name)", lambda v: isinstance(v, str), True),
        ("kappa_P", _NUMBER, _is_number, True),
        ("kappa_I", _NUMBER, _is_number, True),
        ("phi_P", _NUMBER, _is_number, True),
        ("phi_I", _NUMBER, _is_number, True),
        ("Kr", "a number or list of numbers", lambda v: _is_number(v) or _is_numbers(v), True),
        ("sample_period", "a number [s]", lambda v: v is None or _is_number(v), True),
        ("sampled_law", "a text (implicit or paper)", lambda v: isinstance(v, str), True),
        (
            "delay",
            "0 or 1",
            lambda v: isinstance(v, int) and not isinstance(v, bool),
            False,
        ),
    ],
    "check": [
        ("nominal_parameters", "a list of numbers", _is_numbers, True),
        (
            "joint_parameters",
            "a list of lists of numbers",
            lambda v: isinstance(v, list) and all(_is_numbers(row) for row in v),
            True,
        ),
    ],
}


def _checked(payload: dict, path: Path) -> tuple[dict, dict, dict, dict]:
    """The ``robot``, ``box``, ``law`` and ``check`` entries of ``payload``, each checked for its
    structure (the type of every entry) before any is used.

    Raises:
        InputError: naming the file, the field's path and what it must be.
    """
    entries = []
    for section, fields in _ENTRIES.items():
        names = ", ".join(f for f, *_ in fields)
        if section not in payload:
            raise InputError(f"missing; expected an object with {names}", path, section)
        entry = payload[section]
        if not isinstance(entry, dict):
            raise InputError(
                f"{_shown(entry)} is not an object (expected one with {names})", path, section
            )
        for field, what, valid, required in fields:
            if field not in entry:
                if required:
                    raise InputError(f"missing; expected {what}", path, f"{section}.{field}")
                continue
            if not valid(entry[field]):
                raise InputError(
                    f"{_shown(entry[field])} is not {what}", path, f"{section}.{field}"
                )
        entries.append(entry)
    return tuple(entries)  # type: ignore[return-value]


def _shown(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, str) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _same(values, saved: list) -> bool:
    """Whether the saved list (of lists) of numbers equals ``values`` exactly; a ragged list
    never does."""
    try:
        return np.array_equal(np.asarray(values, dtype=float), np.asarray(saved, dtype=float))
    except ValueError:
        return False


def _sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
