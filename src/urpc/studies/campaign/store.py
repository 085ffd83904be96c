"""The campaign's record of runs: an append-only SQLite file (``DIR/runs.sqlite``), one row per
finished run, committed as the run finishes, so that an interrupted or killed campaign keeps every
finished run and can resume.

* **Append-only, committed per run.** SQLite in WAL mode with ``synchronous=FULL``: a run's row is
  either committed whole or absent, whatever happens to the process (SIGKILL included); a
  ``runs.sqlite-wal`` file beside it after a kill is part of the database (SQLite folds it back on
  the next open), not a scratch file.
* **Exact.** A row holds the run's draws and metrics as JSON, whose floats are the shortest text
  that reads back to the same double: a campaign built from its records is bit-identical to the
  one that produced them.
* **Settings.** The first row of ``settings`` holds what determines the runs (the scenario's
  document, seed, run count, initial spread, vertex runs, urpc's version); ``--resume`` continues
  only a campaign with the same settings and names what differs otherwise.
* **Replacing.** A new campaign on a folder whose campaign finished (its outputs written)
  replaces it, as any new run replaces earlier outputs; an interrupted one (even with every run
  recorded, killed before its outputs) is kept until it is resumed or deleted.
* **One campaign per folder.** ``DIR/campaign.lock`` is held with ``fcntl.flock`` while the
  campaign runs (the kernel releases it when the process dies, even by SIGKILL); a second
  campaign on the same folder is refused at start, naming the folder.
"""

from __future__ import annotations

import json
import math
import os
import sqlite3
import warnings
from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError
from .draws import RunSpec
from .worker import RunOutcome

#: File names in the campaign folder.
STORE_NAME, LOCK_NAME = "runs.sqlite", "campaign.lock"
#: Version of the record layout (a change refuses to resume older records).
FORMAT = 1

try:  # POSIX; elsewhere the folder is not locked (documented)
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]


class CampaignStore:
    """The records of one campaign folder, opened and locked by :meth:`open`."""

    def __init__(self, directory: Path, connection: sqlite3.Connection, lock: int):
        self.directory = directory
        self.path = directory / STORE_NAME
        self._connection = connection
        self._lock = lock
        self._created: list[Path] = []

    @classmethod
    def open(cls, directory: str | Path, settings: Mapping[str, Any], *, resume: bool):
        """Lock ``directory`` (created if missing) and open its records for a campaign of
        ``settings``.

        Raises:
            InputError: the folder is in use by another campaign; it holds records of a campaign
                and ``resume`` is false; ``resume`` with records of other settings (names them);
                the records cannot be read.
        """
        directory = Path(directory)
        created = [
            p for p in (directory, directory / LOCK_NAME, directory / STORE_NAME) if not p.exists()
        ]
        try:
            directory.mkdir(parents=True, exist_ok=True)
            lock = os.open(directory / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise InputError(
                f"cannot create the campaign folder ({exc.strerror}); choose another --out",
                source=directory,
            ) from None
        try:
            if fcntl is not None:
                try:
                    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    raise InputError(
                        f"the folder is in use by another campaign (it holds the lock "
                        f"{LOCK_NAME}); wait for it to finish, or give another --out",
                        source=directory,
                    ) from None
            connection = _connect(directory / STORE_NAME)
            store = cls(directory, connection, lock)
            store._created = created
            store._start(dict(settings), resume)
            return store
        except BaseException:
            os.close(lock)
            raise

    def _start(self, settings: dict[str, Any], resume: bool) -> None:
        text = json.dumps(settings, sort_keys=True)
        row = self._query("SELECT value FROM settings WHERE key = 'campaign'").fetchone()
        done = self.count()
        recorded = _runs(row[0]) if row is not None else 0
        finished = self._query("SELECT 1 FROM settings WHERE key = 'finished'").fetchone()
        # Nothing recorded yet, or a finished campaign (its outputs written) that a new one
        # replaces, as a new run replaces any output: (re)start with these settings.
        if row is None or done == 0 or (finished is not None and not resume):
            if resume:  # asked to continue, and there is nothing to continue: say so
                warnings.warn(
                    f"{self.directory}: nothing to resume (no run recorded in {STORE_NAME}); "
                    "starting the campaign from its first run",
                    stacklevel=3,
                )
            with self._connection:
                self._connection.execute("DELETE FROM runs")
                self._connection.execute("DELETE FROM settings WHERE key = 'finished'")
                self._connection.execute(
                    "INSERT OR REPLACE INTO settings VALUES ('campaign', ?)", (text,)
                )
            return
        if not resume:
            raise InputError(
                f"holds an interrupted campaign ({done} of {recorded} runs recorded in "
                f"{STORE_NAME}); add --resume to continue it, give another --out, or delete "
                f"{STORE_NAME} to start over",
                source=self.directory,
            )
        stored = json.loads(row[0])
        differences = _differences(stored, json.loads(text))
        if differences:
            raise InputError(
                "cannot resume: the campaign recorded here has other settings ("
                + "; ".join(differences)
                + "); resume with the recorded settings, or give another --out",
                source=self.directory,
            )

    def mark_finished(self) -> None:
        """Record that the campaign's outputs are written (a new campaign may then replace it)."""
        with self._connection:
            self._connection.execute("INSERT OR REPLACE INTO settings VALUES ('finished', '1')")

    def count(self) -> int:
        return int(self._query("SELECT COUNT(*) FROM runs").fetchone()[0])

    def add(self, outcome: RunOutcome) -> None:
        """Record one finished run (committed before this returns)."""
        with self._connection:
            self._connection.execute(
                "INSERT INTO runs VALUES (?, ?)", (outcome.spec.index, _dump(outcome))
            )

    def outcomes(self) -> dict[int, RunOutcome]:
        """The recorded runs by index."""
        rows = self._query("SELECT run, record FROM runs ORDER BY run").fetchall()
        try:
            return {int(index): _load(text) for index, text in rows}
        except (ValueError, KeyError, TypeError) as exc:
            raise InputError(
                f"a record of {STORE_NAME} cannot be read ({exc}); delete it to start over",
                source=self.directory,
            ) from None

    def discard(self) -> None:
        """Close, and remove what :meth:`open` created if no run was recorded (a campaign that
        failed before its first run leaves the folder as it found it)."""
        empty = self.count() == 0
        self.close()
        if not empty:
            return
        for path in reversed(self._created):
            try:
                path.rmdir() if path == self.directory else path.unlink()
            except OSError:
                pass

    def close(self) -> None:
        """Close the records (folding the WAL back into the file) and release the lock."""
        try:
            self._connection.close()
        finally:
            os.close(self._lock)

    def __enter__(self) -> CampaignStore:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def _query(self, sql: str):
        try:
            return self._connection.execute(sql)
        except sqlite3.DatabaseError as exc:
            raise InputError(
                f"{STORE_NAME} is not a campaign record ({exc}); delete it to start over",
                source=self.directory,
            ) from None


def _connect(path: Path) -> sqlite3.Connection:
    try:
        connection = sqlite3.connect(path)
        connection.execute("PRAGMA journal_mode=WAL")
        connection.execute("PRAGMA synchronous=FULL")
        with connection:
            connection.execute(
                "CREATE TABLE IF NOT EXISTS settings (key TEXT PRIMARY KEY, value TEXT NOT NULL)"
            )
            connection.execute(
                "CREATE TABLE IF NOT EXISTS runs (run INTEGER PRIMARY KEY, record TEXT NOT NULL)"
            )
    except sqlite3.DatabaseError as exc:
        raise InputError(
            f"{path.name} is not a campaign record ({exc}); delete it to start over",
            source=path.parent,
        ) from None
    return connection


def _runs(text: str) -> Any:
    try:
        return json.loads(text).get("runs", "?")
    except (ValueError, AttributeError):
        return "?"


def _differences(stored: Mapping[str, Any], given: Mapping[str, Any]) -> list[str]:
    """What differs between two settings, as ``key: recorded X, now Y`` (scenario keys one by
    one)."""
    differences = []
    for key in sorted(set(stored) | set(given)):
        old, new = stored.get(key), given.get(key)
        if old == new:
            continue
        if key == "scenario" and isinstance(old, Mapping) and isinstance(new, Mapping):
            differences += [
                f"scenario {name}: recorded {_short(old.get(name))}, now {_short(new.get(name))}"
                for name in sorted(set(old) | set(new))
                if old.get(name) != new.get(name)
            ]
        else:
            differences.append(f"{key}: recorded {_short(old)}, now {_short(new)}")
    return differences


def _short(value: Any) -> str:
    if value is None:
        return "not given"
    text = json.dumps(value, sort_keys=True)
    return text if len(text) <= 60 else text[:57] + "..."


def _plain(value: Any) -> Any:
    """JSON-ready data with numpy scalars as Python numbers (floats unchanged bit for bit)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_plain(v) for v in value]
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value)
    return value


def _dump(outcome: RunOutcome) -> str:
    record = {
        "format": FORMAT,
        "spec": _plain(asdict(outcome.spec)),
        "status": outcome.status,
        "metrics": _plain(outcome.metrics),
        "message": outcome.message,
        "cpu_time": float(outcome.cpu_time),
    }
    return json.dumps(record, allow_nan=True)


def _load(text: str) -> RunOutcome:
    record = json.loads(text)
    if record.get("format") != FORMAT:
        raise ValueError(f"record format {record.get('format')!r}, not {FORMAT}")
    spec = record["spec"]
    spec = RunSpec(
        index=int(spec["index"]),
        kind=spec["kind"],
        vertex=spec["vertex"],
        seed=int(spec["seed"]),
        point={name: tuple(values) for name, values in spec["point"].items()},
        q0=tuple(spec["q0"]),
        qd0=tuple(spec["qd0"]),
        rejected=int(spec["rejected"]),
    )
    cpu_time = record["cpu_time"]
    return RunOutcome(
        spec,
        record["status"],
        record["metrics"],
        record["message"],
        math.nan if cpu_time is None else float(cpu_time),
    )
