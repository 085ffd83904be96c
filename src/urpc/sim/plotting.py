"""Figures of simulation results, after the paper's Figs. 1-5.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so it works
headless (no display, no global figure registry); save it with ``figure.savefig(path)``.

* :func:`plot_reference` - the desired joint trajectory alone (Fig. 1);
* :func:`plot_trajectory` - the desired joint trajectory of a run, with the actual one;
* :func:`plot_error` - ``||e||`` on a log scale with the ``epsilon`` line (Figs. 2, 3);
* :func:`plot_torque` - the commanded joint torques (Figs. 2-5);
* :func:`plot_overview` - error and torques of one run stacked (Figs. 2, 3);
* :func:`plot_errors` - error norms of several runs overlaid, with ``epsilon`` (e.g. both
  initial conditions of one scenario);
* :func:`compare` - error norms and torques of several runs overlaid (Figs. 4, 5).

A run is anything with the attributes of :class:`Run` (a :class:`urpc.sim.results.SimulationResult`
is one), so that this module depends on no result class and the result class can plot itself.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

_JOINT_STYLES = ("-", "--", "-.", ":")
_FLOOR = 1e-12  # [rad] floor of log-scale error plots (an exact zero has no logarithm)
_DECADES_BELOW_EPSILON = 1e-6  # error plots show at most 6 decades below epsilon


class Run(Protocol):
    """What a figure reads of a run (see :class:`urpc.sim.results.SimulationResult`)."""

    t: np.ndarray  # [s], (K,)
    q: np.ndarray  # [rad], (K, n)
    q_desired: np.ndarray  # [rad], (K, n)
    torque: np.ndarray  # [N m], (K, n)
    controller: str
    epsilon: float  # [rad]
    sample_period: float | None  # [s], None for continuous time
    scenario: str
    disturbance_bound: float  # [N m]

    @property
    def dof(self) -> int: ...

    @property
    def error_norm(self) -> np.ndarray: ...  # [rad], (K,)

    @property
    def metrics(self) -> dict[str, Any]: ...


def describe(result: Run) -> str:
    """``scenario, controller, sampling`` as a title fragment."""
    timing = (
        "continuous time"
        if result.sample_period is None
        else f"sampled at {1.0 / result.sample_period:g} Hz"
    )
    parts = [result.scenario] if result.scenario else []
    parts += [result.controller, timing]
    if result.disturbance_bound:
        parts.append(f"||d|| <= {result.disturbance_bound:g} N m")
    return ", ".join(parts)


def plot_trajectory(result: Run, *, actual: bool = True) -> Figure:
    """Desired joint positions ``q_d(t)`` [rad] (the paper's Fig. 1), and the actual ``q(t)``
    dashed when ``actual``."""
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    for i in range(result.dof):
        line = axes.plot(result.t, result.q_desired[:, i], label=f"$q_{{d,{i + 1}}}$")[0]
        if actual:
            axes.plot(
                result.t, result.q[:, i], ls="--", color=line.get_color(), label=f"$q_{i + 1}$"
            )
    axes.set(xlabel="time [s]", ylabel="joint position [rad]")
    axes.set_title(f"Trajectory - {describe(result)}")
    axes.grid(True, alpha=0.3)
    axes.legend(ncol=2, fontsize="small")
    return figure


def plot_reference(
    trajectory: Any, duration: float, *, samples: int = 2001, title: str | None = None
) -> Figure:
    """The desired trajectory alone, ``q_d(t)`` [rad] over ``[0, duration]`` (the paper's Fig. 1),
    from any object with ``reference(t)``."""
    times = np.linspace(0.0, duration, samples)
    desired = np.array([trajectory.reference(t).q for t in times])
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    for i in range(desired.shape[1]):
        axes.plot(times, desired[:, i], ls=_JOINT_STYLES[i % 4], label=f"$q_{{d,{i + 1}}}$")
    axes.set(xlabel="time [s]", ylabel="desired joint position [rad]")
    axes.set_title(title or "Desired trajectory")
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize="small")
    return figure


def plot_error(result: Run) -> Figure:
    """``||e(t)||`` [rad] on a log scale with the required precision ``epsilon`` and the entry
    time (Figs. 2, 3)."""
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    _error_axes(axes, [result], labels=[result.controller])
    axes.set_title(f"Tracking error - {describe(result)}")
    return figure


def plot_torque(result: Run) -> Figure:
    """Commanded joint torques ``u(t)`` [N m] (Figs. 2-5)."""
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    _torque_axes(axes, result, label_prefix="")
    axes.set_title(f"Commanded torque - {describe(result)}")
    axes.legend(ncol=min(result.dof, 4), fontsize="small")
    return figure


def plot_overview(result: Run) -> Figure:
    """Error norm (log scale, with ``epsilon``) above the commanded torques, like the paper's
    Figs. 2 and 3."""
    figure = Figure(figsize=(7.0, 6.0), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True)
    _error_axes(top, [result], labels=[result.controller])
    top.set_xlabel("")
    _torque_axes(bottom, result, label_prefix="")
    bottom.legend(ncol=min(result.dof, 4), fontsize="small")
    figure.suptitle(describe(result))
    return figure


def plot_errors(
    results: Sequence[Run],
    *,
    labels: Sequence[str] | None = None,
    title: str | None = None,
) -> Figure:
    """``||e(t)||`` [rad] of several runs on one log-scale axis, with each run's ``epsilon``.

    Args:
        results: Runs to overlay.
        labels: Legend entries (default: ``scenario, controller`` of each run).
        title: Figure title (default: the first run's :func:`describe`).
    """
    if not results:
        raise ValueError("plot_errors() needs at least one result")
    if labels is None:
        labels = [", ".join(p for p in (r.scenario, r.controller) if p) for r in results]
    if len(labels) != len(results):
        raise ValueError(f"{len(labels)} labels for {len(results)} results")
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    _error_axes(axes, results, labels=list(labels))
    axes.set_title(title or f"Tracking error - {describe(results[0])}")
    return figure


def compare(
    results: Sequence[Run],
    *,
    labels: Sequence[str] | None = None,
    title: str | None = None,
) -> Figure:
    """Overlay several runs (the paper's Figs. 4 and 5): error norms on a log scale with each
    run's ``epsilon`` on top, then one torque panel per joint.

    Args:
        results: Runs to compare (same robot; typically one scenario, several controllers).
        labels: Legend entries (default: the controller names).
        title: Figure title (default: the first run's scenario and sampling).
    """
    if not results:
        raise ValueError("compare() needs at least one result")
    labels = list(labels) if labels is not None else [r.controller for r in results]
    if len(labels) != len(results):
        raise ValueError(f"{len(labels)} labels for {len(results)} results")
    dof = results[0].dof
    figure = Figure(figsize=(7.5, 2.6 * (dof + 1)), layout="constrained")
    axes = figure.subplots(dof + 1, 1, sharex=True)
    _error_axes(axes[0], results, labels=labels)
    axes[0].set_xlabel("")
    for i in range(dof):
        ax = axes[i + 1]
        for result, label in zip(results, labels, strict=True):
            ax.plot(result.t, result.torque[:, i], lw=0.8, label=label)
        ax.set_ylabel(f"$u_{i + 1}$ [N m]")
        ax.grid(True, alpha=0.3)
    axes[1].legend(fontsize="small")
    axes[-1].set_xlabel("time [s]")
    if title is None:
        first = results[0]
        title = ", ".join(
            [first.scenario] * bool(first.scenario)
            + [
                "continuous time"
                if first.sample_period is None
                else f"sampled at {1.0 / first.sample_period:g} Hz"
            ]
        )
    figure.suptitle(f"Comparison - {title}")
    return figure


def _error_axes(axes: Axes, results: Sequence[Run], labels: Sequence[str]) -> None:
    epsilons = set()
    smallest = np.inf
    for result, label in zip(results, labels, strict=True):
        norm = result.error_norm
        axes.semilogy(result.t, np.maximum(norm, _FLOOR), lw=0.9, label=label)
        epsilons.add(float(result.epsilon))
        positive = norm[norm > 0]
        if positive.size:
            smallest = min(smallest, float(positive.min()))
    # An exact zero (a run starting on the reference) would stretch the axis down to the floor.
    bottom = max(smallest, _DECADES_BELOW_EPSILON * min(epsilons))
    if np.isfinite(bottom):
        axes.set_ylim(bottom=0.5 * bottom)
    for epsilon in sorted(epsilons):
        axes.axhline(epsilon, color="k", ls="--", lw=1.0, label=f"$\\varepsilon$ = {epsilon:g} rad")
    if len(results) == 1:
        entry = results[0].metrics["entry_time"]
        if entry is not None:
            axes.axvline(entry, color="tab:green", ls=":", lw=1.0, label=f"entry {entry:.3g} s")
    axes.set(xlabel="time [s]", ylabel="$\\|e\\|$ [rad]")
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize="small")


def _torque_axes(axes: Axes, result: Run, label_prefix: str) -> None:
    for i in range(result.dof):
        axes.plot(
            result.t,
            result.torque[:, i],
            ls=_JOINT_STYLES[i % len(_JOINT_STYLES)],
            lw=0.9,
            label=f"{label_prefix}$u_{i + 1}$",
        )
    axes.set(xlabel="time [s]", ylabel="torque [N m]")
    axes.grid(True, alpha=0.3)
