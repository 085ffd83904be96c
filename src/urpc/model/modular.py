"""Modular arms: modules of a library composed into one URDF and one uncertainty box.

The modules and their files are described in :mod:`urpc.model.modules`. :func:`assemble` checks
the chain (a base first, matching flange connector types, at least one actuator, a payload last),
writes the URDF (:mod:`urpc.model.assembly_urdf`) and the combined uncertainty file
(:mod:`urpc.model.assembly_box`): each moving module's box applies unchanged to its link
``m<i>_<module>``, whose frame is the module frame, a payload module becomes the ``payload:`` entry
on the ``tcp`` link, and an actuator's drive the ``joints:`` entry of its joint (and the URDF
joint's ``<dynamics>``). Assembly files (schema
:class:`urpc.formats.assembly.AssemblyFile`) name the modules in order.
"""

from __future__ import annotations

import atexit
import os
import re
import shutil
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ..atomic import replace_file
from ..errors import InputError, did_you_mean
from ..formats.assembly import AssemblyFile
from ..formats.base import read_yaml, validate
from .assembly_box import uncertainty_document
from .assembly_urdf import PAYLOAD_NAME, TCP_LINK, Part, compose_urdf
from .catalog import builtin_root
from .modules import (
    KINDS,
    SHAPES,
    Connector,
    JointSpec,
    Module,
    ModuleKind,
    ModuleLibrary,
    Shape,
    load_module_library,
    read_module,
)
from .parameter_box import ParameterBox
from .robot import Robot, load_robot
from .uncertainty import parse_uncertainty

__all__ = [
    "KINDS", "PAYLOAD_NAME", "SHAPES", "TCP_LINK", "Assembly", "Connector", "JointSpec", "Module",
    "ModuleKind", "ModuleLibrary", "Part", "Shape", "assemble", "builtin_assemblies",
    "load_assembly", "load_module_library", "read_module",
]  # fmt: skip

_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


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
        back (8 ms of the pure-Python YAML reader saved per assembly). As every loaded robot,
        the robot is rigid; the box's ``joints:`` section carries the drives, and
        ``box.nominal_robot(robot)`` (the controller's model) and ``box.plant(point)``
        have them.
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
    spec = validate(AssemblyFile, read_yaml(path), source)
    return _assemble(
        spec.modules,
        spec.name or path.stem,
        library,
        out_dir,
        spec.disturbance,
        source=source,
        description=spec.description,
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
    urdf, parts = compose_urdf(chain, name)
    document = uncertainty_document(chain, parts, name, disturbance, description)

    folder = Path(out_dir) if out_dir is not None else _temporary_folder()
    folder.mkdir(parents=True, exist_ok=True)
    urdf_path = folder / f"{name}.urdf"
    uncertainty_path = folder / f"{name}.uncertainty.yaml"
    replace_file(urdf_path, lambda path: urdf.write_xml_file(str(path)))
    replace_file(
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


# ---------------------------------------------------------------------------- files
try:  # libyaml's writer is several times faster than the pure-Python one
    _Dumper: type = yaml.CSafeDumper
except AttributeError:  # pragma: no cover - PyYAML built without libyaml
    _Dumper = yaml.SafeDumper

_TEMPORARY: list[tuple[int, str]] = []


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
