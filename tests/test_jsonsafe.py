"""JSON-safe conversion: whatever urpc computes dumps with allow_nan=False and reads back."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from urpc.jsonsafe import finite_or_none, jsonable


def test_jsonable_output_is_strict_json_that_reads_back_to_the_finite_values():
    value = {
        1: (np.float64(0.5), np.int64(3), np.bool_(True)),
        "array": np.array([[1.0, np.nan], [np.inf, -2.0]]),
        "nested": [{"x": float("-inf")}, Path("/tmp/run")],
        "plain": [None, "text", 7],
    }
    text = json.dumps(jsonable(value), allow_nan=False)  # raises on NaN or inf
    assert json.loads(text) == {
        "1": [0.5, 3, True],
        "array": [[1.0, None], [None, -2.0]],
        "nested": [{"x": None}, "/tmp/run"],
        "plain": [None, "text", 7],
    }


def test_finite_or_none():
    assert finite_or_none(None) is None and finite_or_none(math.nan) is None
    assert finite_or_none(np.float32(math.inf)) is None
    assert finite_or_none(np.float64(2.5)) == 2.5 and type(finite_or_none(np.int64(2))) is float
