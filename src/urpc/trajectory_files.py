"""Trajectory files: a planner's samples read from CSV or NPZ into a :class:`FileTrajectory`,
checked column by column (:func:`load_samples`).
"""

from __future__ import annotations

import os
import re
import zipfile
import zlib
from pathlib import Path

import numpy as np

from .errors import InputError, no_file
from .trajectory_samples import FileTrajectory
from .validation import checked_count

_NAME = re.compile(r"^(qdd|qd|q)[_\s-]?(\d+)$")

#: A number as a CSV cell holds it: decimal digits with a '.' point and an optional exponent, or
#: nan/inf (refused later, by line, as not finite). Python's float() also reads '1_0' as 10 and
#: other scripts' digits: a planner's '1_0' is a typo, not ten.
_NUMBER = re.compile(
    r"^[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|nan|inf|infinity)$", re.IGNORECASE
)


def load_samples(path: str | Path, dof: int | None = None, joint_names=()) -> FileTrajectory:
    """Read a trajectory file: a CSV (a header row ``t, q1..qn[, qd1..qdn[, qdd1..qddn]]``, names
    ``q1``/``q_1``/a joint's name for positions, ``qd1``, ``qdd1`` for derivatives, in any order
    after ``t``, each joint once; or no header and ``1 + n``, ``1 + 2n`` or ``1 + 3n`` columns) or
    an NPZ (arrays ``t``, ``q`` and optionally ``qd``, ``qdd``, each ``(samples, joints)``).

    ``dof``: the joints expected (an integer >= 1; ``None``: as many as the file has);
    ``joint_names``: the joints' names a header may use (``None``: none).

    Raises:
        InputError: a missing or unreadable file, wrong or repeated columns, a row with too many
            or too few values, a non-finite value, times that do not increase (the sample, and in
            a CSV the line, is named); a path, ``dof`` or names of the wrong type.
    """
    if not isinstance(path, str | os.PathLike):
        raise InputError(
            f"expected a file path (str or pathlib.Path), got {type(path).__name__}", field="path"
        )
    if dof is not None:
        dof = checked_count("dof", dof, 1, " (the robot's joints; None: the file's)")
    names = [] if joint_names is None else _iterable(joint_names)
    if isinstance(joint_names, str | bytes) or not all(isinstance(n, str) for n in names):
        raise InputError(
            f"{joint_names!r:.80} is not a list of joint names (texts); give robot.joint_names "
            "or None",
            field="joint_names",
        )
    joint_names = tuple(names)
    path = Path(path)
    if not path.is_file():
        raise InputError(no_file(path, "trajectory file"), path)
    if path.suffix.lower() == ".npz":
        return _load_npz(path, dof)
    if path.suffix.lower() != ".csv":
        raise InputError(f"unknown trajectory file type '{path.suffix}'; valid: .csv, .npz", path)
    return _load_csv(path, dof, joint_names)


def _iterable(values) -> list:
    """``values`` as a list, or ``[None]`` (not a name) when it cannot be iterated."""
    try:
        return list(values)
    except TypeError:
        return [None]


# ============================================================================ NPZ
def _load_npz(path: Path, dof: int | None) -> FileTrajectory:
    if not zipfile.is_zipfile(path):
        raise InputError(
            "not a readable NPZ file (not a zip archive); save it with numpy.savez(path, t=..., "
            "q=...)",
            path,
        )
    try:
        with zipfile.ZipFile(path) as archive:
            names = archive.namelist()
            data = {}
            for key in _ARRAYS:
                member = next((m for m in (f"{key}.npy", key) if m in names), None)
                if member is not None:
                    with archive.open(member) as stream:
                        size = archive.getinfo(member).file_size
                        data[key] = _read_member(stream, size, key, member, path)
    except (OSError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise InputError(f"not a readable NPZ file ({exc})", path) from None
    if "t" not in data or "q" not in data:
        found = sorted(name.removesuffix(".npy") for name in names)
        raise InputError(f"needs arrays 't' and 'q'; found {', '.join(found) or 'none'}", path)
    t = _numbers(data["t"], "t", path)
    if t.ndim == 2 and t.shape[1] == 1:
        t = t[:, 0]
    if t.ndim != 1:
        raise InputError(
            f"array 't' has shape {_shape(t)}; expected (samples,), one time per sample", path, "t"
        )
    samples = len(t)
    q = _numbers(data["q"], "q", path)
    joints = dof if dof is not None else (q.shape[1] if q.ndim == 2 else 1)
    q = q[:, None] if q.ndim == 1 and joints == 1 else q
    _check_shape(q, "q", samples, joints, path)
    _check_dof(q.shape[1], dof, path)
    derivatives = {}
    for key in ("qd", "qdd"):
        if key in data:
            values = _numbers(data[key], key, path)
            values = values[:, None] if values.ndim == 1 and q.shape[1] == 1 else values
            _check_shape(values, key, samples, q.shape[1], path)
            derivatives[key] = values
    if "qdd" in derivatives and "qd" not in derivatives:
        raise InputError("array 'qdd' needs array 'qd' too", path, "qdd")
    return FileTrajectory(t, q, derivatives.get("qd"), derivatives.get("qdd"), source=path)


#: The arrays an NPZ trajectory is read from (others in the file are not read).
_ARRAYS = ("t", "q", "qd", "qdd")

#: Most samples (rows) read from an NPZ array: 2.8 h at 1 kHz. The .npy header is read first, so
#: a larger declaration is refused before its memory is asked for.
MAX_SAMPLES = 10**7

#: Most values read from one NPZ array (800 MB of doubles: 10^7 samples of 10 joints).
MAX_VALUES = 10**8


def _read_member(stream, size: int, key: str, member: str, path: Path) -> np.ndarray:
    """The array in the NPZ's member ``member`` (``size`` bytes uncompressed), its .npy header
    checked before any data is read: text or other bytes saved under ``t.npy`` are no array, and
    a header may declare more samples than the file holds, or than memory does."""
    what = f"array '{key}' (member {member})"
    try:
        version = np.lib.format.read_magic(stream)
    except ValueError:
        raise InputError(
            f"{what} is not a numpy array: it does not start with the .npy header; save the "
            "file with numpy.savez(path, t=..., q=...)",
            path,
            key,
        ) from None
    readers = {
        (1, 0): np.lib.format.read_array_header_1_0,
        (2, 0): np.lib.format.read_array_header_2_0,
    }
    if version not in readers:
        raise InputError(
            f"{what} is a .npy file of version {version[0]}.{version[1]}; valid: 1.0, 2.0 "
            "(what numpy.savez writes for arrays of numbers)",
            path,
            key,
        )
    try:
        shape, fortran_order, dtype = readers[version](stream)
    except ValueError as exc:
        raise InputError(f"{what} has a damaged .npy header ({exc})", path, key) from None
    if dtype.kind not in "biuf":
        raise InputError(_not_numbers(key, dtype), path, key)
    samples = shape[0] if shape else 1
    values = int(np.prod(shape, dtype=object))
    if samples > MAX_SAMPLES or values > MAX_VALUES:
        raise InputError(
            f"{what} declares shape {tuple(shape)}: {samples} samples, {values} values; at most "
            f"{MAX_SAMPLES} samples and {MAX_VALUES} values are read: split the trajectory",
            path,
            key,
        )
    needed, held = values * dtype.itemsize, size - stream.tell()
    if needed != held:
        raise InputError(
            f"{what} declares shape {tuple(shape)} of {dtype.name} ({needed} bytes), but holds "
            f"{held} bytes: the file is damaged or truncated",
            path,
            key,
        )
    data = stream.read(needed)
    if len(data) != needed:
        raise InputError(f"{what} ends after {len(data)} of {needed} bytes", path, key)
    return np.frombuffer(data, dtype).reshape(shape, order="F" if fortran_order else "C")


def _not_numbers(key: str, dtype: np.dtype) -> str:
    return f"array '{key}' holds {dtype.name} values (dtype {dtype.str}); expected numbers"


def _shape(values: np.ndarray) -> str:
    return str(tuple(values.shape))


def _numbers(values: np.ndarray, key: str, path: Path) -> np.ndarray:
    """``values`` as floats, or an error naming the array and what it holds."""
    if values.dtype.kind not in "biuf":
        raise InputError(_not_numbers(key, values.dtype), path, key)
    return np.asarray(values, dtype=float)


def _check_shape(values: np.ndarray, key: str, samples: int, joints: int | None, path) -> None:
    expected = f"({samples}, {joints if joints is not None else 'joints'})"
    if (
        values.ndim != 2
        or values.shape[0] != samples
        or (joints is not None and values.shape[1] != joints)
    ):
        raise InputError(
            f"array '{key}' has shape {_shape(values)}; expected (samples x joints) = {expected} "
            f"({samples} samples of 't')",
            path,
            key,
        )


# ============================================================================ CSV
#: Most bytes read from a CSV trajectory: 1.3 million samples of 7 joints written with 18 digits
#: (22 min at 1 kHz), more with fewer digits. Reading parses every value in Python: 7.9 s and
#: 0.69 GB of memory for 122 MB (600 000 such samples) here.
MAX_CSV_BYTES = 2**28


def _load_csv(path: Path, dof: int | None, joint_names) -> FileTrajectory:
    size = path.stat().st_size
    if size > MAX_CSV_BYTES:
        raise InputError(
            f"the file has {size / 1e6:.0f} MB; at most {MAX_CSV_BYTES / 1e6:.0f} MB of CSV are "
            "read: save the samples as .npz (arrays t and q, optional qd and qdd: "
            "numpy.savez(path, t=t, q=q)), or split the trajectory",
            path,
        )
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig").splitlines()
    except UnicodeDecodeError as exc:
        raise InputError(
            f"cannot read the file as UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
            f"{exc.start}); save it as a UTF-8 CSV",
            path,
        ) from None
    rows = [
        (number, line)
        for number, line in enumerate(text, start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not rows:
        raise InputError("the file has no samples", path)
    first = [cell.strip() for cell in rows[0][1].split(",")]
    for separator, name in ((";", "semicolons"), ("\t", "tabs")):
        if separator in rows[0][1] and (separator == ";" or len(first) == 1):
            raise InputError(
                f"line {rows[0][0]} separates its values with {name}; a trajectory CSV is "
                "comma-separated, with '.' as the decimal point (t,q1,q2 then 0.1,0.25,-0.5)",
                path,
            )
    has_header = not _is_number(first[0])
    body = rows[1:] if has_header else rows
    if not body:
        raise InputError("the file has a header but no samples", path)
    width = len(first)
    table = np.empty((len(body), width))
    for i, (number, line) in enumerate(body):
        cells = [cell.strip() for cell in line.split(",")]
        if len(cells) != width:
            what = "the header has" if has_header else "the first row has"
            raise InputError(f"line {number} has {len(cells)} values; {what} {width} columns", path)
        for j, cell in enumerate(cells):
            if not _NUMBER.match(cell):
                column = f"'{first[j]}'" if has_header else str(j + 1)
                raise InputError(
                    f"line {number}, column {column}: '{cell}' is not a number (write digits "
                    "with a '.' decimal point and an optional exponent, e.g. -0.25 or 1e-3; no "
                    "'_' or ';')",
                    path,
                )
            table[i, j] = float(cell)
    columns = table.shape[1]
    if has_header:
        pick = _columns_by_name(first, table, dof, tuple(joint_names), path)
    else:
        n = dof or columns - 1
        if n < 1 or columns not in (1 + n, 1 + 2 * n, 1 + 3 * n):
            raise InputError(
                f"{columns} columns; expected t and {n}, {2 * n} or {3 * n} more", path
            )
        blocks = [table[:, 1 + k * n : 1 + (k + 1) * n] for k in range((columns - 1) // n)]
        pick = {
            "q": blocks[0],
            "qd": blocks[1] if len(blocks) > 1 else None,
            "qdd": blocks[2] if len(blocks) > 2 else None,
        }
    # each sample's own line: comment and blank lines between samples are skipped, so a row's
    # index plus the header's lines would name the wrong one
    return FileTrajectory(
        table[:, 0],
        pick["q"],
        pick["qd"],
        pick["qdd"],
        source=path,
        lines=[number for number, _ in body],
    )


def _columns_by_name(header, table, dof, joint_names, path) -> dict:
    """The ``q``, ``qd``, ``qdd`` blocks of ``table`` by the header's names, in joint order:
    ``q1..qn`` (or ``q0..q(n-1)``, or the joints' names), ``qd1..``, ``qdd1..``; an unknown or
    repeated name is an error listing the valid ones."""
    if header[0].lower() not in ("t", "time"):
        raise InputError(
            f"the first column is '{header[0]}'; expected 't' or 'time' (the times in seconds, "
            "with no unit in the name)",
            path,
            "t",
        )
    names = list(joint_names) if dof is None or len(joint_names) == dof else []
    parsed = []  # (column, name, kind, number or joint name)
    for column, name in enumerate(header[1:], start=1):
        match = _NAME.match(name.replace(" ", ""))
        if match:
            parsed.append((column, name, match.group(1), int(match.group(2))))
        elif name in names:
            parsed.append((column, name, "q", name))
        else:
            parsed.append((column, name, None, None))
    numbers = [p[3] for p in parsed if isinstance(p[3], int)]
    base = 0 if 0 in numbers else 1
    count = dof
    if count is None:
        count = sum(1 for p in parsed if p[2] == "q") or 1
    valid = (
        [f"q{k + base}" for k in range(count)]
        + names
        + [f"qd{k + base}" for k in range(count)]
        + [f"qdd{k + base}" for k in range(count)]
    )
    groups: dict[str, dict[int, tuple[int, str]]] = {"q": {}, "qd": {}, "qdd": {}}
    for column, name, kind, key in parsed:
        joint = names.index(key) if isinstance(key, str) else None
        if isinstance(key, int) and base <= key < base + count:
            joint = key - base
        if kind is None or joint is None:
            raise InputError(
                f"unknown column '{name}' (column {column + 1}); valid: t, {', '.join(valid)}",
                path,
                name,
            )
        if joint in groups[kind]:
            other_column, other = groups[kind][joint]
            raise InputError(
                f"column '{name}' (column {column + 1}) repeats joint {joint + 1}, already given "
                f"by '{other}' (column {other_column + 1}); give each joint once",
                path,
                name,
            )
        groups[kind][joint] = (column, name)
    n = len(groups["q"])
    if n == 0:
        raise InputError(f"no joint position columns; valid: t, {', '.join(valid)}", path, "q")
    _check_dof(n, dof, path)
    for kind in ("q", "qd", "qdd"):
        found = groups[kind]
        if found and len(found) != count:
            missing = [f"{kind}{k + base}" for k in range(count) if k not in found]
            raise InputError(
                f"{len(found)} {kind} columns for {count} joints: missing {', '.join(missing)}",
                path,
                kind,
            )
    if groups["qdd"] and not groups["qd"]:
        raise InputError("qdd columns need qd columns too", path, "qdd")
    return {
        kind: table[:, [found[k][0] for k in range(count)]] if found else None
        for kind, found in groups.items()
    }


def _is_number(text: str) -> bool:
    """Whether the first row starts with a number, so has no header: Python's float(), broader
    than :data:`_NUMBER`, so that a first row of '1_0' is a row whose value is refused, not a
    header whose name is."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_dof(n: int, dof: int | None, path) -> None:
    if dof is not None and n != dof:
        raise InputError(f"{n} joint columns; the robot has {dof} joints", path, "q")
