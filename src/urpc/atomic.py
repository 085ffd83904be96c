"""Atomic writes: a reader (or a crash) never sees a half-written file or folder.

* :func:`replace_file` writes one file through a temporary name in the same folder and an
  atomic rename;
* :func:`write_files` writes a set of files into a folder through a staging folder;
* :func:`check_writable` checks, before any work starts, that a folder can be written.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .errors import InputError

__all__ = ["check_writable", "replace_file", "write_files"]


def replace_file(path: str | Path, write: Callable[[Path], Any]) -> None:
    """Write ``path`` by calling ``write`` on a temporary name next to it, then renaming it into
    place (``os.replace``, atomic): a reader never sees a half-written file, and replacing is
    faster than truncating an existing one. The folder must exist.

    Raises:
        InputError: the file cannot be written (the temporary file is removed).
    """
    path = Path(path)
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        write(partial)
        os.replace(partial, path)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        raise InputError(f"cannot write the file ({exc})", source=path) from None


def check_writable(directory: str | Path) -> Path:
    """Check, without creating anything, that ``directory`` can be written (it exists as a
    writable folder, or its nearest existing ancestor is one); returns it as an absolute path.
    Every command that writes files calls it before any work starts.

    Raises:
        InputError: naming the folder that is in the way.
    """
    directory = Path(directory).expanduser().absolute()
    if directory.exists() and not directory.is_dir():
        raise InputError(
            "exists and is not a folder; give a folder for the outputs", source=directory
        )
    target = directory if directory.exists() else directory.parent
    while not target.exists():
        target = target.parent
    if not target.is_dir() or not os.access(target, os.W_OK | os.X_OK):
        raise InputError(
            f"cannot create the output folder: '{target}' is not a writable folder; choose "
            "another --out",
            source=directory,
        )
    return directory


def write_files(directory: str | Path, writers: Mapping[str, Callable[[Path], None]]) -> Path:
    """Write a set of files into ``directory`` so that a failure leaves no partial file behind.

    ``writers`` maps a relative file name (``"summary.json"``, ``"runs/s1/result.npz"``) to a
    function that writes that file at the path it is given. Every file is first written into a
    staging directory; only when all are written do they move into place: a new ``directory``
    (its parents are created) is the staging directory renamed, an existing one receives each file
    by ``os.replace`` (other files in it are kept).

    Returns:
        The directory.

    Raises:
        InputError: ``directory`` is not a path, is a file, or cannot be created (a file in the
            way, a read-only folder) (:func:`check_writable`).
    """
    if not isinstance(directory, str | Path):
        raise InputError(
            f"expected a directory path (str or Path), got {type(directory).__name__}",
            field="directory",
        )
    check_writable(directory)  # a file in the way is an InputError, not NotADirectoryError
    directory = Path(directory)
    existing = directory.is_dir()
    if existing:
        parent = directory
    else:
        parent = directory.parent
        parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", suffix=".tmp", dir=parent))
    try:
        for name, write in writers.items():
            path = staging / name
            path.parent.mkdir(parents=True, exist_ok=True)
            write(path)
        if not existing:
            os.rename(staging, directory)
            return directory
        for name in writers:
            final = directory / name
            final.parent.mkdir(parents=True, exist_ok=True)
            os.replace(staging / name, final)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    shutil.rmtree(staging, ignore_errors=True)
    return directory
