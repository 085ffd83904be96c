"""Atomic writes: a reader (or a crash) never sees a half-written file or folder.

* :func:`replace_file` writes one file through a temporary name in the same folder and an
  atomic rename;
* :func:`write_files` writes a set of files into a folder, each through a ``.partial`` name in
  its final folder;
* :func:`check_writable` checks, before any work starts, that a folder can be written.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .errors import InputError

__all__ = ["check_writable", "partial_path", "replace_file", "write_files"]


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
    """Check that ``directory`` can be written, leaving nothing behind: an existing folder
    receives (and loses at once) a probe file, a missing one is created with its missing parents
    and removed again. Trying is the only test that holds everywhere (``os.access`` says yes to
    root in ``/proc`` or on a read-only mount). Returns the folder as an absolute path. Every
    command that writes files calls it before any work starts.

    Raises:
        InputError: naming the folder that is in the way and why.
    """
    directory = Path(directory).expanduser().absolute()
    if directory.exists() and not directory.is_dir():
        raise InputError(
            "exists and is not a folder; give a folder for the outputs", source=directory
        )
    target = directory
    while not target.exists():
        target = target.parent
    if not target.is_dir():
        raise InputError(
            f"cannot create the output folder: '{target}' is not a writable folder; choose "
            "another --out",
            source=directory,
        )
    try:
        if directory.exists():
            handle, probe = tempfile.mkstemp(prefix=".urpc-probe-", dir=directory)
            os.close(handle)
            os.unlink(probe)
        else:
            created: list[Path] = []
            try:
                _make_folders(directory, created)
            finally:
                for folder in reversed(created):
                    folder.rmdir()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InputError(
            f"cannot write the output folder ({reason}); choose another --out", source=directory
        ) from None
    return directory


#: Marker of a file being written by :func:`write_files`: ``NAME.partial.EXT`` (the extension
#: kept for writers that infer the format from it) takes the name ``NAME.EXT`` when complete.
PARTIAL_SUFFIX = ".partial"


def partial_path(final: Path) -> Path:
    """Where :func:`write_files` writes ``final`` until it is complete."""
    return final.with_name(f"{final.stem}{PARTIAL_SUFFIX}{final.suffix}")


def write_files(directory: str | Path, writers: Mapping[str, Callable[[Path], None]]) -> Path:
    """Write a set of files into ``directory`` so that a failure leaves no partial file behind.

    ``writers`` maps a relative file name (``"summary.json"``, ``"runs/s1/result.npz"``) to a
    function that writes that file at the path it is given. Every file is first written under its
    partial name (:func:`partial_path`, ``summary.partial.json``) in its final folder; only when all are written do they
    take their final names (``os.replace``; other files in ``directory`` are kept). An exception
    removes the partial files and the folders this call created; a process killed while writing
    leaves visible ``*.partial.*`` files inside ``directory`` (replaced by the next write), never a
    hidden scratch folder beside it. Folders and files follow the umask.

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
    created: list[Path] = []
    staged: list[tuple[Path, Path]] = []
    try:
        _make_folders(directory, created)
        for name, write in writers.items():
            final = directory / name
            _make_folders(final.parent, created)
            partial = partial_path(final)
            staged.append((partial, final))
            write(partial)
        for partial, final in staged:
            os.replace(partial, final)
    except BaseException:
        for partial, _ in staged:
            partial.unlink(missing_ok=True)
        for folder in reversed(created):
            try:
                folder.rmdir()
            except OSError:
                pass
        raise
    return directory


def _make_folders(folder: Path, created: list[Path]) -> None:
    """Create ``folder`` and its missing parents (mode 0o777 less the umask), appending each
    folder created to ``created``, parents first."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        folder = folder.parent
    for path in reversed(missing):
        path.mkdir(exist_ok=True)
        created.append(path)
