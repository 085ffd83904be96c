"""Figures of the demos: one panel per configuration (arm and error norm), and the error norm and
gain of a run with a payload change."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .configuration_run import ConfigurationRun
from .drawing import draw_arm
from .tool_change import ToolChangeRun


def plot_reconfigure(runs: Sequence[ConfigurationRun], *, epsilon: float | None = None) -> Figure:
    """For each configuration, a side view of the arm where its run starts (``q_d(0)``; the home
    pose in light grey) above its error norm ``||e||`` [rad] (log scale) with the ``epsilon``
    line."""
    figure = Figure(figsize=(3.6 * len(runs), 6.4), layout="constrained")
    grid = figure.add_gridspec(2, len(runs), height_ratios=(1.15, 1.0))
    for i, run in enumerate(runs):
        drawing = figure.add_subplot(grid[0, i])
        draw_arm(drawing, run.arm, run.trajectory.reference(0.0).q)
        ms = 1e3 * run.arm.timing.total
        drawing.set_title(
            f"{run.name} ({run.arm.dof} DOF)\nsynthesized in {ms:.1f} ms", fontsize=10
        )
        axes = figure.add_subplot(grid[1, i])
        eps = epsilon if run.result is None else run.result.epsilon
        if run.result is None:
            axes.text(0.5, 0.5, "diverged", ha="center", va="center", transform=axes.transAxes)
            axes.set_yscale("log")
            axes.set_ylim(1e-5, 1.0)
        else:
            _error_norm_axes(axes, run.result.t, run.result.error_norm, eps)
            metrics = run.result.metrics
            axes.set_title(
                f"{'met' if metrics['met'] else 'NOT met'}; final max "
                f"{metrics['final_error'] / eps:.3g} " + r"$\varepsilon$",
                fontsize=10,
            )
        if eps is not None:
            axes.axhline(eps, color="tab:red", ls="--", lw=1.0, label=r"$\varepsilon$")
        if i == 0:
            axes.set_ylabel(r"$\|e\|$ [rad]")
            axes.legend(loc="upper right", fontsize="small")
        axes.set_xlabel("time [s]")
    first = next((run.result for run in runs if run.result is not None), None)
    if first is not None and first.sample_period is not None:
        figure.suptitle(
            "Reconfigurable arm: each controller synthesized on the fly with the default "
            f"settings; {1 / first.sample_period:g} Hz, unknown disturbance "
            rf"$\|d\| \leq$ {first.disturbance_bound:g} N m (grey: home pose)",
            fontsize=10,
        )
    return figure


def plot_tool_change(run: ToolChangeRun) -> Figure:
    """The error norm of the whole run (log scale) with ``epsilon`` and the change marked, above
    the gain ``phi``."""
    result = run.result
    figure = Figure(figsize=(7.5, 5.0), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    _error_norm_axes(top, result.t, result.error_norm, result.epsilon)
    top.axhline(result.epsilon, color="tab:red", ls="--", lw=1.0, label=r"$\varepsilon$")
    for axes in (top, bottom):
        axes.axvline(run.t_change, color="k", lw=1.0, ls=":")
        if run.switch_delay > 0:
            axes.axvline(run.t_switch, color="tab:purple", lw=1.0, ls=":")
    reentry = run.reentry_time
    if reentry is None:
        status = "not back below epsilon"
    elif reentry == 0:
        status = "error stayed below epsilon"
    else:
        status = f"back below epsilon after {reentry * 1e3:.0f} ms"
    top.text(
        run.t_change,
        0.04,
        f"  payload change {run.before.name} -> {run.after.name}\n  {status}",
        transform=top.get_xaxis_transform(),
        va="bottom",
        fontsize=9,
    )
    top.set_ylabel(r"$\|e\|$ [rad]")
    top.legend(loc="upper left", fontsize="small")
    bottom.plot(result.t, result.diagnostics["phi"], color="tab:blue")
    bottom.set_ylabel(r"$\phi$ [N m s/rad]")
    bottom.set_xlabel("time [s]")
    bottom.grid(True, alpha=0.3)
    figure.suptitle("Payload change during a run: same controller state, new box", fontsize=11)
    return figure


def _error_norm_axes(axes: Axes, t: np.ndarray, error_norm: np.ndarray, epsilon: float) -> None:
    """``||e||`` on a log axis from its first positive sample (no spike from an exact zero at
    t = 0), with limits that keep the epsilon line off the frame."""
    from ...sim.plotting import log_error_limits, positive_for_log

    axes.semilogy(t, positive_for_log(error_norm), lw=0.8, color="tab:blue", label=r"$\|e\|$")
    axes.set_ylim(*log_error_limits([error_norm], epsilon))
    axes.grid(True, which="both", alpha=0.3)
