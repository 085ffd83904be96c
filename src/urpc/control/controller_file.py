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


def save_controller(controller, path: str | Path) -> Path:
    """Write ``controller`` (an :class:`~urpc.control.interval.IntervalPassivityController`) to
    ``path`` (JSON), atomically.

    Raises:
        InputError: a controller whose box was not read from a file (nothing to rebuild it from)
            or that is not an interval controller.
    """
    from .interval import IntervalPassivityController

    if not isinstance(controller, IntervalPassivityController):
        raise InputError(
            f"only interval controllers can be saved, not {type(controller).__name__}",
            field="controller",
        )
    box = controller.bound.box
    if box.source is None or not Path(box.source).is_file():
        raise InputError(
            "the controller's box was not read from a file (load_uncertainty); build it from one "
            "to save the controller",
            field="box",
        )
    robot = controller.robot
    import yaml

    document = yaml.safe_load(Path(box.source).read_text())
    payload: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "robot": {
            "name": robot.name,
            "urdf": str(Path(robot.urdf_path).resolve()),
            "urdf_sha256": _sha256(robot.urdf_path),
            "locked_joints": dict(robot.locked_joints),
        },
        "box": {"source": str(Path(box.source).resolve()), "document": document},
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
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, staging = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(handle, "w") as stream:
            stream.write(text + "\n")
        os.replace(staging, path)
    except BaseException:
        Path(staging).unlink(missing_ok=True)
        raise
    return path


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

    path = Path(path)
    if not path.is_file():
        raise InputError(no_file(path, "controller file"), path)
    try:
        payload = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"not a JSON controller file ({exc})", path) from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise InputError(f"not a urpc controller file (format is not '{FORMAT}')", path, "format")
    if payload.get("version") != VERSION:
        raise InputError(
            f"version {payload.get('version')!r}; this urpc reads version {VERSION}",
            path,
            "version",
        )
    try:
        robot_entry, box_entry, law, check = (payload[k] for k in ("robot", "box", "law", "check"))
        name, urdf = robot_entry["name"], Path(robot_entry["urdf"])
        locked = robot_entry.get("locked_joints") or {}
    except (KeyError, TypeError) as exc:
        raise InputError(f"missing entry {exc}", path) from None
    source: str | Path = urdf
    try:
        if resolve_robot(name).urdf.resolve() == urdf.resolve() or not urdf.is_file():
            source = name
    except InputError:
        pass
    if not Path(resolve_robot(source).urdf).is_file():
        raise InputError(f"the robot's URDF {urdf} does not exist", path, "robot.urdf")
    digest = _sha256(resolve_robot(source).urdf)
    if digest != robot_entry.get("urdf_sha256"):
        raise InputError(
            f"the URDF {resolve_robot(source).urdf} changed since the controller was saved "
            "(SHA-256 differs); synthesize and save it again",
            path,
            "robot.urdf_sha256",
        )
    positions = {k: v for k, v in locked.items() if v is not None}
    base = load_robot(source, positions if len(positions) == len(locked) else list(locked))
    box = parse_uncertainty(box_entry["document"], base, source=box_entry.get("source"))
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
    except KeyError as exc:
        raise InputError(f"missing law entry {exc}", path, "law") from None
    nominal = np.asarray(controller.robot.nominal_parameters, dtype=float)
    if not np.array_equal(
        nominal, np.asarray(check["nominal_parameters"], dtype=float)
    ) or not np.array_equal(
        np.asarray(controller.robot.joint_parameters, dtype=float),
        np.asarray(check["joint_parameters"], dtype=float),
    ):
        raise InputError(
            "the robot and box rebuilt from this file do not give the saved controller's model "
            "(nominal parameters differ); synthesize and save it again",
            path,
            "check",
        )
    return controller


def _sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
