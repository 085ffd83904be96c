"""Trajectory files: a planner's samples read from CSV or NPZ into a :class:`FileTrajectory`,
checked column by column (:func:`load_samples`).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .errors import InputError, no_file
from .trajectory_samples import FileTrajectory

_NAME = re.compile(r"^(qdd|qd|q)[_\s-]?(\d+)$")


def load_samples(path: str | Path, dof: int | None = None, joint_names=()) -> FileTrajectory:
    """Read a trajectory file: a CSV (a header row ``t, q1..qn[, qd1..qdn[, qdd1..qddn]]``, names
    ``q1``/``q_1``/a joint's name for positions, ``qd1``, ``qdd1`` for derivatives; or no header and
    ``1 + n``, ``1 + 2n`` or ``1 + 3n`` columns) or an NPZ (arrays ``t``, ``q`` and optionally
    ``qd``, ``qdd``).

    Raises:
        InputError: a missing or unreadable file, wrong columns, a non-finite value, times that do
            not increase (the sample is named).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(no_file(path, "trajectory file"), path)
    if path.suffix.lower() == ".npz":
        try:
            with np.load(path, allow_pickle=False) as archive:
                data = {k: archive[k] for k in archive.files}
        except (OSError, ValueError) as exc:
            raise InputError(f"not a readable NPZ file ({exc})", path) from None
        if "t" not in data or "q" not in data:
            raise InputError(
                f"needs arrays 't' and 'q'; found {', '.join(sorted(data)) or 'none'}", path
            )
        q = np.asarray(data["q"], dtype=float)
        q = q[:, None] if q.ndim == 1 else q
        _check_dof(q.shape[1], dof, path)
        return FileTrajectory(data["t"], q, data.get("qd"), data.get("qdd"), source=path)
    if path.suffix.lower() != ".csv":
        raise InputError(f"unknown trajectory file type '{path.suffix}'; valid: .csv, .npz", path)
    text = path.read_text().splitlines()
    rows = [line for line in text if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError("the file has no samples", path)
    first = [cell.strip() for cell in rows[0].split(",")]
    has_header = not _is_number(first[0])
    header_lines = text.index(rows[0]) + 1 if has_header else text.index(rows[0])
    try:
        table = np.array(
            [[float(c) for c in r.split(",")] for r in rows[1 if has_header else 0 :]], ndmin=2
        )
    except ValueError as exc:
        raise InputError(
            f"a value is not a number ({exc}); expected t, q1..qn per row", path
        ) from None
    if table.size == 0:
        raise InputError("the file has a header but no samples", path)
    columns = table.shape[1]
    if has_header:
        if first[0].lower() not in ("t", "time"):
            raise InputError(f"the first column is '{first[0]}'; expected t [s]", path, "t")
        groups: dict[str, list[int]] = {"q": [], "qd": [], "qdd": []}
        names = list(joint_names)
        for index, name in enumerate(first[1:], start=1):
            match = _NAME.match(name.replace(" ", ""))
            if match:
                groups[match.group(1)].append(index)
            elif name in names:
                groups["q"].append(index)
            else:
                raise InputError(
                    f"unknown column '{name}'; expected q1..qn, qd1..qdn, qdd1..qddn or joint names",
                    path,
                    name,
                )
        n = len(groups["q"])
        for kind in ("qd", "qdd"):
            if groups[kind] and len(groups[kind]) != n:
                raise InputError(
                    f"{len(groups[kind])} {kind} columns for {n} q columns", path, kind
                )
        _check_dof(n, dof, path)
        pick = {kind: table[:, idx] if idx else None for kind, idx in groups.items()}
    else:
        n = dof or columns - 1
        if columns not in (1 + n, 1 + 2 * n, 1 + 3 * n):
            raise InputError(
                f"{columns} columns; expected t and {n}, {2 * n} or {3 * n} more", path
            )
        blocks = [table[:, 1 + k * n : 1 + (k + 1) * n] for k in range((columns - 1) // n)]
        pick = {
            "q": blocks[0],
            "qd": blocks[1] if len(blocks) > 1 else None,
            "qdd": blocks[2] if len(blocks) > 2 else None,
        }
    return FileTrajectory(
        table[:, 0], pick["q"], pick["qd"], pick["qdd"], source=path, header_lines=header_lines
    )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_dof(n: int, dof: int | None, path) -> None:
    if dof is not None and n != dof:
        raise InputError(f"{n} joint columns; the robot has {dof} joints", path, "q")
