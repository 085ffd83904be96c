"""Recorded samples for identification: reading CSV/NPZ files, and derivatives estimated from
positions with a stated error bound.

A data file has one row (CSV) or one array entry (NPZ) per sample with the columns

* ``t`` [s];
* ``q1..qn`` [rad or m], the robot's joints in its joint order (``urpc check ROBOT`` lists it);
* ``tau1..taun`` [N m or N], the joint torques (measured or commanded);
* optionally ``qd1..qdn`` [rad/s] and ``qdd1..qddn`` [rad/s^2].

**Derivatives estimated from positions.** Without ``qd``/``qdd`` columns they are estimated by
central differences on the uniform sample grid (step ``h``)::

    qd_k  ~ (q_{k+1} - q_{k-1}) / (2 h)           |error| <= h^2 J / 6  + eps / h
    qdd_k ~ (q_{k+1} - 2 q_k + q_{k-1}) / h^2     |error| <= h^2 S / 12 + 4 eps / h^2

(Taylor's theorem with the Lagrange remainder), where ``J`` bounds ``|q'''|`` [rad/s^3], ``S``
bounds ``|q''''|`` [rad/s^4] over the record and ``eps`` bounds the position error [rad]. With
``qd`` recorded and ``qdd`` not, ``qdd`` is the central difference of ``qd``, with error
``h^2 S / 6 + eps_v / h`` (``eps_v``: the velocity error). The first and last samples are dropped
(no central difference there). These errors are turned into a torque bound per sample and joint
by :mod:`urpc.identify.problem` and added to the torque noise: the identified box stays sound
provided ``J``, ``S`` and ``eps`` are true bounds. They are the user's to state; for a trajectory
written by ``urpc identify --excite`` they are computed exactly from its Fourier series.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import InputError


@dataclass(frozen=True)
class Samples:
    """Samples of one or more records, stacked.

    Attributes:
        t: ``(K,)`` times [s].
        q, qd, qdd, tau: ``(K, n)`` positions, velocities, accelerations and torques.
        velocity_error, acceleration_error: ``(K, n)`` bounds of ``|qd - qd_true|`` and
            ``|qdd - qdd_true|`` (zero when the file gives them and they are taken as exact).
        source: Where the samples came from (file names), for messages.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    velocity_error: np.ndarray
    acceleration_error: np.ndarray
    source: str = "<samples>"

    @property
    def count(self) -> int:
        return int(self.t.shape[0])

    @property
    def dof(self) -> int:
        return int(self.q.shape[1])

    @property
    def estimated(self) -> bool:
        """Whether any derivative carries an estimation error."""
        return bool(np.any(self.velocity_error) or np.any(self.acceleration_error))

    @classmethod
    def from_arrays(cls, t, q, qd, qdd, tau, source: str = "<samples>") -> Samples:
        """Samples with exactly known derivatives (checked: shapes and finiteness)."""
        arrays = {"t": t, "q": q, "qd": qd, "qdd": qdd, "tau": tau}
        arrays = {k: np.asarray(v, dtype=float) for k, v in arrays.items()}
        arrays["t"] = arrays["t"].reshape(-1)
        count = arrays["t"].shape[0]
        for name in ("q", "qd", "qdd", "tau"):
            value = arrays[name]
            if value.ndim == 1:
                value = arrays[name] = value.reshape(count, -1)
            if value.shape != arrays["q"].shape or value.shape[0] != count:
                raise InputError(
                    f"{name} has shape {value.shape}, expected ({count}, {arrays['q'].shape[1]})",
                    source=source,
                    field=name,
                )
        for name, value in arrays.items():
            _check_finite(value, source, name)
        zero = np.zeros_like(arrays["q"])
        return cls(**arrays, velocity_error=zero, acceleration_error=zero.copy(), source=source)

    def concatenated(self, other: Samples) -> Samples:
        """These samples followed by ``other``'s (records identified together)."""
        if other.dof != self.dof:
            raise InputError(
                f"has {other.dof} joints, the other records {self.dof}", source=other.source
            )
        fields = ("t", "q", "qd", "qdd", "tau", "velocity_error", "acceleration_error")
        stacked = {f: np.concatenate([getattr(self, f), getattr(other, f)]) for f in fields}
        return Samples(**stacked, source=f"{self.source}, {other.source}")

    def subset(self, index: np.ndarray) -> Samples:
        fields = ("t", "q", "qd", "qdd", "tau", "velocity_error", "acceleration_error")
        return replace(self, **{f: getattr(self, f)[index] for f in fields})


@dataclass(frozen=True)
class DerivativeBounds:
    """What bounds the error of derivatives estimated from positions (module docstring).

    Attributes:
        jerk: Bound ``J`` of ``|q'''|`` over the record [rad/s^3] (``None``: not given).
        snap: Bound ``S`` of ``|q''''|`` [rad/s^4] (``None``: not given).
        position_error: Bound of the position error [rad] (0: exact positions).
        velocity_error: Bound of the recorded velocity's error [rad/s], when ``qd`` is recorded.
    """

    jerk: float | None = None
    snap: float | None = None
    position_error: float = 0.0
    velocity_error: float = 0.0

    def __post_init__(self) -> None:
        for name in ("jerk", "snap", "position_error", "velocity_error"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value >= 0):
                raise InputError(f"{value!r} must be a finite number >= 0", field=name)


def load_samples(
    paths, dof: int, bounds: DerivativeBounds | None = None, joint_names=None
) -> Samples:
    """Read one or more data files (CSV or NPZ, module docstring) for a robot of ``dof`` joints,
    estimate missing derivatives, and stack them.

    Raises:
        InputError: a missing file or column, a wrong joint count, a NaN or infinite value, a
            non-increasing or non-uniform time column (when derivatives are estimated), missing
            derivative bounds; naming the file and the column.
    """
    if isinstance(paths, str | Path):
        paths = [paths]
    paths = [Path(p) for p in paths]
    if not paths:
        raise InputError("give at least one data file", field="data")
    bounds = bounds or DerivativeBounds()
    samples = None
    for path in paths:
        record = _record(path, dof, bounds, joint_names)
        samples = record if samples is None else samples.concatenated(record)
    return samples


def _record(path: Path, dof: int, bounds: DerivativeBounds, joint_names) -> Samples:
    columns = read_columns(path)
    source = str(path)
    names = f" ({', '.join(joint_names)})" if joint_names else ""
    for base in ("q", "tau"):
        extra = f"{base}{dof + 1}"
        if extra in columns:
            raise InputError(
                f"has a column '{extra}', but the robot has {dof} joints{names}: the columns "
                f"must be {base}1..{base}{dof} in the robot's joint order",
                source=source,
                field=extra,
            )
    if "t" not in columns:
        raise InputError(_missing("t", columns), source=source, field="t")
    t = columns["t"]
    q = _block(columns, "q", dof, source, names)
    tau = _block(columns, "tau", dof, source, names)
    has_qd = any(f"qd{i}" in columns for i in range(1, dof + 1))
    has_qdd = any(f"qdd{i}" in columns for i in range(1, dof + 1))
    if has_qdd and not has_qd:
        raise InputError(
            "has qdd columns but no qd columns: give both, qd only, or neither (then both are "
            "estimated from q)",
            source=source,
            field="qd1",
        )
    qd = _block(columns, "qd", dof, source, names) if has_qd else None
    qdd = _block(columns, "qdd", dof, source, names) if has_qdd else None
    if t.shape[0] < 1:
        raise InputError("has no samples", source=source, field="t")
    zero = np.zeros_like(q)
    if qd is not None and qdd is not None:
        velocity_error = np.full_like(q, bounds.velocity_error)
        return Samples(t, q, qd, qdd, tau, velocity_error, zero.copy(), source)
    return _estimated(source, t, q, qd, tau, bounds)


def _estimated(source, t, q, qd, tau, bounds: DerivativeBounds) -> Samples:
    """Central differences (module docstring) with their error bounds; drops the end samples."""
    what = "qdd" if qd is not None else "qd and qdd"
    if t.shape[0] < 3:
        raise InputError(
            f"{what} are estimated from the samples, which needs at least 3 samples",
            source=source,
            field="t",
        )
    steps = np.diff(t)
    h = float(np.mean(steps))
    if not h > 0 or np.any(steps <= 0):
        raise InputError("t must increase from sample to sample", source=source, field="t")
    if np.max(np.abs(steps - h)) > 1e-6 * h:
        raise InputError(
            f"{what} are estimated by central differences, which need a uniform time step; "
            f"the steps range from {steps.min():.6g} to {steps.max():.6g} s: resample the record "
            "or record qd and qdd",
            source=source,
            field="t",
        )
    missing = [name for name in ("jerk", "snap") if getattr(bounds, name) is None]
    if missing:
        options = " and ".join(f"--{name}-bound" for name in missing)
        raise InputError(
            f"the file has no {what} columns, so they are estimated from "
            f"{'qd' if qd is not None else 'q'}, whose error must be bounded: give {options} "
            "(bounds of |q'''| [rad/s^3] and |q''''| [rad/s^4] over the record), or record "
            "qd1..qdn and qdd1..qddn",
            source=source,
            field="qd1" if qd is None else "qdd1",
        )
    J, S, eps = bounds.jerk, bounds.snap, bounds.position_error
    inner = slice(1, -1)
    if qd is None:
        qd_est = (q[2:] - q[:-2]) / (2 * h)
        qdd_est = (q[2:] - 2 * q[1:-1] + q[:-2]) / (h * h)
        v_err = h * h * J / 6 + eps / h
        a_err = h * h * S / 12 + 4 * eps / (h * h)
    else:
        qd_est = qd[inner]
        qdd_est = (qd[2:] - qd[:-2]) / (2 * h)
        v_err = bounds.velocity_error
        a_err = h * h * S / 6 + bounds.velocity_error / h
    # Outward for the rounding of the differences themselves (a few ulps of the terms).
    ulp = 4 * np.finfo(float).eps
    scale = np.max(np.abs(q if qd is None else qd), axis=0)
    v_err = v_err + (ulp * scale / h if qd is None else 0.0)
    a_err = a_err + ulp * 4 * scale / (h * h if qd is None else h)
    shape = qd_est.shape
    return Samples(
        t[inner],
        q[inner],
        qd_est,
        qdd_est,
        tau[inner],
        np.broadcast_to(v_err, shape).astype(float),
        np.broadcast_to(a_err, shape).astype(float),
        source,
    )


def read_columns(path: Path) -> dict[str, np.ndarray]:
    """The named columns of a CSV (header row, comma separated, ``#`` comments) or NPZ file."""
    source = str(path)
    if not path.exists():
        raise InputError("file does not exist", source=source)
    if path.is_dir():
        raise InputError("is a folder; give a CSV or NPZ data file", source=source)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as archive:
                columns = {k: np.asarray(archive[k]) for k in archive.files}
        except (OSError, ValueError) as exc:
            raise InputError(f"cannot read the NPZ file ({exc})", source=source) from None
        return {k: _numeric(v, source, k).reshape(-1) for k, v in columns.items()}
    if suffix not in (".csv", ".txt"):
        raise InputError(
            f"unknown data file type '{path.suffix}'; valid: .csv, .npz", source=source
        )
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            rows = [row for row in csv.reader(stream) if row and not row[0].startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the CSV file ({exc})", source=source) from None
    if not rows:
        raise InputError("is empty: expected a header row t,q1,...,tau1,...", source=source)
    header = [name.strip() for name in rows[0]]
    duplicates = sorted({n for n in header if header.count(n) > 1})
    if duplicates:
        raise InputError(
            f"column '{duplicates[0]}' appears twice", source=source, field=duplicates[0]
        )
    values = np.full((len(rows) - 1, len(header)), np.nan)
    for r, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise InputError(
                f"line {r} has {len(row)} values, the header {len(header)} columns",
                source=source,
            )
        for c, text in enumerate(row):
            try:
                values[r - 2, c] = float(text)
            except ValueError:
                raise InputError(
                    f"line {r}: '{text.strip()}' is not a number", source=source, field=header[c]
                ) from None
    return {name: values[:, c] for c, name in enumerate(header)}


def _numeric(value: np.ndarray, source: str, name: str) -> np.ndarray:
    if not np.issubdtype(value.dtype, np.number):
        raise InputError(f"is not numeric (dtype {value.dtype})", source=source, field=name)
    return value.astype(float)


def _block(columns, base: str, dof: int, source: str, names: str) -> np.ndarray:
    keys = [f"{base}{i}" for i in range(1, dof + 1)]
    for key in keys:
        if key not in columns:
            raise InputError(
                _missing(key, columns) + f"; the robot has {dof} joints{names}, so the file "
                f"needs {keys[0]}..{keys[-1]}",
                source=source,
                field=key,
            )
    block = np.column_stack([columns[k] for k in keys])
    for k, key in enumerate(keys):
        _check_finite(block[:, k], source, key)
    return block


def _check_finite(value: np.ndarray, source: str, name: str) -> None:
    bad = ~np.isfinite(value)
    if bad.any():
        index = np.argwhere(bad)[0]
        raise InputError(
            f"sample {int(index[0])} is {value[tuple(index)]}: every value must be finite "
            "(drop or repair the sample)",
            source=source,
            field=name,
        )


def _missing(key: str, columns) -> str:
    present = ", ".join(sorted(columns)) if columns else "(none)"
    return f"missing column '{key}' (the file has: {present})"


def write_csv(path: Path, columns: dict[str, np.ndarray], comments: list[str] = ()) -> str:
    """The CSV text of named columns (``%.17g``: round-trips exactly), ``#`` comment lines first."""
    names = list(columns)
    matrix = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    lines = [f"# {c}" for c in comments]
    lines.append(",".join(names))
    lines += [",".join(f"{v:.17g}" for v in row) for row in matrix]
    return "\n".join(lines) + "\n"
