"""Modular arms: a library of modules described in files, composed into one URDF and one box.

A *module* is one rigid body with its nominal inertial parameters, its connection frames and its
own uncertainty, described by a YAML file ``<name>.yaml`` of a library folder (the built-in one is
``robots/modules``; ``docs/modular.md`` documents every field). Kinds:

* ``base``: the root, fixed to the world; one output flange (``distal``).
* ``actuator``: a revolute joint and the housing it turns; the joint sits at the module frame and
  turns about ``joint.axis`` (module frame); input (``proximal``) and output (``distal``) flanges.
* ``link``, ``tool``: rigid parts joined by fixed joints; a tool's output frame is its TCP.
* ``payload``: a held object; it is not put in the URDF but becomes the uncertainty file's
  ``payload:`` entry, fixed to the TCP, so that changing the payload changes only the box.

Connecting module ``b`` after module ``a`` makes ``b``'s input frame coincide with ``a``'s output
frame, so ``b``'s module frame sits at ``X_a = D_a P_b^-1`` in ``a``'s module frame (``D``, ``P``
the output and input frame placements). Flange connector types must be equal.

:func:`assemble` writes the URDF with yourdfpy and the combined uncertainty file; the URDF link of
module ``i`` is ``m<i>_<module>`` (its frame is the module frame, so the module's uncertainty
applies to it unchanged), revolute joints are ``joint1 .. jointN``, and a massless ``tcp`` link
marks the output frame of the last module.
"""

from __future__ import annotations

import atexit
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pinocchio as pin
import yaml

from ..errors import InputError, did_you_mean
from .catalog import builtin_root
from .robot import Robot, inertia_problem, load_robot
from .uncertainty import (
    PHYSICAL_FIELDS,
    LinkBox,
    ParameterBox,
    inertia_from_physical,
    parse_link_box,
    parse_number,
    parse_uncertainty,
    read_yaml,
)

ModuleKind = Literal["base", "actuator", "link", "tool", "payload"]
KINDS: tuple[str, ...] = ("base", "actuator", "link", "tool", "payload")
SHAPES: tuple[str, ...] = ("cylinder", "tube", "box")
#: Name of the massless link at the output frame of the last module (payloads are fixed to it).
TCP_LINK = "tcp"
#: Name of the payload body in the combined uncertainty box.
PAYLOAD_NAME = "payload"

_MODULE_KEYS = (
    "name", "kind", "description", "shape", "inertial", "joint", "proximal", "distal",
    "uncertainty",
)  # fmt: skip
_JOINT_KEYS = ("axis", "lower", "upper", "effort", "velocity")
_CONNECTOR_KEYS = ("connector", "xyz", "rpy")
_SHAPE_DIMENSIONS = {
    "cylinder": ("radius", "length"),
    "tube": ("radius", "wall", "length", "density"),
    "box": ("size",),
}
_ASSEMBLY_KEYS = ("name", "description", "modules", "disturbance")
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
_SNAP = 1e-12  # rotation entries this close to 0 or +-1 are made exact (rpy round trip)


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
            superfluous connection frame or joint, a non-physical inertia, an invalid box.
    """
    path = Path(path)
    source = str(path)
    doc = read_yaml(path)
    _mapping(doc, source, "(top level)")
    _known_keys(doc, _MODULE_KEYS, source, "")
    name = str(doc.get("name", path.stem))
    if name != path.stem:
        raise InputError(
            f"the module name '{name}' differs from the file name; name the file '{name}.yaml' "
            "or drop the name field",
            source,
            "name",
        )
    kind = doc.get("kind")
    if kind not in KINDS:
        raise InputError(
            f"unknown module kind {kind!r}; " + did_you_mean(str(kind), KINDS), source, "kind"
        )

    def required(key: str, needed: bool, why: str) -> None:
        if needed and doc.get(key) is None:
            raise InputError(f"a {kind} module needs '{key}' ({why})", source, key)
        if not needed and doc.get(key) is not None:
            raise InputError(f"a {kind} module has no '{key}' ({why})", source, key)

    required("proximal", kind != "base", "the input frame; only a base has none")
    required("distal", kind != "payload", "the output frame; only a payload has none")
    required("joint", kind == "actuator", "only actuators have a joint")
    if kind == "base" and doc.get("uncertainty"):
        raise InputError(
            "a base is fixed to the world, so its parameters do not enter the dynamics; "
            "remove its uncertainty",
            source,
            "uncertainty",
        )
    if "inertial" not in doc:
        raise InputError("every module needs its nominal inertial parameters", source, "inertial")
    inertial = _read_inertial(doc["inertial"], source, allow_zero_mass=kind == "payload")
    uncertainty = doc.get("uncertainty") or {}
    _mapping(uncertainty, source, "uncertainty")
    if kind == "payload" and "barycentric" in uncertainty:
        raise InputError(
            "a payload box is physical (mass, com_*, i**): it becomes the uncertainty file's "
            "payload entry, which has no barycentric form",
            source,
            "uncertainty.barycentric",
        )
    box = None
    if kind != "base":
        box = parse_link_box(
            uncertainty,
            name,
            inertia_from_physical(inertial),
            source,
            "uncertainty",
            allow_zero_mass=kind == "payload",
        )
    return Module(
        name=name,
        kind=kind,
        source=path,
        description=str(doc.get("description", "")),
        inertial=inertial,
        proximal=_read_connector(doc.get("proximal"), source, "proximal"),
        distal=_read_connector(doc.get("distal"), source, "distal"),
        joint=_read_joint(doc.get("joint"), source),
        uncertainty=uncertainty,
        box=box,
        shape=_read_shape(doc.get("shape"), source),
    )


def _read_inertial(doc: Any, source: str, allow_zero_mass: bool) -> np.ndarray:
    _mapping(doc, source, "inertial")
    _known_keys(doc, PHYSICAL_FIELDS, source, "inertial.")
    if "mass" not in doc:
        raise InputError("the nominal mass [kg] is required", source, "inertial.mass")
    values = np.array(
        [
            parse_number(doc.get(key, 0.0), source, f"inertial.{key}", "a number")
            for key in PHYSICAL_FIELDS
        ]
    )
    if not np.all(np.isfinite(values)):
        raise InputError("inertial parameters must be finite numbers", source, "inertial")
    if values[0] < 0 or (values[0] == 0 and not allow_zero_mass):
        raise InputError(
            f"mass {values[0]:g} must be {'>= 0' if allow_zero_mass else '> 0'} [kg]",
            source,
            "inertial.mass",
        )
    problem = inertia_problem(np.asarray(inertia_from_physical(values).inertia))
    if problem:
        raise InputError(f"non-physical inertia: {problem}", source, "inertial")
    return values


def _read_connector(doc: Any, source: str, key: str) -> Connector | None:
    if doc is None:
        return None
    _mapping(doc, source, key)
    _known_keys(doc, _CONNECTOR_KEYS, source, f"{key}.")
    if not doc.get("connector"):
        raise InputError(
            "the connector type is required (for example L, M or tcp): only flanges of the same "
            "type connect",
            source,
            f"{key}.connector",
        )
    return Connector(
        type=str(doc["connector"]),
        xyz=_vector(doc.get("xyz", [0, 0, 0]), source, f"{key}.xyz"),
        rpy=_vector(doc.get("rpy", [0, 0, 0]), source, f"{key}.rpy"),
    )


def _read_joint(doc: Any, source: str) -> JointSpec | None:
    if doc is None:
        return None
    _mapping(doc, source, "joint")
    _known_keys(doc, _JOINT_KEYS, source, "joint.")
    for key in _JOINT_KEYS:
        if key not in doc:
            raise InputError(
                f"the joint needs '{key}' (all of: {', '.join(_JOINT_KEYS)})",
                source,
                f"joint.{key}",
            )
    axis = np.array(_vector(doc["axis"], source, "joint.axis"))
    norm = float(np.linalg.norm(axis))
    if norm < 1e-9:
        raise InputError("the joint axis must be a non-zero vector", source, "joint.axis")
    values = {k: parse_number(doc[k], source, f"joint.{k}", "a number") for k in _JOINT_KEYS[1:]}
    if not values["lower"] < values["upper"]:
        raise InputError(
            f"lower limit {values['lower']:g} must be below upper limit {values['upper']:g} [rad]",
            source,
            "joint.lower",
        )
    for key in ("effort", "velocity"):
        if not values[key] > 0:
            raise InputError(f"{key} limit must be > 0", source, f"joint.{key}")
    return JointSpec(axis=tuple(float(a) for a in axis / norm), **values)


def _read_shape(doc: Any, source: str) -> Shape | None:
    if doc is None:
        return None
    _mapping(doc, source, "shape")
    kinds = [k for k in doc if k in SHAPES]
    _known_keys(doc, (*SHAPES, "xyz", "rpy"), source, "shape.")
    if len(kinds) != 1:
        raise InputError(f"give exactly one shape, one of: {', '.join(SHAPES)}", source, "shape")
    kind = kinds[0]
    dimensions = doc[kind]
    _mapping(dimensions, source, f"shape.{kind}")
    _known_keys(dimensions, _SHAPE_DIMENSIONS[kind], source, f"shape.{kind}.")
    values: dict[str, Any] = {}
    for key in _SHAPE_DIMENSIONS[kind]:
        if key not in dimensions:
            raise InputError(
                f"a {kind} needs {', '.join(_SHAPE_DIMENSIONS[kind])}", source, f"shape.{kind}"
            )
        if key == "size":
            values[key] = _vector(dimensions[key], source, f"shape.{kind}.size")
        else:
            values[key] = parse_number(dimensions[key], source, f"shape.{kind}.{key}", "a number")
    return Shape(
        kind=kind,
        dimensions=values,
        xyz=_vector(doc.get("xyz", [0, 0, 0]), source, "shape.xyz"),
        rpy=_vector(doc.get("rpy", [0, 0, 0]), source, "shape.rpy"),
    )


def _vector(value: Any, source: str, fieldname: str) -> tuple[float, float, float]:
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise InputError(f"{value!r} is not a list of 3 numbers", source, fieldname)
    numbers = tuple(parse_number(v, source, fieldname, "a number") for v in value)
    if not all(np.isfinite(numbers)):
        raise InputError(f"{value!r} has a non-finite entry", source, fieldname)
    return numbers  # type: ignore[return-value]


def _mapping(value: Any, source: str | None, fieldname: str) -> None:
    if not isinstance(value, Mapping):
        raise InputError(
            f"expected a mapping (key: value lines), got {type(value).__name__} {value!r}",
            source,
            fieldname,
        )


def _known_keys(doc: Mapping, valid: Sequence[str], source: str | None, prefix: str) -> None:
    for key in doc:
        if str(key) not in valid:
            raise InputError(
                f"unknown key '{key}'; " + did_you_mean(str(key), valid), source, f"{prefix}{key}"
            )


# ============================================================================ assemblies
@dataclass(frozen=True)
class Part:
    """Where one module of an assembly went.

    Attributes:
        module: Module name.
        kind: Module kind.
        link: Its URDF link (``m<i>_<module>``), or the payload's name in the box.
        joint: The URDF joint attaching that link to the previous one (``joint<k>`` for an
            actuator, ``m<i>_<module>_fixed`` otherwise), ``None`` for the base and a payload.
    """

    module: str
    kind: str
    link: str
    joint: str | None


@dataclass(frozen=True)
class Assembly:
    """A modular arm composed into one URDF and one uncertainty file (see :func:`assemble`).

    Attributes:
        name: Assembly (and URDF robot) name.
        modules: The module names, base first.
        urdf_path: The written URDF.
        uncertainty_path: The written uncertainty file (the :attr:`uncertainty` document).
        uncertainty: The combined uncertainty document (urpc uncertainty format): each moving
            module's box on its link, a payload module as the ``payload:`` entry on ``tcp``.
        parts: One :class:`Part` per module, in order.
        compose_time: Time spent composing and writing both files [s].
        library: The module library the assembly was made from.
    """

    name: str
    modules: tuple[str, ...]
    urdf_path: Path
    uncertainty_path: Path
    uncertainty: Mapping[str, Any] = field(repr=False)
    parts: tuple[Part, ...] = field(repr=False)
    compose_time: float = field(compare=False)
    library: ModuleLibrary = field(repr=False, compare=False)

    @property
    def dof(self) -> int:
        """Number of joints (actuator modules)."""
        return sum(part.kind == "actuator" for part in self.parts)

    def load(self) -> tuple[Robot, ParameterBox]:
        """The robot model (:func:`urpc.model.robot.load_robot` on :attr:`urdf_path`) and its box.

        The box is :attr:`uncertainty` validated by :func:`urpc.model.uncertainty.parse_uncertainty`,
        the same as ``load_uncertainty(uncertainty_path, robot)`` without parsing the YAML text
        back (8 ms of the pure-Python YAML reader saved per assembly).
        """
        robot = load_robot(self.urdf_path)
        return robot, parse_uncertainty(self.uncertainty, robot, source=str(self.uncertainty_path))


def assemble(
    modules: Sequence[str],
    *,
    name: str = "assembly",
    library: ModuleLibrary | str | Path | None = None,
    out_dir: str | Path | None = None,
    disturbance: float | None = None,
) -> Assembly:
    """Compose modules, base first, into one URDF (written with yourdfpy) and one uncertainty file.

    Args:
        modules: Module names in chain order: a base, then modules each connecting to the previous
            one's output flange, at least one actuator, optionally a payload last.
        name: Assembly name (URDF robot name and file stem): letters, digits, ``_ . -``.
        library: A :class:`ModuleLibrary` or its folder (default: the built-in library).
        out_dir: Folder for ``<name>.urdf`` and ``<name>.uncertainty.yaml`` (created if needed);
            default: a fresh temporary folder, removed when the process exits.
        disturbance: Bound on ``||d||`` [N m] for the uncertainty file, ``None``: unknown.

    Raises:
        InputError: an empty list, an unknown module (naming close names), a chain not starting
            with a base, incompatible connectors (naming both modules and their connectors), no
            actuator, a payload that is not last, an invalid name.
    """
    return _assemble(modules, name, library, out_dir, disturbance, source=None, description=None)


def builtin_assemblies() -> dict[str, Path]:
    """The shipped assembly files (``robots/assemblies/*.yaml``) by name (the file stem)."""
    folder = builtin_root() / "assemblies"
    return {p.stem: p for p in sorted(folder.glob("*.yaml"))} if folder.is_dir() else {}


def load_assembly(
    path: str | Path,
    *,
    library: ModuleLibrary | str | Path | None = None,
    out_dir: str | Path | None = None,
) -> Assembly:
    """Compose the assembly described by a YAML file, or a shipped one by name (``arm_3dof``)::

        name: arm_3dof                  # optional, default: the file stem
        description: ...                # optional
        disturbance: unknown            # optional, or a bound on ||d|| [N m]
        modules: [base, actuator_large, elbow_large, link_500, elbow_small, link_300, tool_gripper]

    Raises:
        InputError: an unknown name (listing the shipped ones); naming the file and the field,
            as :func:`assemble`.
    """
    text = str(path)
    path = Path(text).expanduser()
    if not path.exists() and "/" not in text and path.suffix not in (".yaml", ".yml"):
        shipped = builtin_assemblies()
        if text not in shipped:
            raise InputError(
                f"unknown assembly '{text}': give an assembly file or a shipped name; "
                + did_you_mean(text, shipped),
                field="assembly",
            )
        path = shipped[text]
    source = str(path)
    doc = read_yaml(path)
    _mapping(doc, source, "(top level)")
    _known_keys(doc, _ASSEMBLY_KEYS, source, "")
    if "modules" not in doc:
        raise InputError("the list of module names is required", source, "modules")
    disturbance = doc.get("disturbance", "unknown")
    if isinstance(disturbance, str) and disturbance.strip().lower() == "unknown":
        disturbance = None
    elif disturbance is not None:
        disturbance = parse_number(disturbance, source, "disturbance", "a bound [N m] or 'unknown'")
        if not (np.isfinite(disturbance) and disturbance >= 0):
            raise InputError("the bound must be a finite number >= 0 [N m]", source, "disturbance")
    return _assemble(
        doc["modules"],
        str(doc.get("name", path.stem)),
        library,
        out_dir,
        disturbance,
        source=source,
        description=doc.get("description"),
    )


def _assemble(
    names: Any,
    name: str,
    library: ModuleLibrary | str | Path | None,
    out_dir: str | Path | None,
    disturbance: float | None,
    source: str | None,
    description: str | None,
) -> Assembly:
    start = time.perf_counter()
    if not isinstance(library, ModuleLibrary):
        library = load_module_library(library)
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise InputError(
            f"assembly name {name!r} must be letters, digits, '_', '.' or '-'", source, "name"
        )
    chain = _validated_chain(names, library, source)
    urdf, parts = _compose_urdf(chain, name)
    document = _uncertainty_document(chain, parts, name, disturbance, description)

    folder = Path(out_dir) if out_dir is not None else _temporary_folder()
    folder.mkdir(parents=True, exist_ok=True)
    urdf_path = folder / f"{name}.urdf"
    uncertainty_path = folder / f"{name}.uncertainty.yaml"
    _write_replacing(urdf_path, lambda path: urdf.write_xml_file(str(path)))
    _write_replacing(
        uncertainty_path,
        lambda path: path.write_text(
            yaml.dump(document, Dumper=_Dumper, sort_keys=False, default_flow_style=None)
        ),
    )
    return Assembly(
        name=name,
        modules=tuple(m.name for m in chain),
        urdf_path=urdf_path,
        uncertainty_path=uncertainty_path,
        uncertainty=document,
        parts=parts,
        compose_time=time.perf_counter() - start,
        library=library,
    )


def _validated_chain(names: Any, library: ModuleLibrary, source: str | None) -> list[Module]:
    if isinstance(names, str) or not isinstance(names, Sequence):
        raise InputError(
            f"expected a list of module names, got {type(names).__name__} {names!r}",
            source,
            "modules",
        )
    bases = library.of_kind("base")
    if not names:
        raise InputError(
            "the assembly is empty: give a base, then modules ending with a link or tool; "
            f"bases: {', '.join(bases)}; actuators: {', '.join(library.of_kind('actuator'))}",
            source,
            "modules",
        )
    chain = []
    for i, module_name in enumerate(names):
        if not isinstance(module_name, str) or module_name not in library:
            raise InputError(
                f"unknown module {module_name!r}; " + did_you_mean(str(module_name), library),
                source,
                f"modules[{i}]",
            )
        chain.append(library[module_name])
    if chain[0].kind != "base":
        raise InputError(
            f"an assembly starts with a base, not the {chain[0].kind} '{chain[0].name}'; "
            f"valid: {', '.join(bases)}",
            source,
            "modules[0]",
        )
    for i, module in enumerate(chain[1:], start=1):
        if module.kind == "base":
            raise InputError(
                f"'{module.name}' is a base; only the first module may be a base",
                source,
                f"modules[{i}]",
            )
        if module.kind == "payload" and i != len(chain) - 1:
            raise InputError(
                f"the payload '{module.name}' must be the last module (it is held at the TCP), "
                f"but {len(chain) - 1 - i} module(s) follow it",
                source,
                f"modules[{i}]",
            )
        parent = chain[i - 1]
        if parent.distal.type != module.proximal.type:
            fitting = [
                m.name
                for m in library.modules.values()
                if m.proximal is not None and m.proximal.type == parent.distal.type
            ]
            raise InputError(
                f"cannot connect '{module.name}' (input connector '{module.proximal.type}') to "
                f"'{parent.name}' (output connector '{parent.distal.type}'): the connector types "
                f"differ; modules with a '{parent.distal.type}' input: "
                + (", ".join(fitting) or "(none)"),
                source,
                f"modules[{i}]",
            )
    if not any(module.kind == "actuator" for module in chain):
        raise InputError(
            "the chain has no joint: add at least one actuator; actuators: "
            + ", ".join(library.of_kind("actuator")),
            source,
            "modules",
        )
    return chain


def _compose_urdf(chain: Sequence[Module], name: str) -> tuple[Any, tuple[Part, ...]]:
    import yourdfpy

    links, joints, parts = [], [], []
    parent: Module | None = None
    parent_link = ""
    n_joints = 0
    for i, module in enumerate(chain):
        if module.kind == "payload":
            parts.append(Part(module.name, module.kind, PAYLOAD_NAME, None))
            continue
        link = f"m{i}_{module.name}"
        links.append(
            yourdfpy.Link(name=link, inertial=_inertial(module), visuals=_visuals(module, link))
        )
        joint_name = None
        if parent is not None:
            origin = _homogeneous(parent.distal.placement * module.proximal.placement.inverse())
            if module.kind == "actuator":
                n_joints += 1
                joint_name = f"joint{n_joints}"
                spec = module.joint
                joints.append(
                    yourdfpy.Joint(
                        name=joint_name,
                        type="revolute",
                        parent=parent_link,
                        child=link,
                        origin=origin,
                        axis=np.array(spec.axis),
                        limit=yourdfpy.Limit(
                            effort=spec.effort,
                            velocity=spec.velocity,
                            lower=spec.lower,
                            upper=spec.upper,
                        ),
                    )
                )
            else:
                joint_name = f"{link}_fixed"
                joints.append(
                    yourdfpy.Joint(
                        name=joint_name, type="fixed", parent=parent_link, child=link, origin=origin
                    )
                )
        parts.append(Part(module.name, module.kind, link, joint_name))
        parent, parent_link = module, link
    links.append(yourdfpy.Link(name=TCP_LINK))
    joints.append(
        yourdfpy.Joint(
            name=f"{TCP_LINK}_fixed",
            type="fixed",
            parent=parent_link,
            child=TCP_LINK,
            origin=_homogeneous(parent.distal.placement),
        )
    )
    robot = yourdfpy.Robot(name=name, links=links, joints=joints)
    urdf = yourdfpy.URDF(robot=robot, build_scene_graph=False, load_meshes=False)
    return urdf, tuple(parts)


def _inertial(module: Module) -> Any:
    import yourdfpy

    inertia = module.inertia
    origin = np.eye(4)
    origin[:3, 3] = inertia.lever
    return yourdfpy.Inertial(
        origin=origin, mass=float(inertia.mass), inertia=np.asarray(inertia.inertia).copy()
    )


def _visuals(module: Module, link: str) -> list[Any]:
    import yourdfpy

    shape = module.shape
    if shape is None:
        return []
    d = shape.dimensions
    if shape.kind == "box":
        geometry = yourdfpy.Geometry(box=yourdfpy.Box(size=np.array(d["size"])))
    else:
        radius = d["radius"] + (d["wall"] / 2 if shape.kind == "tube" else 0.0)
        geometry = yourdfpy.Geometry(cylinder=yourdfpy.Cylinder(radius=radius, length=d["length"]))
    return [
        yourdfpy.Visual(
            name=f"{link}_visual", origin=_homogeneous(shape.placement), geometry=geometry
        )
    ]


def _snapped(matrix: np.ndarray) -> np.ndarray:
    """Entries within :data:`_SNAP` of 0 or +-1 made exact.

    Rotations by multiples of 90 degrees (the usual flange orientations) then survive yourdfpy's
    matrix -> rpy conversion exactly, also at the rpy singularity (pitch = +-90 degrees).
    """
    matrix = np.where(np.abs(matrix) < _SNAP, 0.0, matrix)
    return np.where(np.abs(np.abs(matrix) - 1.0) < _SNAP, np.sign(matrix), matrix)


def _homogeneous(placement: pin.SE3) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = _snapped(placement.rotation)
    matrix[:3, 3] = np.where(np.abs(placement.translation) < _SNAP, 0.0, placement.translation)
    return matrix


def _uncertainty_document(
    chain: Sequence[Module],
    parts: Sequence[Part],
    name: str,
    disturbance: float | None,
    description: str | None,
) -> dict[str, Any]:
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
    R = _snapped(pose.rotation)
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
    offset[1:4] = np.where(np.abs(pose.translation) < _SNAP, 0.0, pose.translation)
    return _snapped(linear), offset


def _plain(value: Any) -> Any:
    """A copy made of plain dicts, lists, strings and floats (for the YAML writer)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


# ---------------------------------------------------------------------------- files
try:  # libyaml's writer is several times faster than the pure-Python one
    _Dumper: type = yaml.CSafeDumper
except AttributeError:  # pragma: no cover - PyYAML built without libyaml
    _Dumper = yaml.SafeDumper

_TEMPORARY: list[tuple[int, str]] = []


def _write_replacing(path: Path, write: Callable[[Path], Any]) -> None:
    """Write a file through a temporary name and an atomic rename: a reader never sees a
    half-written file (and replacing is faster than truncating an existing file)."""
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        write(partial)
        os.replace(partial, path)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        raise InputError(f"cannot write the file ({exc})", source=path) from None


def _temporary_folder() -> Path:
    """A fresh temporary folder, removed at exit by the process that made it."""
    folder = tempfile.mkdtemp(prefix="urpc-assembly-")
    _TEMPORARY.append((os.getpid(), folder))
    return Path(folder)


@atexit.register
def _remove_temporary_folders() -> None:
    for pid, folder in _TEMPORARY:
        if pid == os.getpid():
            shutil.rmtree(folder, ignore_errors=True)
