"""The package's exceptions: one base class, and messages that say what to fix.

Every error raised for bad user input is a :class:`UrpcError`. Its message names the file (when
there is one), the field, and the valid choices, so that the CLI can print it on one line.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from pathlib import Path


class UrpcError(Exception):
    """Base class of every error urpc raises on purpose."""


class InputError(UrpcError, ValueError):
    """Bad user input: a file, a field or a value that must be fixed.

    Args:
        message: What is wrong and how to fix it.
        source: The file the input came from, if any.
        field: Dotted path of the offending field inside that file (``links.link2.mass``).
    """

    def __init__(self, message: str, source: str | Path | None = None, field: str | None = None):
        self.source = None if source is None else str(source)
        self.field = field
        self.detail = message
        where = []
        if self.source:
            where.append(self.source)
        if field:
            where.append(f"field '{field}'")
        prefix = ": ".join(where)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class SimulationError(UrpcError, RuntimeError):
    """A simulation that cannot continue (diverged, non-finite state)."""


def no_file(path: str | Path, what: str | None = None) -> str:
    """Why ``path`` cannot be read as a file: ``"<what> is a folder, not a file"`` for a folder,
    ``"<what> is not a regular file (...)"`` for a device, pipe or socket (``/dev/zero`` exists:
    "does not exist" would send the user looking for a typo), else ``"<what> does not exist"``
    (``what`` defaults to nothing, resp. ``"file"``)."""
    path = Path(path).expanduser()
    if path.is_dir():
        return (f"{what} " if what else "") + "is a folder, not a file"
    if path.exists():
        return (f"{what} " if what else "") + "is not a regular file (a device, a pipe or a socket)"
    return f"{what or 'file'} does not exist"


def did_you_mean(name: str, choices: Iterable[str]) -> str:
    """A hint naming the closest valid choice, or listing the valid choices."""
    choices = sorted(choices)
    close = difflib.get_close_matches(name, choices, n=1, cutoff=0.6)
    if close:
        return f"did you mean '{close[0]}'? (valid: {', '.join(choices)})"
    return f"valid: {', '.join(choices) if choices else '(none)'}"
