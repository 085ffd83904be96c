"""The campaign's figure: histograms of ``final_error / epsilon`` and of the entry time."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...wording import count


def plot_campaign(rows: Sequence[Mapping[str, Any]], summary: Mapping[str, Any]):
    """The figure of :meth:`urpc.studies.campaign.CampaignResult.plot`, from its ``rows()`` and
    ``summary()``."""
    from matplotlib.figure import Figure

    rows = [r for r in rows if r["status"] == "ok"]
    figure = Figure(figsize=(10.0, 4.0), layout="constrained")
    ratio_axes, entry_axes = figure.subplots(1, 2)
    groups = [("vertex", "tab:orange"), ("uniform", "tab:blue")]
    colors = [color for _, color in groups]

    ratios = [r["final_error_over_epsilon"] for r in rows]
    top = max([1.1, *(1.05 * x for x in ratios)])
    ratio_axes.hist(
        [[r["final_error_over_epsilon"] for r in rows if r["kind"] == k] for k, _ in groups],
        bins=np.linspace(0.0, top, 34),
        stacked=True,
        color=colors,
        label=[f"{k} ({sum(r['kind'] == k for r in rows)})" for k, _ in groups],
    )
    ratio_axes.axvline(1.0, color="tab:red", ls="--", label="epsilon")
    ratio_axes.set(
        xlabel="final error / epsilon\n(max ||e|| over the last second; the last quarter of a "
        "run < 4 s)",
        ylabel="runs",
        title=f"final error, worst {_fmt(summary['worst_final_error_over_epsilon'])} epsilon",
    )

    deadline = 0.75 * summary["duration"]
    entries = [r["entry_time"] for r in rows if r["entry_time"] is not None]
    right = max([deadline * 1.05, *(1.05 * t for t in entries)])
    by_kind = [[r["entry_time"] for r in rows if r["kind"] == k] for k, _ in groups]
    entry_axes.hist(
        [[t for t in times if t is not None] for times in by_kind],
        bins=np.linspace(0.0, right, 34),
        stacked=True,
        color=colors,
    )
    entry_axes.axvline(deadline, color="tab:red", ls="--", label="deadline 0.75 T")
    entry_axes.set(
        xlabel="entry time [s]\n(last entry into ||e|| < epsilon)",
        ylabel="runs",
        title=f"entry time, worst {_fmt(summary['worst_entry_time'])} s",
    )
    counts = {"never entered": summary["never_entered"], "diverged": summary["diverged"]}
    notes = ", ".join(f"{count} {what}" for what, count in counts.items() if count)
    if notes:
        entry_axes.text(
            0.5,
            0.95,
            f"{notes} (not shown)",
            transform=entry_axes.transAxes,
            ha="center",
            va="top",
            color="tab:red",
        )
    for axes in (ratio_axes, entry_axes):
        axes.grid(True, alpha=0.3)
        axes.legend(fontsize="small")
    figure.suptitle(
        f"Campaign {summary['scenario']}: {count(summary['runs'], 'run')} "
        f"({count(summary['vertex_runs'], 'vertex', 'vertices')}, "
        f"{summary['uniform_runs']} uniform), met "
        f"{summary['met']}/{summary['runs']}, seed {summary['seed']}"
    )
    return figure


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"
