"""The outcome of a campaign: one row per run, the summary, the figure and the files."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...model.parameter_box import JOINTS
from ..scenario import Scenario
from .figures import plot_campaign
from .outputs import (
    HISTOGRAM_NAME,
    RUNS_NAME,
    SUMMARY_NAME,
    write_csv,
    write_outputs,
    write_summary,
)
from .worker import RunOutcome

#: Columns of ``runs.csv`` that carry metrics of the run (after the draw columns).
METRIC_COLUMNS = (
    "status", "met", "entry_time", "final_error", "final_error_over_epsilon",
    "max_error_after_entry", "torque_peak", "torque_rms", "torque_variation", "phi", "kappa",
)  # fmt: skip


@dataclass(frozen=True)
class CampaignResult:
    """The outcome of :func:`run_campaign`: one :class:`RunOutcome` per run, in run order.

    Attributes:
        scenario: The scenario every run starts from.
        outcomes: The runs, ``outcomes[i].spec.index == i``.
        seed: Campaign seed.
        draws: Draw statistics (see :func:`draw_runs`).
        parameter_names: ``(link, field, k)`` of each uncertain box coordinate: the CSV column
            ``link.field`` holds coordinate ``k`` of that link's point.
        joint_names: Joint names (the initial-offset columns).
        workers: Local worker processes (``None`` on a Dask cluster).
        scheduler: Dask scheduler address, or ``None`` for the local pool.
        wall_time: Wall time of the whole campaign [s], pool or client start-up included.
        certificate: :func:`~urpc.studies.certification.certificate_fields` of the scenario's
            controller (the same for every run: the box, reference and disturbance are shared).
        certificate_source: How the certificate was obtained (``cached (key ...)``,
            ``computed in 2.1 s, ...``), or ``None``; not part of :meth:`summary`, which is the
            same either way.
    """

    scenario: Scenario
    outcomes: tuple[RunOutcome, ...]
    seed: int
    draws: Mapping[str, Any]
    parameter_names: tuple[tuple[str, str, int], ...]
    joint_names: tuple[str, ...]
    workers: int | None
    scheduler: str | None
    wall_time: float
    certificate: Mapping[str, Any]
    certificate_source: str | None = None

    @property
    def certified(self) -> bool | None:
        """Whether the scenario is certified; ``None`` when its certificate was not computed."""
        value = self.certificate["certified"]
        return None if value is None else bool(value)

    @property
    def runs(self) -> int:
        return len(self.outcomes)

    @property
    def met_fraction(self) -> float:
        return sum(o.met for o in self.outcomes) / len(self.outcomes)

    def rows(self) -> list[dict[str, Any]]:
        """One dict per run with the ``runs.csv`` columns (deterministic: no wall times)."""
        epsilon = self.scenario.epsilon
        rows = []
        for outcome in self.outcomes:
            spec, metrics = outcome.spec, outcome.metrics
            row: dict[str, Any] = {
                "run": spec.index,
                "kind": spec.kind,
                "vertex": spec.vertex,
                "seed": spec.seed,
                "rejected_draws": spec.rejected,
            }
            for link, field, k in self.parameter_names:
                column = field if link == JOINTS else f"{link}.{field}"
                row[column] = spec.point[link][k]
            for j, name in enumerate(self.joint_names):
                row[f"q0.{name}"] = spec.q0[j]
            final = metrics.get("final_error")
            row.update({name: metrics.get(name) for name in METRIC_COLUMNS})
            row["status"], row["met"] = outcome.status, outcome.met
            row["final_error_over_epsilon"] = None if final is None else final / epsilon
            row["message"] = outcome.message
            rows.append(row)
        return rows

    def summary(self) -> dict[str, Any]:
        """The content of ``summary.json``.

        Keys: the scenario's settings (``scenario``, ``scenario_file``, ``controller`` and its
        ``controller_options``, ``epsilon`` [rad], ``duration`` [s], ``sample_period`` [s], ``disturbance`` [N m]);
        ``seed``, ``runs``, ``met``, ``met_fraction``; ``worst_final_error_over_epsilon`` (and
        its ``worst_final_error_run``), ``worst_entry_time`` [s], ``never_entered``,
        ``diverged`` and ``torque_peak_max`` [N m], over the runs that did not diverge (``None``
        when none); the draws (``vertex_runs``, ``vertex_total``, ``uniform_runs``,
        ``rejected_draws``, ``rejected_vertices``, ``uncertain_parameters``); the execution
        (``workers``, ``scheduler``, ``wall_time`` [s], ``runs_per_minute``, ``run_cpu_time_mean``
        [s] and ``runs_per_minute_per_core`` = 60 / ``run_cpu_time_mean``, the throughput of
        one unshared core); ``certified``, ``not_certified`` (why, or ``None``) and
        ``certificate`` (:func:`~urpc.studies.certification.certificate_fields`).
        """
        rows = self.rows()
        ok = [r for r in rows if r["status"] == "ok"]
        entered = [r for r in ok if r["entry_time"] is not None]
        worst = max(ok, key=lambda r: r["final_error_over_epsilon"], default=None)
        cpu_time = _mean(o.cpu_time for o in self.outcomes if math.isfinite(o.cpu_time))
        scenario = self.scenario
        return {
            "scenario": scenario.name,
            "scenario_file": None if scenario.source is None else str(scenario.source),
            "controller": scenario.controller,
            "controller_options": scenario.to_dict()["controller_options"][scenario.controller],
            "epsilon": scenario.epsilon,
            "duration": scenario.duration,
            "sample_period": scenario.sample_period,
            "disturbance": scenario.disturbance,
            "disturbance_model": scenario.disturbance_model,
            "seed": self.seed,
            "runs": self.runs,
            "met": sum(r["met"] for r in rows),
            "met_fraction": self.met_fraction,
            "worst_final_error_over_epsilon": None
            if worst is None
            else worst["final_error_over_epsilon"],
            "worst_final_error_run": None if worst is None else worst["run"],
            "worst_entry_time": max((r["entry_time"] for r in entered), default=None),
            "never_entered": len(ok) - len(entered),
            "diverged": len(rows) - len(ok),
            "torque_peak_max": max((r["torque_peak"] for r in ok), default=None),
            "vertex_runs": self.draws["vertices"],
            "vertex_total": self.draws["vertex_total"],
            "uniform_runs": self.runs - self.draws["vertices"],
            "rejected_draws": self.draws["rejected_draws"],
            "rejected_vertices": self.draws["rejected_vertices"],
            "uncertain_parameters": [f"{link}.{field}" for link, field, _ in self.parameter_names],
            "workers": self.workers,
            "scheduler": self.scheduler,
            "wall_time": self.wall_time,
            "runs_per_minute": 60.0 * self.runs / self.wall_time if self.wall_time > 0 else None,
            "run_cpu_time_mean": cpu_time,
            "runs_per_minute_per_core": 60.0 / cpu_time if cpu_time else None,
            **self.certificate,
        }

    def plot(self):
        """Histograms of ``final_error / epsilon`` and ``entry_time``, vertex and uniform runs
        stacked, with the ``epsilon`` line and the entry deadline (a headless matplotlib
        :class:`~matplotlib.figure.Figure`)."""
        return plot_campaign(self.rows(), self.summary())

    def save(self, directory: str | Path) -> Path:
        """Write ``runs.csv``, ``summary.json`` and ``histogram.png`` into ``directory``,
        atomically: everything is written in a temporary sibling folder first, then renamed into
        place (an existing folder receives each file by ``os.replace``).

        Raises:
            InputError: the folder cannot be written (names it).
        """
        return write_outputs(
            directory,
            {
                RUNS_NAME: lambda path: write_csv(self.rows(), path),
                SUMMARY_NAME: lambda path: write_summary(self.summary(), path),
                HISTOGRAM_NAME: lambda path: self.plot().savefig(path, dpi=100),
            },
        )


def _mean(values) -> float | None:
    numbers = [v for v in values if v is not None]
    return float(np.mean(numbers)) if numbers else None
