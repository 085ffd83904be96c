"""The key of a certificate: a sha256 of everything :func:`urpc.control.certificate.certify`
reads, so that two configurations share a key only if their certificates are the same.

The key hashes one canonical document of:

* **the code**: :data:`~urpc.control.certificate.CERTIFICATE_VERSION`, urpc's version, a digest
  of urpc's own source files (an edited checkout never reuses a certificate of older code), and
  the versions of Pinocchio, NumPy and SciPy;
* **the robot** the controller was synthesized for: its Pinocchio model in Pinocchio's own text
  serialization (every joint and its axis, placement, inertia, limit, armature, damping and
  friction, at 17 significant digits), its per-link inertial data, locked joints and URDF
  dynamics;
* **the box**: every link interval (kind, nominal, lower, upper), the payloads, the joint-drive
  box and the disturbance bound (its values, not the file they were read from);
* **the controller**: its class, law, sample period, ``epsilon``, every gain (``Kr``,
  ``kappa_P``, ``kappa_I``, ``phi_P``, ``phi_I``, the ceiling ``phi_max``), the bound method, and
  the inertia bounds of the implicit law (their two model copies, scale and eigenvalue ceiling);
* **the reference**: its class and :meth:`~urpc.trajectories.Trajectory.fingerprint`;
* the **duration**, the **disturbance bound**, the number of **cells** asked for, the
  plant's **actuation delay** (resolved: ``None`` counts as the law's own delay) and, when
  asked for, **require_efforts** (absent from the default verdict's document).

Floats enter by their exact bits (``float.hex``), arrays by dtype, shape and a sha256 of their
bytes. A reference whose class gives no fingerprint (the base class's ``None``, or one inherited
from above an overridden :meth:`~urpc.trajectories.Trajectory.evaluate` or
:meth:`~urpc.trajectories.Trajectory.jerk_bound`) has no key: :class:`NoKey` says why, and its
certificate is computed every time.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..trajectories import READ_METHODS, Trajectory, defining_class

#: The methods of a reference the certificate reads: its fingerprint must be defined at or below
#: the class that defines each of them.
_READ = READ_METHODS + ("period",)


class NoKey(Exception):
    """A configuration that has no key (a reference without a fingerprint); the message says
    why."""


def certificate_key(
    controller,
    trajectory: Trajectory,
    *,
    duration: float,
    disturbance_bound: float | None = None,
    cells: int | None = None,
    actuation_delay: int | None = None,
    require_efforts: bool = False,
) -> str:
    """The sha256 (64 hex digits) of everything ``certify(controller, trajectory, duration=...,
    disturbance_bound=..., cells=..., actuation_delay=..., require_efforts=...)`` depends on
    (module docstring).

    Raises:
        NoKey: the reference gives no fingerprint.
    """
    document = key_document(
        controller, trajectory, duration, disturbance_bound, cells, actuation_delay
    )
    if require_efforts:  # absent otherwise: the keys of the default verdict stay as they were
        document["require_efforts"] = True
    text = json.dumps(document, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def key_document(
    controller,
    trajectory: Trajectory,
    duration: float,
    disturbance_bound: float | None,
    cells: int | None,
    actuation_delay: int | None,
) -> dict[str, Any]:
    """The canonical document :func:`certificate_key` hashes (JSON data, module docstring), of
    the arguments of :func:`certificate_key` (all given: the defaults are its own).

    Raises:
        NoKey: the reference gives no fingerprint.
    """
    from .. import __version__
    from .base import actuation_delay_of
    from .certificate import CERTIFICATE_VERSION

    bound = controller.bound
    inertia = controller.inertia_bounds
    return {
        "code": {
            "certificate_version": CERTIFICATE_VERSION,
            "urpc": __version__,
            "source": source_digest(),
            **library_versions(),
        },
        "robot": robot_fingerprint(controller.robot),
        "box": canonical(dataclasses.replace(bound.box, source=None)),
        "bound": {
            "class": _class_name(bound),
            "method": bound.name,
            "disturbance_bound": canonical(bound.disturbance_bound),
            "joints": canonical(bound.joints),
        },
        "controller": {
            "class": _class_name(controller),
            "delay": int(controller.delay),
            "epsilon": canonical(controller.epsilon),
            "kappa_P": canonical(controller.kappa_P),
            "kappa_I": canonical(controller.kappa_I),
            "phi_P": canonical(controller.phi_P),
            "phi_I": canonical(controller.phi_I),
            "phi_max": canonical(controller.phi_max),
            "Kr": canonical(np.asarray(controller.Kr, dtype=float)),
            "adaptive": bool(controller.adaptive),
            "sample_period": canonical(controller.sample_period),
            "sampled_law": controller.sampled_law,
        },
        "inertia_bounds": None
        if inertia is None
        else {
            "scale": canonical(inertia.scale),
            "max_upper_eigenvalue": canonical(inertia.max_upper_eigenvalue),
            "lower": robot_fingerprint(inertia.lower_robot),
            "upper": robot_fingerprint(inertia.upper_robot),
        },
        "trajectory": trajectory_fingerprint(trajectory),
        "duration": canonical(float(duration)),
        "disturbance_bound": None
        if disturbance_bound is None
        else canonical(float(disturbance_bound)),
        "cells": None if cells is None else int(cells),
        "actuation_delay": actuation_delay_of(controller, actuation_delay),
    }


def trajectory_fingerprint(trajectory: Trajectory) -> dict[str, Any]:
    """The class of ``trajectory``, its ``dof`` and its canonical
    :meth:`~urpc.trajectories.Trajectory.fingerprint`.

    Raises:
        NoKey: the class gives no fingerprint, or inherits one from above a method the
            certificate reads (:data:`_READ`) that it overrides.
    """
    kind = type(trajectory)
    owner = defining_class(kind, "fingerprint")
    for name in _READ:
        if not issubclass(owner, defining_class(kind, name)):
            raise NoKey(
                f"{kind.__name__} overrides {name}() but not fingerprint(): its certificate is "
                "not cached"
            )
    values = trajectory.fingerprint()
    if values is None:
        raise NoKey(f"{kind.__name__} gives no fingerprint(): its certificate is not cached")
    try:
        return {
            "class": _class_name(trajectory),
            "dof": int(trajectory.dof),
            "fingerprint": canonical(values),
        }
    except TypeError as exc:
        raise NoKey(
            f"the fingerprint of {kind.__name__} {exc}: its certificate is not cached"
        ) from None


def robot_fingerprint(robot) -> dict[str, Any]:
    """The robot's Pinocchio model (its text serialization, hashed), per-link inertial data,
    locked joints, URDF dynamics and joint kinds."""
    model = hashlib.sha256(robot.model.saveToString().encode()).hexdigest()
    links = [
        [
            link.name,
            int(link.joint_index),
            canonical(np.asarray(link.placement.homogeneous, dtype=float)),
            canonical(np.asarray(link.parameters, dtype=float)),
        ]
        for link in robot.links
    ]
    return {
        "model": model,
        "links": links,
        "locked_joints": canonical(dict(robot.locked_joints)),
        "urdf_dynamics": canonical(np.asarray(robot.urdf_dynamics, dtype=float)),
        "joint_kinds": list(robot.joint_kinds),
    }


def canonical(value: Any) -> Any:
    """``value`` as JSON data that identifies it exactly: floats by ``float.hex``, arrays by
    dtype, shape and the sha256 of their bytes, mappings with sorted keys, dataclasses by class
    and compared fields.

    Raises:
        TypeError: a value of another kind (names it).
    """
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return {"float": float(value).hex()}
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise TypeError("holds an array of Python objects")
        array = np.ascontiguousarray(value)
        digest = hashlib.sha256(array.tobytes()).hexdigest()
        return {"array": array.dtype.str, "shape": list(array.shape), "sha256": digest}
    if isinstance(value, Mapping):
        return {"mapping": sorted([str(k), canonical(v)] for k, v in value.items())}
    if isinstance(value, list | tuple):
        return [canonical(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {
            f.name: canonical(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if f.compare
        }
        return {"dataclass": _class_name(value), "fields": fields}
    raise TypeError(f"holds a {type(value).__name__}, which has no canonical form")


@functools.cache
def source_digest() -> str:
    """The sha256 of urpc's own source files (every ``.py`` under the package, by relative path
    and content), computed once per process."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


@functools.cache
def library_versions() -> dict[str, str]:
    """The versions of the numerical libraries the certificate is computed with."""
    import pinocchio
    import scipy

    return {"pinocchio": pinocchio.__version__, "numpy": np.__version__, "scipy": scipy.__version__}


def _class_name(value: Any) -> str:
    kind = type(value)
    return f"{kind.__module__}.{kind.__qualname__}"
