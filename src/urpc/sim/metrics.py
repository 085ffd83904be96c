"""Metrics of one simulation run: did it meet ``||e|| < epsilon``, and at what torque cost.

Definitions, for recorded samples ``t_0 < ... < t_K`` (the control samples of a sampled run, the
output grid of a continuous one), ``T = t_K - t_0`` and ``e_k = q_d(t_k) - q(t_k)``:

``entry_time`` [s]
    The first recorded time ``t_j`` such that ``||e_k|| < epsilon`` for every ``k >= j``;
    ``None`` when the last sample is outside the ball.
``met`` [bool]
    ``entry_time`` is not ``None`` and ``entry_time <= t_0 + 0.75 T``: at least the final quarter
    of the run lies inside the epsilon ball.
``max_error_after_entry`` [rad]
    ``max ||e_k||`` over ``t_k >= entry_time`` (``None`` when never entered).
``final_error`` [rad]
    ``max ||e_k||`` over the final window ``t_k >= t_K - W``, ``W = min(1 s, T / 4)``
    (:func:`final_window`): the last second, or the last quarter of a run shorter than 4 s. The
    window lies inside the final quarter by which ``met`` is judged, so a met run always has
    ``final_error < epsilon``.
``torque_rms`` [N m]
    ``sqrt(mean_k ||u_k||^2)``, the RMS of the Euclidean norm of the commanded torque.
``torque_peak`` [N m]
    ``max_{k,i} |u_{k,i}|``, the largest commanded joint torque.
``torque_variation`` [N m/s]
    ``sum_{k=1..K} ||u_k - u_{k-1}||_1 / T``: the total variation of the commanded torque per
    second, the chattering index. It depends on the recording grid for non-smooth torques, so
    compare runs recorded at the same rate.
one key per diagnostic series of the controller (e.g. ``phi`` [N m s/rad], ``kappa`` [s/rad])
    Its final value (``None`` when NaN); a controller without diagnostics adds no key.
``step_time_median`` [s]
    Median wall time of one control step (one torque evaluation and state update).
``wall_time`` [s]
    Wall time of the whole simulation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..jsonsafe import finite_or_none

#: The metric names every run has, in report order (the keys of ``SimulationResult.metrics``
#: besides the final value of each of the controller's diagnostic series).
METRIC_NAMES = (
    "entry_time",
    "met",
    "max_error_after_entry",
    "final_error",
    "torque_rms",
    "torque_peak",
    "torque_variation",
    "step_time_median",
    "wall_time",
)

#: Longest final window of ``final_error`` [s].
FINAL_WINDOW_MAX = 1.0


def final_window(span: float) -> float:
    """The length ``W = min(1 s, T / 4)`` [s] of the window of ``final_error`` for a run of
    ``span = T`` seconds: the last second, or the last quarter of a shorter run."""
    return min(FINAL_WINDOW_MAX, 0.25 * float(span))


def describe_final_window(span: float) -> str:
    """What ``final_error`` covers in words: ``"the last second"`` or ``"the last 0.25 s, the
    final quarter"``."""
    window = final_window(span)
    if window == FINAL_WINDOW_MAX:
        return "the last second"
    return f"the last {window:.3g} s, the final quarter"


def series_metrics(
    t: np.ndarray,
    error_norm: np.ndarray,
    torque: np.ndarray,
    epsilon: float,
    *,
    diagnostics: Mapping[str, np.ndarray] | None = None,
    step_time_median: float | None = None,
    wall_time: float | None = None,
) -> dict[str, Any]:
    """The metrics from raw series: times ``t`` [s] (``K+1``), ``error_norm`` [rad] (``K+1``),
    commanded ``torque`` [N m] (``(K+1) x dof``), the precision ``epsilon`` [rad]; the named
    ``diagnostics`` series, whose last value is reported under each name (after
    ``torque_variation``)."""
    t = np.asarray(t, dtype=float)
    error_norm = np.asarray(error_norm, dtype=float)
    torque = np.asarray(torque, dtype=float).reshape(len(t), -1)
    span = float(t[-1] - t[0])
    outside = np.flatnonzero(~(error_norm < epsilon))
    if outside.size == 0:
        entry = 0
    elif outside[-1] == len(t) - 1:
        entry = None
    else:
        entry = int(outside[-1]) + 1
    entry_time = None if entry is None else float(t[entry])
    # The quarter's start is computed as met's deadline is, so the two agree to the last bit.
    quarter = final_window(span) < FINAL_WINDOW_MAX
    final = t >= (t[0] + 0.75 * span if quarter else t[-1] - FINAL_WINDOW_MAX)
    differences = np.abs(np.diff(torque, axis=0)).sum() if len(t) > 1 else 0.0
    return {
        "entry_time": entry_time,
        "met": bool(entry_time is not None and entry_time <= t[0] + 0.75 * span),
        "max_error_after_entry": None if entry is None else float(error_norm[entry:].max()),
        "final_error": float(error_norm[final].max()),
        "torque_rms": float(math.sqrt(np.mean(np.sum(torque**2, axis=1)))),
        "torque_peak": float(np.abs(torque).max()),
        "torque_variation": float(differences / span) if span > 0 else 0.0,
        **{name: _final(series) for name, series in (diagnostics or {}).items()},
        "step_time_median": finite_or_none(step_time_median),
        "wall_time": finite_or_none(wall_time),
    }


def _final(series: np.ndarray | None) -> float | None:
    if series is None or len(series) == 0:
        return None
    return finite_or_none(np.asarray(series, dtype=float)[-1])
