"""Checks of arguments at the API boundary (numbers, vectors, a reference's joints): one
:class:`~urpc.errors.InputError` naming the argument, instead of a numpy error (or a silent NaN)
deep inside a simulation or a certificate."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError


def check_type(field: str, value: Any, kind: type | tuple[type, ...], expected: str) -> None:
    """``value`` must be a ``kind``; ``expected`` says what is (e.g. ``"a Robot
    (urpc.load_robot(...))"``).

    Raises:
        InputError: ``expected ..., got <its type>`` (``field`` named).
    """
    if not isinstance(value, kind):
        raise InputError(f"expected {expected}, got {type(value).__name__}", field=field)


def finite_vector(field: str, value: Any, n: int) -> np.ndarray:
    """``value`` as a float vector of ``n`` finite entries.

    Raises:
        InputError: not numbers, another length, or a NaN or infinite entry (``field`` named).
    """
    try:
        vector = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{value!r} is not a vector of {n} numbers", field=field) from None
    if vector.shape != (n,) or not np.isfinite(vector).all():
        raise InputError(f"{value!r} must be {n} finite numbers", field=field)
    return vector


def per_joint(
    field: str, value, n: int | None, unit: str, *, finite: bool = True, broadcast: bool = True
) -> np.ndarray:
    """``value`` as a float vector of ``n`` entries (a scalar is every joint's when
    ``broadcast``; ``n = None``: any length), not NaN, and finite when ``finite``; ``unit``
    completes the messages.

    Raises:
        InputError: not numbers, another length, NaN or (``finite``) infinite entries (``field``
            named).
    """
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(
            f"{value!r} is not a number or a list of numbers [{unit}]", field=field
        ) from None
    if broadcast and array.ndim == 0 and n is not None:
        array = np.full(n, float(array))
    array = array.reshape(-1) if array.ndim == 0 else array
    if array.ndim != 1 or (n is not None and array.shape != (n,)):
        count = "one number per joint" if n is None else f"{n} numbers (one per joint)"
        raise InputError(
            f"{value!r} has shape {array.shape}; it must be {count} [{unit}]", field=field
        )
    bad = np.isnan(array) | (~np.isfinite(array) if finite else False)
    if bad.any():
        kind = "finite" if finite else "numbers (not NaN)"
        raise InputError(f"{array.tolist()}: every entry must be {kind} [{unit}]", field=field)
    return array


def checked_count(name: str, value: Any, minimum: int, note: str = "") -> int:
    """``value`` as an ``int >= minimum`` (a bool or a float is not a count); ``note`` completes
    the message (``" (late cycles allowed in a row)"``).

    Raises:
        InputError: not an integer, or below ``minimum`` (``name`` named).
    """
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InputError(f"{value!r} must be an integer >= {minimum}{note}", field=name)
    return int(value)


def positive_number(field: str, value: Any, expected: str) -> float:
    """``value`` as a finite float ``> 0``; ``expected`` completes the message
    (e.g. ``"a finite number > 0 [s]"``).

    Raises:
        InputError: not a number (a text such as ``"0.01"`` is not one in the API), or out of
            range (``field`` named).
    """
    return number_in(field, value, expected, lambda x: x > 0)


def number_in(field: str, value: Any, expected: str, valid: Callable[[float], bool]) -> float:
    """``value`` as a finite float for which ``valid`` holds (``lambda x: x >= 1``);
    ``expected`` completes the message (e.g. ``"a finite number >= 1 (Theorem 1)"``).

    Raises:
        InputError: not a number (a text such as ``"0.01"`` is not one in the API), or out of
            range (``field`` named).
    """
    if isinstance(value, str | bytes | bool):
        raise InputError(
            f"{value!r} is a {type(value).__name__}, not a number; expected {expected}",
            field=field,
        )
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(
            f"{value!r:.60} is not a (double precision) number; expected {expected}", field=field
        ) from None
    if not (math.isfinite(number) and valid(number)):
        raise InputError(f"{value!r} is out of range; expected {expected}", field=field)
    return number


#: Most samples one simulated run records (its series are held in memory: about 50 doubles per
#: sample for a 7-joint arm, so 1e7 samples are some 4 GB; 2.8 h of simulated time at 1 kHz).
MAX_RUN_SAMPLES = 10**7


def check_run_length(
    duration: float,
    sample_period: float | None,
    output_rate: float = 1000.0,
    source: str | Path | None = None,
) -> None:
    """Refuse a run whose series would not fit in memory, before anything is computed.

    ``duration`` [s] at ``sample_period`` [s] (``None``: continuous time, recorded at
    ``output_rate`` [Hz]) must record at most :data:`MAX_RUN_SAMPLES` samples; ``source``: the
    file the duration came from (a scenario), named in the error.

    Raises:
        InputError: too many samples (field ``duration``), saying the longest duration allowed.
    """
    step = 1.0 / output_rate if sample_period is None else sample_period
    samples = duration / step
    if samples > MAX_RUN_SAMPLES:
        what = "period" if sample_period is not None else "recording step"
        raise InputError(
            f"{duration:g} s at the {what} {step:g} s records {samples:.3g} samples, more than "
            f"the {MAX_RUN_SAMPLES:.0e} a run holds in memory: give a duration of at most "
            f"{MAX_RUN_SAMPLES * step:g} s (split a longer study into runs)",
            source=source,
            field="duration",
        )


def check_trajectory_dof(trajectory: Any, dof: int, owner: str) -> None:
    """Refuse ``trajectory`` unless it has ``reference(t)`` and ``dof`` joints (when it says);
    ``owner`` names what it drives in the message (``"the plant 'ur5'"``).

    Raises:
        InputError: not a trajectory, or one of another number of joints (field ``trajectory``).
    """
    if not callable(getattr(trajectory, "reference", None)):
        raise InputError(
            "expected a trajectory with reference(t) (urpc.trajectories: PaperTrajectory, "
            "SinusoidTrajectory, QuinticTrajectory, generic_trajectory), got "
            f"{type(trajectory).__name__}",
            field="trajectory",
        )
    joints = getattr(trajectory, "dof", dof)
    if joints != dof:
        hint = (
            "PaperTrajectory is the paper's 2-joint reference: give its amplitude per joint "
            f"(PaperTrajectory(amplitude=[...] with {dof} values)) or use generic_trajectory(robot)"
            if getattr(trajectory, "kind", None) == "paper"
            else "give a reference for every joint (generic_trajectory(robot) fits any arm)"
        )
        raise InputError(
            f"{trajectory!r} has {joints} joints, {owner} has {dof}: {hint}", field="trajectory"
        )
