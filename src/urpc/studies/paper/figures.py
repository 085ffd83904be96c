"""The paper's figures (Figs. 1-5 and the sampled scenarios' error norms), as file writers."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ...sim.results import SimulationResult
from .runs import scenario_name


def figure_writers(runs: dict) -> dict[str, Callable[[Path], None]]:
    """The figures (Fig. 1-5 and the sampled scenarios' error norms), as writers."""
    from ...sim.plotting import compare, plot_errors, plot_overview, plot_reference
    from ..scenario import build, load_scenario

    def result(number: int, ic: int, controller: str) -> SimulationResult:
        return runs[(number, ic, controller)]["result"]

    first = result(1, 1, "interval")
    trajectory = build(load_scenario(scenario_name(1, 1))).trajectory
    figures = {
        "fig1_trajectory": plot_reference(
            trajectory, first.duration, title="Fig. 1 - desired trajectory q_d(t)"
        ),
    }
    for number, ic in ((1, 1), (1, 2)):
        figure = plot_overview(result(number, ic, "interval"))
        figure.suptitle(f"Fig. {ic + 1} - interval controller, scenario 1, IC{ic} (continuous)")
        figures[f"fig{ic + 1}_s1_ic{ic}_interval"] = figure
    for number, rate in ((2, "10 kHz"), (3, "1 kHz")):
        figures[f"errors_s{number}_interval"] = plot_errors(
            [result(number, 1, "interval"), result(number, 2, "interval")],
            labels=["IC1", "IC2"],
            title=f"Interval controller, scenario {number} ({rate}, ||d|| <= 10 N m)",
        )
    for number, rate in ((2, "10 kHz"), (3, "1 kHz")):
        # r-alpha first, so that the interval controller's torque is drawn over its chattering
        figure = compare(
            [result(number, 2, "r-alpha"), result(number, 2, "interval")],
            labels=["r-alpha", "interval (proposed)"],
        )
        figure.suptitle(
            f"Fig. {number + 2} - interval controller vs r-alpha, scenario {number} ({rate}, "
            "||d|| <= 10 N m), IC2"
        )
        figures[f"fig{number + 2}_s{number}_ic2_comparison"] = figure
    return {f"figures/{name}.png": _figure_writer(figure) for name, figure in figures.items()}


def _figure_writer(figure) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        figure.savefig(path, dpi=100, format="png")

    return write
