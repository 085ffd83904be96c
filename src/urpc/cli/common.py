"""What every CLI command shares: the error contract, argument types, JSON output."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InputError

if TYPE_CHECKING:  # numpy is imported when a command needs it (start-up time of the CLI)
    import numpy as np

EXIT_OK = 0
EXIT_INPUT = 2


class Parser(argparse.ArgumentParser):
    """argparse with the package's error contract: one ``error:`` line, exit code 2."""

    def error(self, message: str):  # type: ignore[override]
        raise InputError(f"{message} (see '{self.prog} --help')")


def vector(text: str) -> np.ndarray:
    """Parse ``"0.1,0.2"`` or ``"0.1 0.2"`` into a float vector (NaN/inf rejected)."""
    import numpy as np

    parts = [p for p in text.replace(",", " ").split() if p]
    try:
        values = np.array([float(p) for p in parts])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a list of numbers, e.g. 0.1,0.2"
        ) from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"'{text}' must be finite numbers, e.g. 0.1,0.2")
    return values


def finite_float(text: str) -> float:
    """A finite number (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' must be a finite number")
    return value


def positive_float(text: str) -> float:
    """A finite number > 0 (argparse type)."""
    value = finite_float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be a finite number > 0")
    return value


def non_negative_float(text: str) -> float:
    """A finite number >= 0 (argparse type)."""
    value = finite_float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be a finite number >= 0")
    return value


def _integer(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not an integer") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"'{text}' must be an integer >= {minimum}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1 (argparse type)."""
    return _integer(text, 1)


def non_negative_int(text: str) -> int:
    """An integer >= 0 (argparse type)."""
    return _integer(text, 0)


def names(text: str) -> list[str]:
    return [p for p in text.replace(",", " ").split() if p]


def add_robot_arguments(parser: argparse.ArgumentParser, uncertainty_required: bool = False):
    parser.add_argument(
        "robot", help="URDF path, built-in name (rr_planar) or example-robot-data name (ur5, panda)"
    )
    parser.add_argument(
        "--uncertainty",
        "-u",
        type=Path,
        required=uncertainty_required,
        help="uncertainty YAML file (default for built-in robots: the robot's uncertainty.yaml)",
    )
    parser.add_argument(
        "--lock",
        type=names,
        default=[],
        metavar="JOINTS",
        help="comma-separated joints to lock, e.g. panda_finger_joint1,panda_finger_joint2",
    )


def one_line(text: str) -> str:
    return " ".join(text.split())


def json_text(payload: dict) -> str:
    return json.dumps(jsonable(payload), indent=2, allow_nan=False)


def print_json(payload: dict) -> None:
    print(json_text(payload))


def warn_uncertified(guarantee: dict) -> None:
    """One ``warning:`` line on stderr when a run's configuration is not certified."""
    if not guarantee["certified"]:
        print(f"warning: {guarantee['not_certified']}", file=sys.stderr)


def jsonable(value):
    import numpy as np

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
