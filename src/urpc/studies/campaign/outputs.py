"""The campaign's files (``runs.csv``, ``summary.json``, ``histogram.png``), written atomically."""

from __future__ import annotations

import csv
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...atomic import check_writable, write_files
from ...errors import InputError

#: File names written by :meth:`CampaignResult.save`.
RUNS_NAME, SUMMARY_NAME, HISTOGRAM_NAME = "runs.csv", "summary.json", "histogram.png"


def write_outputs(directory: str | Path, writers: Mapping[str, Callable[[Path], None]]) -> Path:
    """Write the files of ``writers`` (file name -> function writing it at a path) into
    ``directory`` atomically (:func:`urpc.atomic.write_files`), after
    :func:`urpc.atomic.check_writable`.

    Raises:
        InputError: the folder cannot be written (names it).
    """
    directory = check_writable(directory)
    try:
        return write_files(directory, writers)
    except OSError as exc:
        raise InputError(f"cannot write the campaign outputs ({exc})", source=directory) from None


def write_csv(rows: Sequence[Mapping[str, Any]], path: Path) -> None:
    """``rows`` (dicts with the same keys) as CSV: a header, then one line per row."""
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(rows[0].keys())
        for row in rows:
            writer.writerow(_cell(value) for value in row.values())


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, float | np.floating):
        return repr(float(value))  # shortest text that reads back to the same double
    return str(value)


def write_summary(summary: Mapping[str, Any], path: Path) -> None:
    with path.open("w") as stream:
        json.dump(summary, stream, indent=2, allow_nan=False)
        stream.write("\n")
