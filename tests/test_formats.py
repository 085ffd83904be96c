"""The file formats: published JSON Schemas equal the models, every shipped YAML file validates
against its schema with an independent validator (jsonschema), the names the formats declare
match the registries they stand for, and validation errors name the field path."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import pytest
import yaml

from urpc.errors import InputError
from urpc.formats import FORMATS, json_schema_text
from urpc.formats import scenario as scenario_format
from urpc.formats.base import validate
from urpc.formats.controller_options import IntervalOptions
from urpc.formats.uncertainty import UncertaintyFile

jsonschema = pytest.importorskip("jsonschema")

ROOT = Path(__file__).resolve().parents[1]
SCHEMAS = ROOT / "docs" / "schemas"
SHIPPED = sorted((ROOT / "robots").rglob("*.yaml"))
MARKER = "# yaml-language-server: $schema="


def expected_format(path: Path) -> str:
    """The format of a shipped file, from where it lies."""
    parts = path.relative_to(ROOT / "robots").parts
    if parts[0] in ("modules", "assemblies"):
        return {"modules": "module", "assemblies": "assembly"}[parts[0]]
    if parts[1] == "scenarios":
        return "scenario"
    return "uncertainty" if path.name.startswith("uncertainty") else "parameter-point"


@pytest.mark.parametrize("name", sorted(FORMATS))
def test_published_schemas_are_generated_from_the_models(name):
    path = SCHEMAS / f"{name}.schema.json"
    assert path.read_text() == json_schema_text(name), "run python scripts/export_schemas.py"


def test_no_stale_schema_files():
    # The folder is also the data package urpc._schemas (its __init__.py), which ships them.
    assert sorted(p.name for p in SCHEMAS.glob("*.json")) == sorted(
        f"{name}.schema.json" for name in FORMATS
    )


def test_every_format_has_shipped_files():
    assert {expected_format(path) for path in SHIPPED} == set(FORMATS)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: str(p.relative_to(ROOT / "robots")))
def test_shipped_yaml_names_and_meets_its_schema(path):
    first = path.read_text().splitlines()[0]
    assert first.startswith(MARKER), f"{path} lacks the yaml-language-server line"
    schema_path = (path.parent / first.removeprefix(MARKER)).resolve()
    assert schema_path == SCHEMAS / f"{expected_format(path)}.schema.json"
    schema = json.loads(schema_path.read_text())
    validator = jsonschema.Draft202012Validator(schema)
    validator.check_schema(schema)
    errors = [
        f"{'.'.join(map(str, e.absolute_path))}: {e.message}"
        for e in validator.iter_errors(yaml.safe_load(path.read_text()))
    ]
    assert errors == []


def test_schemas_reject_unknown_keys_and_wrong_notations():
    schema = json.loads((SCHEMAS / "uncertainty.schema.json").read_text())
    validator = jsonschema.Draft202012Validator(schema)
    assert validator.is_valid({"links": {"link2": {"mass": "10%", "iyy": ["5/12", "+100%"]}}})
    assert not validator.is_valid({"links": {"link2": {"mas": "10%"}}})
    assert not validator.is_valid({"links": {"link2": {"mass": "heavy"}}})
    assert not validator.is_valid({"links": {"link2": {"mass": [1, 2, 3]}}})
    for name in FORMATS:  # no machine paths (defaults, ...) in a published file
        assert str(ROOT) not in json_schema_text(name)


def test_the_interval_options_are_synthesize_keywords():
    """The interval options are synthesize's keyword arguments; the period is the scenario's."""
    from urpc.control.synthesis import synthesize

    keywords = [
        p.name
        for p in inspect.signature(synthesize).parameters.values()
        if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name != "sample_period"
    ]
    assert list(IntervalOptions.model_fields) == keywords


@pytest.mark.parametrize(
    "document, field, words",
    [
        ({"links": {"link2": {"mass": {"lo": 1}}}}, "links.link2.mass", ["is not an interval"]),
        ({"payload": {"mass": [0, 1]}}, "payload.link", ["'link' is required", "link1, link2"]),
        ({"links": "link2"}, "links", ["expected a mapping", "got str"]),
        ({"description": ["a"]}, "description", ["is not a text"]),
    ],
)
def test_errors_name_the_field_path(document, field, words):
    with pytest.raises(InputError) as info:
        validate(UncertaintyFile, document, "box.yaml", hints={"payload.link": ("link1", "link2")})
    assert info.value.source == "box.yaml" and info.value.field == field
    for word in words:
        assert word in str(info.value)


def test_union_tags_are_not_in_the_field_path():
    document = {
        "robot": "rr_planar",
        "uncertainty": str(ROOT / "robots" / "rr_planar" / "uncertainty.yaml"),
        "trajectory": {"kind": "quintic", "points": [[0, 0], [0, "x"]]},
    }
    with pytest.raises(InputError) as info:
        validate(scenario_format.Scenario, document, "s.yaml")
    assert info.value.field == "trajectory.points[1][1]"
    assert "'x' is not a finite number" in str(info.value)
    document["trajectory"] = {"amplitude": [1, 2]}
    with pytest.raises(InputError, match="'kind' is required") as info:
        validate(scenario_format.Scenario, document, "s.yaml")
    assert info.value.field == "trajectory.kind"
