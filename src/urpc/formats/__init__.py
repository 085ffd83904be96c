"""The input file formats, each declared once as a typed schema (pydantic).

One module per format: :mod:`.uncertainty` (uncertainty box), :mod:`.parameter_point` (a true
plant), :mod:`.scenario` (its controllers' options in :mod:`.controller_options`), :mod:`.module`
and :mod:`.assembly` (modular arms). The value grammar (numbers as arithmetic, vectors, values of
several forms, interval notations) is in :mod:`.values`, and :mod:`.base` turns validation errors
into :class:`urpc.errors.InputError` naming the file and the field. The JSON
Schemas in ``docs/schemas/`` are generated from these models (:func:`json_schemas`).

This layer depends only on :mod:`urpc.errors` and :mod:`urpc.expressions`: the robot model, the
controllers and the studies build on it, never the other way around.
"""

from __future__ import annotations

import json
from typing import Any

from pydantic import BaseModel

from .assembly import AssemblyFile
from .module import ModuleFile
from .parameter_point import ParameterPointFile
from .scenario import Scenario
from .uncertainty import UncertaintyFile

#: Every format by the name of its JSON Schema file (``docs/schemas/<name>.schema.json``).
FORMATS: dict[str, type[BaseModel]] = {
    "uncertainty": UncertaintyFile,
    "parameter-point": ParameterPointFile,
    "scenario": Scenario,
    "module": ModuleFile,
    "assembly": AssemblyFile,
}


def json_schema(name: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of the format ``name`` (a key of :data:`FORMATS`)."""
    schema = FORMATS[name].model_json_schema(mode="validation")
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **schema}


def json_schema_text(name: str) -> str:
    """:func:`json_schema` as the text of its file in ``docs/schemas/``."""
    return json.dumps(json_schema(name), indent=2, sort_keys=True, ensure_ascii=False) + "\n"
