"""Figures of simulation results, after the paper's Figs. 1-5.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so it works
headless (no display, no global figure registry); save it with ``figure.savefig(path)``.

* :func:`plot_reference` - the desired joint trajectory alone (Fig. 1);
* :func:`plot_trajectory` - the desired joint trajectory of a run, with the actual one;
* :func:`plot_error` - ``||e||`` on a log scale with the ``epsilon`` line (Figs. 2, 3), above
  ``||e|| / epsilon`` on a linear scale with the final window's maximum (the margin to epsilon);
* :func:`plot_torque` - the commanded joint torques, one panel per joint (Figs. 2-5);
* :func:`plot_gains` - the controller's diagnostic series (the adaptive gains ``phi`` and
  ``kappa`` of the interval law) over time;
* :func:`plot_overview` - error and torques of one run stacked (Figs. 2, 3);
* :func:`plot_errors` - error norms of several runs overlaid, with ``epsilon`` (e.g. both
  initial conditions of one scenario);
* :func:`compare` - error norms and torques of several runs overlaid (Figs. 4, 5).

A run is anything with the attributes of :class:`Run` (a :class:`urpc.sim.results.SimulationResult`
is one), so that this module depends on no result class and the result class can plot itself.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

_JOINT_STYLES = ("-", "--", "-.", ":")
_DECADES_BELOW_EPSILON = 1e-6  # error plots show at most 6 decades below epsilon
_TITLE_SIZE = 10


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
    diagnostics: Mapping[str, np.ndarray]  # name -> (K,), the controller's diagnostic series
    info: dict[str, Any]  # "diagnostic_units": name -> unit

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
        model = (getattr(result, "info", None) or {}).get("disturbance_model")
        pushed = f" ({DISTURBANCE_WORDS.get(model, model)})" if model else ""
        parts.append(f"||d|| <= {result.disturbance_bound:g} N m{pushed}")
    return ", ".join(parts)


#: How a title names a disturbance model other than the default ball
#: (``info["disturbance_model"]``, :data:`urpc.names.DISTURBANCE_MODELS`).
DISTURBANCE_WORDS = {
    "against": "against r",
    "worst": "at the bound, against r",
    "lightest": "at the bound, along the lightest mode",
}


#: Past this many legend entries (8 joints with their references) the legend goes beside the
#: axes, where it hides no curve.
INSIDE_LEGEND = 16


def _joint_legend(axes, handles=None, labels=None, ncol: int = 1) -> None:
    """The legend of per-joint curves: inside the axes (``ncol`` columns) for a few, beside them
    for more than :data:`INSIDE_LEGEND` entries (20 per column)."""
    if handles is None:
        handles, labels = axes.get_legend_handles_labels()
    if len(handles) <= INSIDE_LEGEND:
        axes.legend(handles, labels, ncol=ncol, fontsize="small")
        return
    axes.legend(
        handles, labels, ncol=-(-len(handles) // 20), fontsize="x-small",
        loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
    )  # fmt: skip


def plot_trajectory(result: Run, *, actual: bool = True) -> Figure:
    """Desired joint positions ``q_d(t)`` [rad] (the paper's Fig. 1), and the actual ``q(t)``
    dashed when ``actual``."""
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    for i in range(result.dof):
        line = axes.plot(result.t, result.q_desired[:, i], label=f"$q_{{d,{i + 1}}}$")[0]
        if actual:
            axes.plot(
                result.t, result.q[:, i], ls="--", color=line.get_color(), label=f"$q_{{{i + 1}}}$"
            )
    axes.set(xlabel="time [s]", ylabel=f"joint position [{position_unit(result)}]")
    # Two lines, as the other figures' titles: a long description is not cut at the frame.
    figure.suptitle(f"Trajectory\n{describe(result)}", fontsize=_TITLE_SIZE)
    axes.grid(True, alpha=0.3)
    _joint_legend(axes, ncol=2)
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
    _joint_legend(axes)
    return figure


def plot_error(result: Run) -> Figure:
    """``||e(t)||`` [rad] on a log scale with the required precision ``epsilon`` and the entry
    time (Figs. 2, 3), above the margin to epsilon: ``||e(t)|| / epsilon`` on a linear scale, with
    the final window of ``final_error`` (:func:`urpc.sim.metrics.final_window`) shaded and its
    maximum written as a fraction of epsilon."""
    figure = Figure(figsize=(7.0, 5.2), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    _error_axes(top, [result], labels=[result.controller])
    top.set_xlabel("")
    _margin_axes(bottom, result)
    figure.suptitle(f"Tracking error\n{describe(result)}", fontsize=_TITLE_SIZE)
    return figure


def plot_torque(result: Run) -> Figure:
    """Commanded joint torques ``u_i(t)`` [N m] ([N] for a prismatic joint), one panel per joint
    so that no joint hides another (Figs. 2-5)."""
    dof = result.dof
    figure = Figure(figsize=(7.0, 1.2 + 1.5 * dof), layout="constrained")
    axes = np.atleast_1d(figure.subplots(dof, 1, sharex=True))
    units = _torque_units(result)
    for i, ax in enumerate(axes):
        ax.plot(result.t, result.torque[:, i], lw=0.7, color=f"C{i % 10}")
        ax.set_ylabel(f"$u_{{{i + 1}}}$ [{units[i]}]")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    figure.suptitle(f"Commanded torque\n{describe(result)}", fontsize=_TITLE_SIZE)
    return figure


def plot_gains(result: Run) -> Figure:
    """The controller's diagnostic series over time, one panel each (the interval law's
    adaptive gains ``phi(t)`` [N m s/rad], which scales the damping of the sliding variable, and
    ``kappa(t)`` [s/rad], which scales the robust term; both grow while ``||e|| >= epsilon`` and
    freeze inside the ball). A controller without diagnostics gets a note instead of curves."""
    diagnostics = dict(result.diagnostics)
    units = result.info.get("diagnostic_units", {})
    figure = Figure(figsize=(7.0, 4.6), layout="constrained")
    axes = np.atleast_1d(figure.subplots(max(1, len(diagnostics)), 1, sharex=True))
    if not diagnostics:
        axes[0].text(
            0.5,
            0.5,
            f"no diagnostic series ({result.controller} controller)",
            ha="center",
            va="center",
            transform=axes[0].transAxes,
        )
    for k, (ax, (name, series)) in enumerate(zip(axes, diagnostics.items(), strict=False)):
        series = np.asarray(series, dtype=float)
        unit = units.get(name, "")
        label = f"$\\{name}$" if name in _GREEK else name
        if series.size and np.isfinite(series).any():
            ax.plot(result.t, series, lw=1.0, color=_GAIN_COLORS[k % len(_GAIN_COLORS)])
            final = float(series[np.isfinite(series)][-1])
            _corner_note(ax, f"final {final:.4g} {unit}")
        ax.set_ylabel(f"{label} [{unit}]" if unit else label)
        ax.ticklabel_format(axis="y", useOffset=False)  # 2.0008, not "+2" and 0.0008
        ax.grid(True, alpha=0.3)
    entry = result.metrics["entry_time"]
    if entry is not None:
        for ax in axes:
            ax.axvline(entry, color="tab:green", ls=":", lw=1.0)
    axes[-1].set_xlabel("time [s]")
    figure.suptitle(f"Controller diagnostics\n{describe(result)}", fontsize=_TITLE_SIZE)
    return figure


#: Diagnostic names drawn as Greek letters, and the colors of successive panels.
_GREEK = ("phi", "kappa", "rho", "eta", "alpha", "beta")
_GAIN_COLORS = ("tab:blue", "tab:purple", "tab:orange", "tab:green")


def plot_overview(result: Run) -> Figure:
    """Error norm (log scale, with ``epsilon``) above the commanded torques, like the paper's
    Figs. 2 and 3."""
    figure = Figure(figsize=(7.0, 6.0), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True)
    _error_axes(top, [result], labels=[result.controller])
    top.set_xlabel("")
    _torque_axes(bottom, result, label_prefix="")
    figure.suptitle(describe(result))
    return figure


def _legend_labels(
    caller: str,
    results: Sequence[Run],
    labels: Sequence[str] | None,
    default: Callable[[Run], str],
) -> list[str]:
    """One legend entry per run: ``labels`` checked against ``results``, or ``default`` of each
    run; ``caller`` names the plotting function in the errors."""
    if not results:
        raise ValueError(f"{caller}() needs at least one result")
    labels = list(labels) if labels is not None else [default(r) for r in results]
    if len(labels) != len(results):
        raise ValueError(f"{len(labels)} labels for {len(results)} results")
    return labels


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
    labels = _legend_labels(
        "plot_errors",
        results,
        labels,
        lambda r: ", ".join(p for p in (r.scenario, r.controller) if p),
    )
    figure = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = figure.add_subplot()
    _error_axes(axes, results, labels=list(labels))
    figure.suptitle(title or f"Tracking error\n{describe(results[0])}", fontsize=_TITLE_SIZE)
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
    labels = _legend_labels("compare", results, labels, lambda r: r.controller)
    dof = results[0].dof
    figure = Figure(figsize=(7.5, 2.6 * (dof + 1)), layout="constrained")
    axes = figure.subplots(dof + 1, 1, sharex=True)
    _error_axes(axes[0], results, labels=labels)
    axes[0].set_xlabel("")
    for i in range(dof):
        ax = axes[i + 1]
        for result, label in zip(results, labels, strict=True):
            ax.plot(result.t, result.torque[:, i], lw=0.8, label=label)
        ax.set_ylabel(f"$u_{{{i + 1}}}$ [{_torque_units(results[0])[i]}]")
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


def positive_for_log(values: np.ndarray) -> np.ndarray:
    """``values`` with exact zeros (a run starting on the reference has ``||e(0)|| = 0``) as NaN,
    so that a log axis starts at the first positive sample instead of a spike from the floor."""
    values = np.asarray(values, dtype=float)
    return np.where(values > 0, values, np.nan)


def log_error_limits(norms: Sequence[np.ndarray], epsilon: float) -> tuple[float, float]:
    """Limits of a log axis of error norms [rad] with an ``epsilon`` line: from half the smallest
    positive error (at most 6 decades below epsilon) to twice the larger of epsilon and the
    largest error, so that the epsilon line never lies on the frame."""
    positive = [n[n > 0] for n in (np.asarray(n, dtype=float) for n in norms)]
    positive = [p[np.isfinite(p)] for p in positive if p.size]
    smallest = min((float(p.min()) for p in positive if p.size), default=epsilon)
    largest = max((float(p.max()) for p in positive if p.size), default=epsilon)
    bottom = 0.5 * max(min(smallest, epsilon), _DECADES_BELOW_EPSILON * epsilon)
    return bottom, 2.0 * max(largest, epsilon)


def _error_axes(axes: Axes, results: Sequence[Run], labels: Sequence[str]) -> None:
    epsilons = set()
    unit = position_unit(results[0])
    for result, label in zip(results, labels, strict=True):
        axes.semilogy(result.t, positive_for_log(result.error_norm), lw=0.9, label=label)
        epsilons.add(float(result.epsilon))
    axes.set_ylim(*log_error_limits([r.error_norm for r in results], min(epsilons)))
    for epsilon in sorted(epsilons):
        axes.axhline(
            epsilon, color="k", ls="--", lw=1.0, label=f"$\\varepsilon$ = {epsilon:g} {unit}"
        )
    if len(results) == 1:
        entry = results[0].metrics["entry_time"]
        if entry is not None:
            axes.axvline(entry, color="tab:green", ls=":", lw=1.0, label=f"entry {entry:.3g} s")
    axes.set(xlabel="time [s]", ylabel=f"$\\|e\\|$ [{unit}]")
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize="small")


def _margin_axes(axes: Axes, result: Run) -> None:
    """``||e|| / epsilon`` on a linear axis (1 = the epsilon line), the final window shaded and
    its maximum written as a fraction of epsilon: a steady 0.9993 epsilon reads as such."""
    from .metrics import describe_final_window, final_window

    t = np.asarray(result.t, dtype=float)
    ratio = np.asarray(result.error_norm, dtype=float) / result.epsilon
    axes.plot(t, ratio, lw=0.9, color="tab:blue")
    axes.axhline(1.0, color="k", ls="--", lw=1.0)
    span = float(t[-1] - t[0])
    start = t[-1] - final_window(span)
    final = ratio[t >= start]
    axes.axvspan(start, t[-1], color="tab:orange", alpha=0.15, lw=0)
    worst = float(final.max())
    margin = 1.0 - worst
    _corner_note(
        axes,
        f"final max {worst:.4g} $\\varepsilon$ over {describe_final_window(span)}: "
        + (f"margin {100 * margin:.3g} % of $\\varepsilon$" if margin > 0 else "ABOVE epsilon"),
        bbox={"boxstyle": "round", "fc": "white", "ec": "0.7", "alpha": 0.9},
    )
    finite = ratio[np.isfinite(ratio)]
    # Linear, up to 1.5 epsilon: the transient is on the log panel above.
    axes.set_ylim(0.0, max(1.5, 1.25 * worst) if finite.size else 1.5)
    axes.set(xlabel="time [s]", ylabel="$\\|e\\| / \\varepsilon$")
    axes.grid(True, alpha=0.3)


def _corner_note(axes: Axes, text: str, **style) -> None:
    """``text`` in small print inside the top right corner of ``axes`` (``style``: more
    :meth:`~matplotlib.axes.Axes.annotate` options, e.g. a ``bbox``)."""
    axes.annotate(
        text,
        xy=(1.0, 1.0),
        xycoords="axes fraction",
        xytext=(-4, -4),
        textcoords="offset points",
        ha="right",
        va="top",
        fontsize="small",
        **style,
    )


def _joint_kinds(result: Run) -> tuple[str, ...]:
    """The run's ``info["joint_kinds"]`` when recorded, every joint revolute otherwise."""
    info = getattr(result, "info", None) or {}
    return tuple(info.get("joint_kinds") or ("revolute",) * result.dof)


def position_unit(result: Run) -> str:
    """The unit of a run's joint positions and of its ``||e||``: ``rad``, ``m`` when every joint
    is prismatic, ``rad, m`` for a mix (the norm then adds radians and metres, as ``epsilon``
    does)."""
    kinds = set(_joint_kinds(result))
    if kinds == {"prismatic"}:
        return "m"
    return "rad, m" if "prismatic" in kinds else "rad"


def _torque_units(result: Run) -> list[str]:
    """Per joint: ``N m`` for a revolute joint, ``N`` for a prismatic one (the run's
    ``info["joint_kinds"]`` when recorded, revolute otherwise)."""
    return ["N" if kind == "prismatic" else "N m" for kind in _joint_kinds(result)]


def _torque_axes(axes: Axes, result: Run, label_prefix: str) -> None:
    # Joint 1 last, so that it is drawn on top; thin, slightly transparent lines so that a
    # chattering joint does not hide another.
    for i in reversed(range(result.dof)):
        axes.plot(
            result.t,
            result.torque[:, i],
            ls=_JOINT_STYLES[i % len(_JOINT_STYLES)],
            lw=0.7,
            alpha=0.8,
            color=f"C{i % 10}",
            label=f"{label_prefix}$u_{{{i + 1}}}$",
        )
    handles, labels = axes.get_legend_handles_labels()
    _joint_legend(axes, handles[::-1], labels[::-1], ncol=min(result.dof, 4))
    units = sorted(set(_torque_units(result)), reverse=True)
    axes.set(xlabel="time [s]", ylabel=f"torque [{', '.join(units)}]")
    axes.grid(True, alpha=0.3)
