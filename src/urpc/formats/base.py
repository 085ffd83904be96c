"""What every file format shares: the base schema, YAML reading, and errors that say what to fix.

A format is a pydantic model derived from :class:`FileFormat`. :func:`validate` checks a parsed
document against it and turns pydantic's :class:`~pydantic.ValidationError` into the package's
:class:`~urpc.errors.InputError`, naming the file, the field path (``links.link2.mass``), what was
found and what is valid (with "did you mean" for a misspelt key or choice).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model, model_validator
from pydantic.fields import FieldInfo

from ..errors import InputError, did_you_mean, no_file

Format = TypeVar("Format", bound="FileFormat")


class FieldError(ValueError):
    """A validator's complaint about one sub-field of the value it checks (``path`` below it)."""

    def __init__(self, path: str | tuple[str | int, ...], message: str):
        super().__init__(message)
        self.path = (path,) if isinstance(path, str) else tuple(path)


class FileFormat(BaseModel):
    """Base of every format: a mapping whose keys are the fields (or their aliases), no others.

    A key with no value (``key:`` or ``key: null``) counts as not given.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        if not isinstance(data, Mapping):
            raise ValueError(
                f"expected a mapping (key: value lines), got {type(data).__name__} {data!r}"
            )
        valid = [field.alias or name for name, field in cls.model_fields.items()]
        for key in data:
            if str(key) not in valid:
                raise FieldError(str(key), f"unknown key '{key}'; " + did_you_mean(str(key), valid))
        return {key: value for key, value in data.items() if value is not None}


#: libyaml's safe loader when PyYAML was built with it (5-10x faster), else the Python one.
_SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


#: Limits on a data file (boxes, points, scenarios, modules: a few kB each when shipped): its
#: size [bytes], its nesting depth, and its node count with every alias expanded (an alias bomb
#: is small on disk and huge once expanded). Each is refused with one error before any work.
MAX_YAML_BYTES = 1 << 20
MAX_YAML_DEPTH = 32
MAX_YAML_NODES = 20_000


def read_yaml(path: str | Path) -> Any:
    """Load a YAML file, turning every I/O or syntax problem into an :class:`InputError`.

    Hostile files are refused before they are built: more than :data:`MAX_YAML_BYTES`, nesting
    deeper than :data:`MAX_YAML_DEPTH`, or more than :data:`MAX_YAML_NODES` nodes once the
    aliases are expanded (counted on the event stream, without expanding anything).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(no_file(path), source=path)
    try:
        with path.open("rb") as stream:
            data = stream.read(MAX_YAML_BYTES + 1)
        if len(data) > MAX_YAML_BYTES:
            size = path.stat().st_size
            raise InputError(
                f"the file is too large for a data file ({size / 2**20:.3g} MiB; at most "
                f"{MAX_YAML_BYTES // 2**20} MiB): give the uncertainty, scenario or module "
                "file itself",
                source=path,
            )
        text = data.decode("utf-8")
        _check_yaml_size(text, path)
        _refuse_duplicate_keys(text, path)
        return yaml.load(text, Loader=_SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise InputError(f"YAML syntax error{where}: {problem}", source=path) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the file ({exc})", source=path) from None


def _check_yaml_size(text: str, path: Path) -> None:
    """Refuse a document nested deeper than :data:`MAX_YAML_DEPTH` or with more than
    :data:`MAX_YAML_NODES` nodes once its aliases are expanded, from its event stream: each
    node's expanded size is summed into its parent, an anchor remembers the size of its node and
    an alias adds it again, so nothing is built or expanded."""
    anchors: dict[str, int] = {}
    stack: list[list] = [[0, None]]  # per open collection: [expanded size, anchor]
    total = 0
    for event in yaml.parse(text, Loader=_SafeLoader):
        if isinstance(event, yaml.CollectionStartEvent):
            stack.append([1, event.anchor])
            if len(stack) - 1 > MAX_YAML_DEPTH:
                line = event.start_mark.line + 1 if event.start_mark else "?"
                raise InputError(
                    f"the YAML is nested deeper than {MAX_YAML_DEPTH} levels (line {line}); "
                    "a data file needs a few",
                    source=path,
                )
            continue
        if isinstance(event, yaml.CollectionEndEvent):
            size, anchor = stack.pop()
        elif isinstance(event, yaml.ScalarEvent):
            size, anchor = 1, event.anchor
        elif isinstance(event, yaml.AliasEvent):
            size, anchor = anchors.get(event.anchor, 1), None
        else:
            continue
        if anchor is not None:
            anchors[anchor] = size
        stack[-1][0] += size
        total = stack[0][0]
        if total > MAX_YAML_NODES or size > MAX_YAML_NODES:
            expanded = " once its aliases (*name) are expanded" if anchors else ""
            raise InputError(
                f"the YAML holds more than {MAX_YAML_NODES} values{expanded}; a data file "
                "holds a few hundred (an alias bomb?)",
                source=path,
            )


def _refuse_duplicate_keys(text: str, path: Path) -> None:
    """Refuse a mapping that gives a key twice (YAML would keep the last one silently: an
    ``epsilon:`` edited further down, a link listed twice), from the event stream, naming the
    key's place and both lines."""
    stack: list[list] = []  # per open collection: [mapping?, nodes seen, {key: line}, key]
    for event in yaml.parse(text, Loader=_SafeLoader):
        if isinstance(event, yaml.CollectionEndEvent):
            stack.pop()
            continue
        if not isinstance(event, (yaml.ScalarEvent, yaml.AliasEvent, yaml.CollectionStartEvent)):
            continue
        if stack:
            parent = stack[-1]
            is_key = parent[0] and parent[1] % 2 == 0
            parent[1] += 1
            if is_key and isinstance(event, yaml.ScalarEvent):
                line = event.start_mark.line + 1 if event.start_mark else 0
                if event.value in parent[2]:
                    keys = [entry[3] for entry in stack[:-1] if entry[0] and entry[3] is not None]
                    raise InputError(
                        f"'{event.value}' is given twice (lines {parent[2][event.value]} and "
                        f"{line}); YAML would keep only the last: remove one",
                        source=path,
                        field=".".join([*keys, event.value]),
                    )
                parent[2][event.value] = line
                parent[3] = event.value
        if isinstance(event, yaml.CollectionStartEvent):
            stack.append([isinstance(event, yaml.MappingStartEvent), 0, {}, None])


def validate(
    schema: type[Format],
    document: Any,
    source: str | Path | None = None,
    context: Mapping[str, Any] | None = None,
    hints: Mapping[str, Sequence[str]] | None = None,
) -> Format:
    """``document`` (parsed YAML) checked against ``schema``.

    Args:
        context: Passed to the validators (for instance the folder relative paths start from).
        hints: Valid values of fields that only the caller knows (field path -> names), added to
            the message of a missing field.

    Raises:
        InputError: the first problem, naming ``source`` and the field.
    """
    try:
        return schema.model_validate({} if document is None else document, context=context)
    except ValidationError as exc:
        raise input_error(exc, document, schema, source, hints) from None


def validate_fields(
    schema: type[FileFormat],
    values: Mapping[str, Any],
    source: str | Path | None = None,
    context: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Some top-level entries of a ``schema`` document, checked as in a whole document (unknown
    keys, values, nested models; errors as :func:`validate`'s), by field name.

    The entries left out are not required, and the checks of ``schema`` that combine its fields
    are not run: the caller checks the model the values go into.
    """
    partial = validate(_partial(schema), values, source, context)
    return {name: getattr(partial, name) for name in partial.model_fields_set}


@functools.cache
def _partial(schema: type[FileFormat]) -> type[FileFormat]:
    """``schema``'s fields, each optional, without the model's own validators."""
    fields = {
        name: (
            Annotated[(field.annotation, *field.metadata)] if field.metadata else field.annotation,
            Field(None, alias=field.alias, title=field.title),
        )
        for name, field in schema.model_fields.items()
    }
    return create_model(schema.__name__, __base__=FileFormat, **fields)


def input_error(
    exc: ValidationError,
    document: Any,
    schema: type[BaseModel],
    source: str | Path | None,
    hints: Mapping[str, Sequence[str]] | None = None,
) -> InputError:
    """The :class:`InputError` of the first problem ``exc`` reports."""
    error = exc.errors(include_url=False)[0]
    kind, value, ctx = error["type"], error.get("input"), error.get("ctx") or {}
    path = _document_path(document, error["loc"], keep_last=kind == "missing")
    cause = ctx.get("error")
    if isinstance(cause, FieldError):
        path += cause.path
    name = str(path[-1]) if path else "value"
    if isinstance(cause, ValueError):
        message = str(cause)
    elif kind == "union_tag_not_found":  # a mapping without its discriminating key
        path += (ctx["discriminator"].strip("'"),)
        message = f"'{path[-1]}' is required"
    elif kind == "missing":
        found = _field(schema, path)
        description = found.description if found is not None else None
        message = f"'{name}' is required" + (f" ({description})" if description else "")
        choices = (hints or {}).get(_dotted(path))
        if choices is not None:
            message += f"; valid: {', '.join(choices)}"
    elif kind in ("literal_error", "union_tag_invalid", "enum"):
        if kind == "union_tag_invalid":
            path += (ctx["discriminator"].strip("'"),)
            value, name = ctx["tag"], ctx["discriminator"].strip("'")
        choices = re.findall(r"'([^']*)'", ctx.get("expected") or ctx.get("expected_tags", ""))
        found = _field(schema, path)
        what = found.title if found is not None and found.title else name
        message = f"unknown {what} {value!r}; " + did_you_mean(str(value), choices)
    elif kind in ("dict_type", "model_type", "model_attributes_type"):
        message = f"expected a mapping (key: value lines), got {type(value).__name__} {value!r}"
    elif kind in ("list_type", "tuple_type"):
        message = f"expected a list, got {type(value).__name__} {value!r}"
    elif kind in ("string_type", "str_type"):
        message = f"{value!r} is not a text"
    else:  # a pydantic message, with what was found
        message = f"{value!r}: {error['msg'][0].lower()}{error['msg'][1:]}"
    return InputError(message, source=source, field=_dotted(path) or None)


def _document_path(document: Any, loc: tuple, keep_last: bool) -> tuple[str | int, ...]:
    """The entries of pydantic's ``loc`` that index the document (union tags and ``[key]``
    markers dropped); with ``keep_last`` the last entry is kept even if absent (a missing key)."""
    path: list[str | int] = []
    node = document
    for k, part in enumerate(loc):
        last = k == len(loc) - 1
        if isinstance(node, Mapping) and part in node:
            node = node[part]
        elif isinstance(node, list | tuple) and isinstance(part, int) and part < len(node):
            node = node[part]
        elif not (keep_last and last):
            continue
        path.append(part)
    return tuple(path)


def _dotted(path: Sequence[str | int]) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _field(schema: type[BaseModel], path: Sequence[str | int]) -> FieldInfo | None:
    """The schema's field at ``path`` (through nested models, mappings and lists), if found."""
    models: list[Any] = [schema]
    found = None
    for k, part in enumerate(path):
        matches = [
            field
            for model in models
            for name, field in (getattr(model, "model_fields", None) or {}).items()
            if part in (name, field.alias)
        ]
        if matches:  # else: a mapping key or a list index, inside the same models
            found = matches[0]
            models = _nested_models(found.annotation)
        elif k == len(path) - 1:
            return None
    return found


def _nested_models(annotation: Any) -> list[Any]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in getattr(annotation, "__args__", ()) for m in _nested_models(arg)]
