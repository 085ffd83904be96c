"""The assembly file: a modular arm as a list of module names, base first.

Documented in ``docs/modular.md``; read by :func:`urpc.model.modular.load_assembly`, which checks
the chain against the module library (known names, matching connectors, one actuator at least).
"""

from __future__ import annotations

from pydantic import Field

from .base import FileFormat
from .uncertainty import Disturbance
from .values import Text


class AssemblyFile(FileFormat):
    """An assembly file: the chain of modules and what is known about the disturbance."""

    name: Text | None = Field(
        None,
        description="assembly and URDF robot name (letters, digits, _ . -); default: file stem",
    )
    description: Text | None = Field(None, description="free text")
    disturbance: Disturbance = Field(
        None, description="bound on ||d|| [N m] for the uncertainty file, or 'unknown' (default)"
    )
    modules: list[Text] = Field(
        description="module names in chain order: a base, modules each connecting to the "
        "previous one's output flange, at least one actuator, optionally a payload last"
    )
