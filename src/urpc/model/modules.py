"""Module libraries: the bodies a modular arm is made of, each described by a module file.

A *module* is one rigid body with its nominal inertial parameters, its connection frames and its
own uncertainty, described by a YAML file ``<name>.yaml`` of a library folder (the built-in one is
``robots/modules``; the schema is :class:`urpc.formats.module.ModuleFile`, and ``docs/modular.md``
documents every field). Kinds:

* ``base``: the root, fixed to the world; one output flange (``distal``).
* ``actuator``: a revolute joint and the housing it turns; the joint sits at the module frame and
  turns about ``joint.axis`` (module frame); input (``proximal``) and output (``distal``) flanges;
  optionally its ``drive:`` (armature, damping, friction: :mod:`urpc.model.drives`).
* ``link``, ``tool``: rigid parts joined by fixed joints; a tool's output frame is its TCP.
* ``payload``: a held object; it is not put in the URDF but becomes the uncertainty file's
  ``payload:`` entry, fixed to the TCP, so that changing the payload changes only the box.

:mod:`urpc.model.modular` composes modules into arms.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, get_args

import numpy as np
import pinocchio as pin

from ..errors import InputError, did_you_mean
from ..formats import module as schema
from ..formats.base import read_yaml, validate
from ..formats.uncertainty import LinkEntry
from .catalog import builtin_root
from .drives import Drive, resolve_drive
from .inertia import inertia_problem
from .parameter_box import PHYSICAL_FIELDS, LinkBox, inertia_from_physical
from .uncertainty import resolve_link_box

ModuleKind = schema.ModuleKind
KINDS: tuple[str, ...] = get_args(ModuleKind)
SHAPES: tuple[str, ...] = ("cylinder", "tube", "box")


# ============================================================================ module description
@dataclass(frozen=True)
class Connector:
    """A connection frame (flange) of a module, given in the module frame.

    Attributes:
        type: Connector type (``"L"``, ``"M"``, ``"tcp"``, ...); a module's input connects to the
            previous module's output only if both types are equal.
        xyz: Origin of the frame [m].
        rpy: Orientation, URDF roll-pitch-yaw [rad]; by convention the frame's z axis points along
            the chain, away from the base.
    """

    type: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]

    @property
    def placement(self) -> pin.SE3:
        """Pose of the frame in the module frame."""
        return pin.SE3(pin.rpy.rpyToMatrix(np.array(self.rpy)), np.array(self.xyz))


@dataclass(frozen=True)
class JointSpec:
    """The revolute joint of an actuator; it turns the module about ``axis`` at the module frame.

    Attributes:
        axis: Unit joint axis in the module frame.
        lower, upper: Position limits [rad].
        effort: Torque limit [N m].
        velocity: Velocity limit [rad/s].
    """

    axis: tuple[float, float, float]
    lower: float
    upper: float
    effort: float
    velocity: float


@dataclass(frozen=True)
class Shape:
    """Geometry of a module, for drawings and URDF visuals (the inertial data are authoritative).

    Attributes:
        kind: ``"cylinder"`` (``radius``, ``length`` [m], axis z), ``"tube"`` (thin-walled:
            mean ``radius``, ``wall``, ``length`` [m], ``density`` [kg/m^3], axis z) or ``"box"``
            (``size`` [m], three sides along x, y, z).
        dimensions: The dimensions named above.
        xyz, rpy: Pose of the shape's center in the module frame [m], [rad].
    """

    kind: str
    dimensions: Mapping[str, Any]
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]

    @property
    def placement(self) -> pin.SE3:
        return pin.SE3(pin.rpy.rpyToMatrix(np.array(self.rpy)), np.array(self.xyz))


@dataclass(frozen=True, eq=False)
class Module:
    """One module of a library, read from ``<name>.yaml``.

    Attributes:
        name: Module name (the file stem).
        kind: One of :data:`KINDS`.
        source: The module file.
        description: Free text.
        inertial: Nominal physical coordinates :data:`urpc.model.uncertainty.PHYSICAL_FIELDS` in the
            module frame: mass [kg], CoM [m], rotational inertia about the CoM [kg m^2].
        proximal: Input frame (``None`` for a base).
        distal: Output frame (``None`` for a payload).
        joint: The actuator's joint (``None`` for other kinds).
        uncertainty: The module's box, an entry in the uncertainty format (module frame).
        box: That box, resolved against :attr:`inertial` (``None`` for a base).
        shape: Geometry for drawings, or ``None``.
        drive: The joint's drive (armature, damping, friction with their intervals), or
            ``None``: a rigid joint (an actuator without ``drive:``, or another kind).
    """

    name: str
    kind: str
    source: Path
    description: str
    inertial: np.ndarray
    proximal: Connector | None
    distal: Connector | None
    joint: JointSpec | None
    uncertainty: Mapping[str, Any]
    box: LinkBox | None
    shape: Shape | None
    drive: Drive | None = None

    @property
    def inertia(self) -> pin.Inertia:
        """Nominal spatial inertia in the module frame."""
        return inertia_from_physical(self.inertial)


@dataclass(frozen=True, eq=False)
class ModuleLibrary:
    """The modules of one folder, by name. Use :func:`load_module_library` to read one."""

    root: Path
    modules: Mapping[str, Module]

    def __getitem__(self, name: str) -> Module:
        try:
            return self.modules[name]
        except KeyError:
            raise InputError(
                f"unknown module '{name}'; " + did_you_mean(name, self.modules),
                source=self.root,
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self.modules

    def __iter__(self) -> Iterator[str]:
        return iter(self.modules)

    def __len__(self) -> int:
        return len(self.modules)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.modules)

    def of_kind(self, kind: str) -> tuple[str, ...]:
        """Names of the modules of one kind."""
        return tuple(name for name, module in self.modules.items() if module.kind == kind)


# ============================================================================ reading modules
_LIBRARY_CACHE: dict[Path, tuple[list, ModuleLibrary]] = {}


def load_module_library(path: str | Path | None = None) -> ModuleLibrary:
    """Read every module file ``*.yaml`` of a folder (default: the built-in ``robots/modules``).

    The result is cached per folder and re-read only when a file is added, removed or changed.

    Raises:
        InputError: the folder does not exist or holds no module; a module file is invalid
            (naming the file and the field).
    """
    root = Path(builtin_root() / "modules" if path is None else path).expanduser().resolve()
    if not root.is_dir():
        raise InputError("module library folder does not exist", source=root)
    signature = []
    with os.scandir(root) as entries:
        for entry in entries:
            if entry.name.endswith(".yaml") and entry.is_file():
                stat = entry.stat()
                signature.append((entry.name, stat.st_mtime_ns, stat.st_size))
    signature.sort()
    cached = _LIBRARY_CACHE.get(root)
    if cached is not None and cached[0] == signature:
        return cached[1]
    if not signature:
        raise InputError("the module library holds no module file (*.yaml)", source=root)
    modules = {}
    for filename, _, _ in signature:
        module = read_module(root / filename)
        modules[module.name] = module
    library = ModuleLibrary(root, modules)
    _LIBRARY_CACHE[root] = (signature, library)
    return library


def read_module(path: str | Path) -> Module:
    """Read and validate one module file.

    Raises:
        InputError: naming the file and the field, for an unknown key or kind, a missing or
            superfluous connection frame or joint, a non-physical inertia, an invalid box, a
            drive on a module without a joint or with an invalid interval.
    """
    path = Path(path)
    source = str(path)
    document = read_yaml(path)
    spec = validate(schema.ModuleFile, document, source)
    name = spec.name or path.stem
    if name != path.stem:
        raise InputError(
            f"the module name '{name}' differs from the file name; name the file '{name}.yaml' "
            "or drop the name field",
            source,
            "name",
        )
    inertial = np.array([getattr(spec.inertial, key) or 0.0 for key in PHYSICAL_FIELDS])
    problem = inertia_problem(np.asarray(inertia_from_physical(inertial).inertia))
    if problem:
        raise InputError(f"non-physical inertia: {problem}", source, "inertial")
    box = None
    if spec.kind != "base":
        box = resolve_link_box(
            spec.uncertainty or LinkEntry(),
            name,
            inertia_from_physical(inertial),
            source,
            "uncertainty",
            allow_zero_mass=spec.kind == "payload",
        )
    return Module(
        name=name,
        kind=spec.kind,
        source=path,
        description=spec.description,
        inertial=inertial,
        proximal=_connector(spec.proximal),
        distal=_connector(spec.distal),
        joint=_joint(spec.joint),
        uncertainty=document.get("uncertainty") or {},
        box=box,
        shape=_shape(spec.shape),
        drive=None if spec.drive is None else resolve_drive(spec.drive, source),
    )


def _connector(spec: schema.Connector | None) -> Connector | None:
    return None if spec is None else Connector(spec.connector, spec.xyz, spec.rpy)


def _joint(spec: schema.Joint | None) -> JointSpec | None:
    if spec is None:
        return None
    axis = np.array(spec.axis) / np.linalg.norm(spec.axis)
    return JointSpec(
        tuple(float(a) for a in axis), spec.lower, spec.upper, spec.effort, spec.velocity
    )


def _shape(spec: schema.Shape | None) -> Shape | None:
    if spec is None:
        return None
    kind = next(k for k in SHAPES if getattr(spec, k) is not None)
    dimensions = getattr(spec, kind).model_dump()
    return Shape(kind=kind, dimensions=dimensions, xyz=spec.xyz, rpy=spec.rpy)
