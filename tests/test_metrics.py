"""Metrics on synthetic series whose answers are known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from urpc.sim.metrics import METRIC_NAMES, series_metrics

EPSILON = 1e-2


def _grid(duration=8.0, rate=1000.0):
    """Sample times k / rate (exact for whole multiples, so comparisons below are exact)."""
    return np.arange(round(duration * rate) + 1) / rate


def test_diagnostic_series_add_their_final_value_under_their_own_name():
    """The keys are the fixed metrics plus one per diagnostic series, whatever its name: the
    metrics know no controller's gains."""
    t = _grid(2.0)
    plain = series_metrics(t, np.zeros_like(t), np.zeros((len(t), 2)), EPSILON)
    assert set(plain) == set(METRIC_NAMES)
    named = {"gain": np.linspace(0.0, 3.0, len(t)), "other": np.full(len(t), np.nan)}
    metrics = series_metrics(t, np.zeros_like(t), np.zeros((len(t), 2)), EPSILON, diagnostics=named)
    assert set(metrics) - set(METRIC_NAMES) == {"gain", "other"}
    assert metrics["gain"] == 3.0 and metrics["other"] is None  # the last value; NaN: none


def test_entry_time_is_the_start_of_the_final_stay_inside():
    t = _grid()
    # Outside until 2 s, inside, one excursion at 3.5 s, then inside at 0.4 epsilon decaying.
    error = np.where(t < 2.0, 1.0, 0.5 * EPSILON)
    error[3500] = 2 * EPSILON  # t = 3.5 s
    late = t > 3.5
    error[late] = 0.4 * EPSILON * np.exp(-(t[late] - 3.5))
    metrics = series_metrics(t, error, np.zeros((len(t), 2)), EPSILON)
    assert metrics["entry_time"] == pytest.approx(3.501)
    assert metrics["met"] is True
    assert metrics["max_error_after_entry"] == pytest.approx(0.4 * EPSILON * math.exp(-0.001))
    # Last second: t in [7, 8], the largest error is at t = 7.
    assert metrics["final_error"] == pytest.approx(0.4 * EPSILON * math.exp(-3.5))


def test_exactly_epsilon_counts_as_outside_and_met_needs_the_final_quarter():
    t = _grid(8.0)
    at_epsilon = np.full(len(t), EPSILON)
    never = series_metrics(t, at_epsilon, np.zeros((len(t), 1)), EPSILON)
    assert never["entry_time"] is None and never["met"] is False
    assert never["max_error_after_entry"] is None
    assert never["final_error"] == EPSILON

    late = np.where(t < 6.5, 1.0, 0.0)  # enters at 6.5 s > 0.75 * 8 s = 6 s
    metrics = series_metrics(t, late, np.zeros((len(t), 1)), EPSILON)
    assert metrics["entry_time"] == pytest.approx(6.5) and metrics["met"] is False
    boundary = np.where(t < 6.0, 1.0, 0.0)  # enters at exactly 0.75 T
    assert series_metrics(t, boundary, np.zeros((len(t), 1)), EPSILON)["met"] is True

    always = series_metrics(t + 1.0, np.zeros(len(t)), np.zeros((len(t), 1)), EPSILON)
    assert always["entry_time"] == 1.0 and always["met"] is True  # the first sample


def test_torque_metrics_of_a_rotating_torque():
    """u = A (sin wt, cos wt): ||u|| = A, so rms = A; peak = A; each component's total variation
    over whole periods is 4 A per period, i.e. 4 A f per second per joint."""
    amplitude, frequency, duration = 30.0, 5.0, 4.0
    t = _grid(duration, rate=20000.0)
    phase = 2 * np.pi * frequency * t
    torque = amplitude * np.column_stack((np.sin(phase), np.cos(phase)))
    metrics = series_metrics(t, np.zeros(len(t)), torque, EPSILON)
    assert metrics["torque_rms"] == pytest.approx(amplitude, rel=1e-12)
    assert metrics["torque_peak"] == pytest.approx(amplitude, rel=1e-9)
    assert metrics["torque_variation"] == pytest.approx(2 * 4 * amplitude * frequency, rel=1e-6)


def test_constant_torque_has_no_variation_and_a_step_counts_once():
    t = _grid(2.0)
    torque = np.tile([10.0, -40.0], (len(t), 1))
    metrics = series_metrics(t, np.zeros(len(t)), torque, EPSILON)
    assert metrics["torque_variation"] == 0.0
    assert metrics["torque_peak"] == 40.0
    assert metrics["torque_rms"] == pytest.approx(math.hypot(10.0, 40.0))
    torque[t >= 1.0, 0] = 20.0  # one jump of 10 N m in 2 s
    assert series_metrics(t, np.zeros(len(t)), torque, EPSILON)["torque_variation"] == 5.0


def test_gains_and_timings_are_optional():
    t = _grid(1.0)
    zeros = np.zeros(len(t))
    plain = series_metrics(t, zeros, np.zeros((len(t), 2)), EPSILON)
    assert "phi" not in plain and "kappa" not in plain
    assert plain["step_time_median"] is None and plain["wall_time"] is None
    nan = series_metrics(
        t, zeros, np.zeros((len(t), 2)), EPSILON, diagnostics={"phi": zeros + np.nan}
    )
    assert nan["phi"] is None
    phi = np.linspace(1.0, 7.0, len(t))
    full = series_metrics(
        t,
        zeros,
        np.zeros((len(t), 2)),
        EPSILON,
        diagnostics={"phi": phi, "kappa": phi / 2},
        step_time_median=2e-5,
        wall_time=1.5,
    )
    assert (full["phi"], full["kappa"], full["step_time_median"], full["wall_time"]) == (
        7.0,
        3.5,
        2e-5,
        1.5,
    )
