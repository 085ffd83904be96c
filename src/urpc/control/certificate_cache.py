"""Certificates computed once per configuration: a cache on disk, reused by ``urpc simulate``,
``urpc campaign`` and ``urpc certify`` (:func:`cached_certify`).

* **Where.** ``$URPC_CACHE_DIR`` when set, else ``$XDG_CACHE_HOME/urpc``, else
  ``~/.cache/urpc`` (:func:`default_directory`): one SQLite file, ``certificates.sqlite``, in WAL
  mode (readers never wait for a writer; several processes may share it).
* **Key.** The sha256 of everything the certificate depends on
  (:func:`urpc.control.certificate_key.certificate_key`: the code, the robot, the box, the
  controller's law, period, epsilon and gains, the reference, the duration, the disturbance bound
  and the cells). A reference without a fingerprint has no key: computed every time.
* **Record.** The certificate's :meth:`~urpc.control.certificate.Certificate.to_dict`, read back
  exactly by :meth:`~urpc.control.certificate.Certificate.from_dict`, with the time it took, one
  line describing the configuration, the date, urpc's version and
  :data:`~urpc.control.certificate.CERTIFICATE_VERSION`.
* **Never in the way.** A cache that cannot be opened, read or written (a read-only folder, a
  corrupt file, a full disk) never fails a run: one warning per file and process, and the
  certificate is computed. A record that does not read back as a certificate is computed again
  and replaced.
* **Clearing.** Delete the folder, or its ``certificates.sqlite*`` files; nothing else refers to
  them.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import sqlite3
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..trajectories import Trajectory
from . import certificate as certificate_module
from .certificate import CERTIFICATE_VERSION, Certificate
from .certificate_key import NoKey, certificate_key

#: The environment variable that names the cache folder.
CACHE_ENV = "URPC_CACHE_DIR"
#: The cache file in that folder.
FILE_NAME = "certificates.sqlite"
#: Layout of the file (``PRAGMA user_version``); a file of another layout is left alone.
FORMAT = 1
#: Hex digits of the key shown to the user.
SHORT_KEY = 12

#: The cache files already warned about in this process (one warning each).
_warned: set[str] = set()


def default_directory() -> Path:
    """``$URPC_CACHE_DIR``, else ``$XDG_CACHE_HOME/urpc``, else ``~/.cache/urpc``."""
    chosen = os.environ.get(CACHE_ENV)
    if chosen:
        return Path(chosen).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "urpc"


class CertificateCache:
    """The certificates stored in ``directory/certificates.sqlite`` (module docstring).

    Args:
        directory: The cache folder (created when first written); ``None``:
            :func:`default_directory`, read when the cache is made.
    """

    def __init__(self, directory: str | Path | None = None):
        self.directory = default_directory() if directory is None else Path(directory)
        self.path = self.directory / FILE_NAME

    def get(self, key: str) -> Certificate | None:
        """The certificate stored under ``key``, or ``None`` (not stored, or the cache cannot be
        read: warned once)."""
        try:
            with self._connection() as connection:
                row = connection.execute(
                    "SELECT certificate FROM certificates WHERE key = ?", (key,)
                ).fetchone()
        except (OSError, sqlite3.Error) as exc:
            self._warn(exc, "cannot be read")
            return None
        if row is None:
            return None
        try:
            return Certificate.from_dict(json.loads(row[0]))
        except (ValueError, TypeError, InputError) as exc:
            self._warn(exc, f"holds a record that is no certificate (key {key[:SHORT_KEY]})")
            return None

    def put(self, key: str, certificate: Certificate, *, seconds: float, description: str) -> bool:
        """Store ``certificate`` under ``key`` (replacing a record); ``False`` when the cache
        cannot be written (warned once)."""
        from .. import __version__

        record = json.dumps(certificate.to_dict(), allow_nan=False, separators=(",", ":"))
        created = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
        values = (key, CERTIFICATE_VERSION, __version__, created, float(seconds), description)
        try:
            with self._connection() as connection, connection:
                connection.execute(
                    "INSERT OR REPLACE INTO certificates VALUES (?, ?, ?, ?, ?, ?, ?)",
                    (*values, record),
                )
        except (OSError, sqlite3.Error) as exc:
            self._warn(exc, "cannot be written")
            return False
        return True

    def seconds(self, key: str) -> float | None:
        """How long the certificate stored under ``key`` took to compute [s], or ``None``."""
        try:
            with self._connection() as connection:
                row = connection.execute(
                    "SELECT seconds FROM certificates WHERE key = ?", (key,)
                ).fetchone()
        except (OSError, sqlite3.Error):
            return None
        return None if row is None else float(row[0])

    def __len__(self) -> int:
        """The number of stored certificates (0 when the cache cannot be read)."""
        try:
            with self._connection() as connection:
                return int(connection.execute("SELECT COUNT(*) FROM certificates").fetchone()[0])
        except (OSError, sqlite3.Error):
            return 0

    @contextlib.contextmanager
    def _connection(self):
        """An open connection to the file (created with its folder and table if missing)."""
        self.directory.mkdir(parents=True, exist_ok=True)
        connection = sqlite3.connect(self.path, timeout=10.0)
        try:
            connection.execute("PRAGMA journal_mode = WAL")
            connection.execute("PRAGMA synchronous = NORMAL")
            layout = connection.execute("PRAGMA user_version").fetchone()[0]
            if layout == 0:
                with connection:
                    connection.execute(
                        "CREATE TABLE IF NOT EXISTS certificates (key TEXT PRIMARY KEY, "
                        "certificate_version INTEGER NOT NULL, urpc TEXT NOT NULL, "
                        "created TEXT NOT NULL, seconds REAL NOT NULL, "
                        "description TEXT NOT NULL, certificate TEXT NOT NULL)"
                    )
                    connection.execute(f"PRAGMA user_version = {FORMAT}")
            elif layout != FORMAT:
                raise sqlite3.DatabaseError(
                    f"its layout {layout} is not this urpc's {FORMAT}; delete it to start over"
                )
            yield connection
        finally:
            connection.close()

    def _warn(self, exc: BaseException, what: str) -> None:
        reason = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
        if str(self.path) in _warned:
            return
        _warned.add(str(self.path))
        warnings.warn(
            f"the certificate cache {self.path} {what} ({reason}); the certificate is computed "
            f"without it (set {CACHE_ENV} to another folder, or delete this one)",
            stacklevel=3,
        )


@dataclass(frozen=True)
class CachedCertificate:
    """A certificate and where it came from.

    Attributes:
        certificate: The certificate, the same whether computed or read back.
        key: Its key (:func:`~urpc.control.certificate_key.certificate_key`), or ``None`` when
            the configuration has none.
        from_cache: Read from the cache (not computed).
        seconds: Time spent computing it [s]: now, or, read from the cache, when it was stored.
        note: Why it was computed without being stored, or ``None``.
    """

    certificate: Certificate
    key: str | None
    from_cache: bool
    seconds: float
    note: str | None = None

    def describe(self) -> str:
        """One line: ``cached (key 1a2b3c4d5e6f)`` or ``computed in 2.1 s ...``."""
        short = None if self.key is None else self.key[:SHORT_KEY]
        if self.from_cache:
            return f"cached (key {short}; computing it took {self.seconds:.3g} s)"
        text = f"computed in {self.seconds:.3g} s"
        if self.note is not None:
            return f"{text} (not cached: {self.note})"
        if short is None:
            return text
        return f"{text}, cached (key {short})"


def cached_certify(
    controller,
    trajectory: Trajectory,
    *,
    duration: float,
    disturbance_bound: float | None = None,
    cells: int | None = None,
    actuation_delay: int | None = None,
    require_efforts: bool = False,
    progress: Callable[[str], Any] | None = None,
    cache: bool | CertificateCache = True,
    refresh: bool = False,
) -> CachedCertificate:
    """:func:`urpc.control.certificate.certify`, computed once per configuration: read from
    ``cache`` when it holds this configuration's key, else computed and stored.

    Args:
        controller, trajectory, duration, disturbance_bound, cells, actuation_delay,
            require_efforts, progress: As for
            :func:`~urpc.control.certificate.certify`.
        cache: ``True`` for the default folder (:func:`default_directory`), a
            :class:`CertificateCache`, or ``False``: computed, nothing read or written.
        refresh: Compute even when the certificate is cached, and replace the record.

    Raises:
        InputError: as :func:`~urpc.control.certificate.certify` (a bad reference); never for
            the cache itself.
    """
    arguments = {
        "duration": duration,
        "disturbance_bound": disturbance_bound,
        "cells": cells,
        "actuation_delay": actuation_delay,
        "require_efforts": bool(require_efforts),
    }
    store = None
    if cache is True:
        store = CertificateCache()
    elif isinstance(cache, CertificateCache):
        store = cache
    elif cache is not False and cache is not None:
        raise InputError(
            f"{cache!r} is not a cache; give True, False or a CertificateCache", field="cache"
        )
    key, note = None, None
    if store is not None:
        try:
            key = certificate_key(controller, trajectory, **arguments)
        except NoKey as exc:
            note = str(exc)
    if key is not None and not refresh:
        start = time.perf_counter()
        found = store.get(key)
        if found is not None:
            took = store.seconds(key)
            spent = time.perf_counter() - start if took is None else took
            return CachedCertificate(found, key, True, spent)
    start = time.perf_counter()
    # Looked up in its module, so that the certificate computed is always the current one.
    certificate = certificate_module.certify(controller, trajectory, progress=progress, **arguments)
    seconds = time.perf_counter() - start
    if key is not None:
        description = _describe(controller, trajectory, duration, disturbance_bound)
        if not store.put(key, certificate, seconds=seconds, description=description):
            note = "the cache cannot be written"
    return CachedCertificate(certificate, key, False, seconds, note)


def _describe(controller, trajectory: Trajectory, duration: float, disturbance) -> str:
    """One line naming the configuration of a record (for a person reading the file)."""
    period = controller.sample_period
    law = "continuous" if period is None else f"{controller.feedback.name} law, T = {period:g} s"
    d = "the box's" if disturbance is None else f"{float(disturbance):g}"
    return (
        f"{controller.robot.name}: {law}, epsilon = {controller.epsilon:g}, "
        f"{type(trajectory).__name__} over {float(duration):g} s, disturbance {d}"
    )
