"""JSON-safe values: what ``json.dumps(..., allow_nan=False)`` accepts, from what urpc computes.

Non-finite floats become ``null`` (JSON has no NaN or infinity; :func:`non_finite_paths` lists
where they were, :func:`restore_non_finite` puts them back), numpy scalars and arrays become
Python numbers and lists, tuples become lists, paths become text, mapping keys become text.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["finite_or_none", "jsonable", "non_finite_paths", "restore_non_finite"]


def jsonable(value: Any) -> Any:
    """``value`` with every container, number and path made JSON-safe (module docstring)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Path):
        return str(value)
    return value


def finite_or_none(value: float | None) -> float | None:
    """``value`` as a float, or ``None`` when it is ``None``, NaN or infinite."""
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def non_finite_paths(value: Any, prefix: str = "") -> dict[str, str]:
    """The non-finite floats inside ``value`` (what :func:`jsonable` turns into ``None``): their
    JSON Pointers (RFC 6901: ``/figures/margin``, ``/conditions/0/value``) -> ``"inf"``,
    ``"-inf"`` or ``"nan"``. :func:`restore_non_finite` puts them back."""
    found: dict[str, str] = {}
    if isinstance(value, dict):
        items = ((str(k), v) for k, v in value.items())
    elif isinstance(value, list | tuple | np.ndarray):
        items = ((str(i), v) for i, v in enumerate(value))
    else:
        if isinstance(value, float | np.floating) and not math.isfinite(value):
            found[prefix] = "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
        return found
    for key, item in items:
        found.update(non_finite_paths(item, f"{prefix}/{_escape(key)}"))
    return found


#: The floats :func:`restore_non_finite` puts back (the module's constants, so that a restored
#: NaN is the very object ``math.nan`` a fresh computation holds).
_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


def restore_non_finite(value: Any, paths: dict[str, str]) -> Any:
    """A copy of ``value`` (JSON data) with the non-finite floats of :func:`non_finite_paths` put
    back.

    Raises:
        ValueError: a pointer that does not lead to a ``None`` in ``value``, or an unknown value.
    """
    value = copy.deepcopy(value)
    for path, text in paths.items():
        if text not in _NON_FINITE:
            raise ValueError(f"'{text}' at '{path}' is not one of inf, -inf, nan")
        if not path.startswith("/"):
            raise ValueError(f"'{path}' is not a JSON Pointer (it starts with /)")
        *parents, last = (_unescape(key) for key in path[1:].split("/"))
        container = value
        try:
            for key in parents:
                container = container[int(key) if isinstance(container, list) else key]
            index = int(last) if isinstance(container, list) else last
            if container[index] is not None:
                raise ValueError(f"'{path}' holds {container[index]!r}, not null")
        except (KeyError, IndexError, TypeError) as exc:
            raise ValueError(f"no value at '{path}' ({exc})") from None
        container[index] = _NON_FINITE[text]
    return value


def _escape(key: str) -> str:
    return key.replace("~", "~0").replace("/", "~1")


def _unescape(key: str) -> str:
    return key.replace("~1", "/").replace("~0", "~")
