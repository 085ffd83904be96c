"""JSON-safe values: what ``json.dumps(..., allow_nan=False)`` accepts, from what urpc computes.

Non-finite floats become ``null`` (JSON has no NaN or infinity), numpy scalars and arrays become
Python numbers and lists, tuples become lists, paths become text, mapping keys become text.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["finite_or_none", "jsonable"]


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
