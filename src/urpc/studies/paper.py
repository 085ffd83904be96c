"""Reproduce the paper's Section IV: six scenarios, two controllers, the figures and a table.

Giusti & Althoff compare their interval passivity controller with the r-alpha tracking controller
of Zenieh & Corless on the RR arm of Table I, in the three scenarios of Table II (1: continuous
time, no disturbance, epsilon = 1e-3 rad; 2: 10 kHz zero-order hold with ``||d|| <= 10 N m``,
epsilon = 1e-2 rad; 3: the same at 1 kHz), each from the initial conditions IC1 and IC2.
:func:`reproduce_paper` runs the twelve simulations (the shipped scenarios
``rr_planar/s{1,2,3}_ic{1,2}``, each with ``interval`` and ``r-alpha``) in parallel processes
and writes into ``out_dir``:

* ``results.md``: one table row per run (met, entry time, errors, torque peak, RMS and variation,
  the final ``phi``, wall time), the r-alpha bounds estimated versus the paper's, the r-alpha
  design conditions;
* ``results.json``: ``{"runs": [...], "betas": {...}, "design_conditions": {...}, ...}``, one
  object per run with ``scenario``, ``initial_condition``, ``controller`` and the metrics;
* ``figures/``: the paper's Fig. 1 (desired trajectory), Figs. 2-3 (error norm on a log scale with
  the epsilon line, and torques, scenario 1), the error norms of scenarios 2 and 3 with both
  initial conditions, and Figs. 4-5 (both controllers' errors and torques, scenarios 2 and 3, IC2);
* ``runs/<scenario>-<controller>/``: each run's ``result.npz`` and ``summary.json``
  (:meth:`urpc.sim.results.SimulationResult.save` without the CSV table).

Each run is seeded by its scenario file, so a parallel reproduction gives the same series as a
serial one (``tests/test_paper.py`` checks it). Nothing is written into ``out_dir`` before every run
has finished (:func:`urpc.sim.results.write_files`).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..sim.results import NPZ_NAME, SUMMARY_NAME, SimulationResult, write_files

#: The paper's scenarios (Table II number, initial condition) in report order.
PAPER_RUNS = tuple((number, ic) for number in (1, 2, 3) for ic in (1, 2))
#: The two controllers the paper compares.
PAPER_CONTROLLERS = ("interval", "r-alpha")
#: Default output directory of ``urpc reproduce-paper``.
DEFAULT_OUT_DIR = Path("urpc-results") / "paper"
#: Columns of the Markdown table (after scenario, IC and controller).
TABLE_METRICS = (
    ("met", "met", ""),
    ("entry_time", "entry time", "s"),
    ("final_error", "final error", "rad"),
    ("max_error_after_entry", "max error after entry", "rad"),
    ("torque_peak", "torque peak", "N m"),
    ("torque_rms", "torque RMS", "N m"),
    ("torque_variation", "torque variation", "N m/s"),
    ("phi", "phi", "N m s/rad"),
    ("wall_time", "wall time", "s"),
)

_ROBOT = "rr_planar"


def scenario_name(number: int, ic: int) -> str:
    """The shipped scenario of Table II scenario ``number`` with initial condition ``ic``."""
    return f"{_ROBOT}/s{number}_ic{ic}"


def reproduce_paper(
    out_dir: str | Path = DEFAULT_OUT_DIR,
    *,
    progress: bool | Callable[[int, int, str], Any] | None = None,
    duration: float | None = None,
    workers: int = 2,
) -> dict[str, Any]:
    """Run the paper's six scenarios with both controllers and write the report into ``out_dir``.

    Args:
        out_dir: Output directory (created with its parents; files of an earlier reproduction
            are replaced, other files kept).
        progress: ``None``; ``True`` for a tqdm bar on stderr counting finished runs; or a
            callable ``(finished, total, label)`` called after each run.
        duration: Simulated time of every run [s]; ``None`` keeps the scenario files' 10 s.
        workers: Number of processes (``1``: run in this process, one run after the other).

    Returns:
        The content of ``results.json`` plus ``out_dir`` and ``files`` (paths relative to it).

    Raises:
        InputError: ``duration`` or ``workers`` out of range, or a scenario that fails to load.
        SimulationError: a run diverged.
    """
    if duration is not None and not (
        isinstance(duration, int | float) and math.isfinite(duration) and duration > 0
    ):
        raise InputError(f"{duration!r} must be a finite number > 0 [s]", field="duration")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"{workers!r} must be an integer >= 1", field="workers")
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError("exists and is not a directory", source=out_dir, field="out")
    start = time.perf_counter()
    jobs = [(n, ic, c) for n, ic in PAPER_RUNS for c in PAPER_CONTROLLERS]
    # The 10 kHz runs take longest: start them first so that two workers finish together.
    order = sorted(jobs, key=lambda job: (job[0] != 2, job[0] != 3))
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.runs.", dir=out_dir.parent))
    try:
        runs = _run_all(order, duration, scratch, workers, _Reporter(progress, len(jobs)))
        runs = {job: runs[job] for job in jobs}  # report order
        document = _document(runs, duration, workers)
        writers = _figure_writers(runs)
        for run in runs.values():
            folder = scratch / run["folder"]
            for name in (NPZ_NAME, SUMMARY_NAME):
                writers[f"runs/{run['folder']}/{name}"] = _mover(folder / name)
        document["wall_time"] = time.perf_counter() - start
        writers["results.md"] = _text_writer(results_markdown(document))
        writers["results.json"] = _text_writer(json.dumps(_jsonable(document), indent=2) + "\n")
        write_files(out_dir, writers)
        files = sorted(writers)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return {**document, "out_dir": str(out_dir), "files": files}


# ============================================================================== running
def _run_one(number: int, ic: int, controller: str, duration: float | None, scratch: str) -> dict:
    """One run (in a worker process): simulate, save npz + summary, return what the report needs."""
    from .scenario import build, build_controller, load_scenario, simulate_setup

    scenario = load_scenario(scenario_name(number, ic))
    if duration is not None:
        scenario = scenario.with_overrides(duration=duration)
    setup = build(scenario)
    law = build_controller(setup, controller)
    result = simulate_setup(setup, law)
    folder = f"s{number}_ic{ic}-{controller}"
    result.save(Path(scratch) / folder, csv=False)
    run = {"result": result, "folder": folder}
    if controller == "r-alpha":
        betas = law.betas
        run["betas"] = {**betas.as_dict(), "n_samples": betas.n_samples, "seed": betas.seed}
        run["design_conditions"] = _conditions(law)
        run["gains"] = {
            "r": law.r,
            "alpha": law.alpha,
            "Lambda": law.Lambda.tolist(),
            "Q": law.Q.tolist(),
            "eta": law.eta,
        }
    return run


def _run_all(jobs, duration, scratch: Path, workers: int, reporter) -> dict:
    runs = {}
    if workers == 1:
        for job in jobs:
            runs[job] = _run_one(*job, duration, str(scratch))
            reporter.done(_label(job))
        reporter.close()
        return runs
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_run_one, *job, duration, str(scratch)): job for job in jobs}
        reporter.open()
        try:
            for future in as_completed(futures):
                job = futures[future]
                runs[job] = future.result()
                reporter.done(_label(job))
        except BaseException:
            for future in futures:
                future.cancel()
            raise
        finally:
            reporter.close()
    return runs


def _label(job) -> str:
    number, ic, controller = job
    return f"scenario {number} IC{ic} {controller}"


class _Reporter:
    """Progress over runs: a tqdm bar on stderr, a callable, or nothing."""

    def __init__(self, progress, total: int):
        self.progress, self.total, self.finished, self.bar = progress, total, 0, None

    def open(self) -> None:
        if self.progress is True and self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, file=sys.stderr, unit="run", desc="reproduce-paper")

    def done(self, label: str) -> None:
        self.open()
        self.finished += 1
        if self.bar is not None:
            self.bar.set_postfix_str(label, refresh=False)
            self.bar.update(1)
        elif callable(self.progress):
            self.progress(self.finished, self.total, label)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _conditions(controller) -> dict[str, Any]:
    conditions = controller.design_conditions()
    return {
        **asdict(conditions),
        "rate_Lambda": conditions.rate_Lambda,
        "rate_Q": conditions.rate_Q,
        "tolerance": conditions.tolerance,
        "hold": conditions.hold,
    }


# ============================================================================== report
def _document(runs: dict, duration: float | None, workers: int) -> dict:
    from ..control.r_alpha import PAPER_BETAS, RAlphaController

    rows = []
    for (number, ic, controller), run in runs.items():
        result: SimulationResult = run["result"]
        rows.append(
            {
                "scenario": number,
                "initial_condition": f"IC{ic}",
                "controller": controller,
                "scenario_file": scenario_name(number, ic),
                "sample_period": result.sample_period,
                "disturbance_bound": result.disturbance_bound,
                "duration": result.duration,
                **result.summary(),
            }
        )
    r_alpha = next(run for run in runs.values() if "betas" in run)
    distinct = {json.dumps(run["betas"], sort_keys=True) for run in runs.values() if "betas" in run}
    if len(distinct) != 1:  # the files share one r-alpha design; say so if someone changed that
        raise InputError(
            "the r-alpha runs of the paper scenarios were designed with different betas",
            field="controller_options.r-alpha",
        )
    gains = r_alpha["gains"]
    dof = len(gains["Q"])
    with_paper_betas = RAlphaController(PAPER_BETAS, dof, **gains)
    return {
        "paper": "Giusti & Althoff, Ultimate Robust Performance Control of Rigid Robot "
        "Manipulators using Interval Arithmetic, Sec. IV",
        "duration": duration if duration is not None else rows[0]["duration"],
        "workers": workers,
        "wall_time": None,  # set when the report is complete
        "runs": rows,
        "betas": {**r_alpha["betas"], "paper": PAPER_BETAS.as_dict()},
        "design_conditions": {
            "estimated_betas": r_alpha["design_conditions"],
            "paper_betas": _conditions(with_paper_betas),
        },
    }


def results_markdown(document: dict) -> str:
    """The Markdown report of a reproduction (the content of ``results.md``)."""
    lines = [
        "# Reproduction of Giusti & Althoff, Sec. IV",
        "",
        f"Generated by `urpc reproduce-paper`: {len(document['runs'])} runs of "
        f"{document['duration']:g} s each, {document['workers']} worker process(es), "
        f"{document['wall_time']:.1f} s wall time in total. Scenario (Table II): 1 continuous "
        "time, no disturbance, epsilon = 1e-3 rad; 2 sampled at 10 kHz; 3 sampled at 1 kHz; 2 and "
        "3 with a disturbance ||d|| <= 10 N m unknown to the controllers, epsilon = 1e-2 rad.",
        "",
        "| scenario | IC | controller | "
        + " | ".join(f"{title} [{unit}]" if unit else title for _, title, unit in TABLE_METRICS)
        + " |",
        "|" + " --- |" * (3 + len(TABLE_METRICS)),
    ]
    for run in document["runs"]:
        cells = [str(run["scenario"]), run["initial_condition"], run["controller"]]
        cells += [_cell(key, run[key]) for key, _, _ in TABLE_METRICS]
        lines.append("| " + " | ".join(cells) + " |")
    betas = document["betas"]
    lines += [
        "",
        "`met`: `||e|| < epsilon` from `entry time` to the end, and at least over the final "
        "quarter of the run. `final error`: max `||e||` over the last second. `torque variation`: "
        "total variation of the commanded torque per second (the chattering index; sampled runs "
        "are recorded at their control rate, continuous ones at 1 kHz).",
        "",
        "## r-alpha bounds",
        "",
        f"Estimated by sampling ({betas['n_samples']} samples, seed {betas['seed']}) versus the "
        "paper's values:",
        "",
        "| bound | estimated | paper |",
        "| --- | --- | --- |",
    ]
    for name in ("beta0", "beta1", "beta2", "beta3"):
        lines.append(f"| {name} | {betas[name]:.4g} | {betas['paper'][name]:.4g} |")
    lines += ["", "## r-alpha design conditions (paper gains r, alpha, Lambda, Q, eta)", ""]
    lines += ["| betas | lambda_min(Q) >= alpha beta1 | eta <= eta_max | all hold |"]
    lines += ["| --- | --- | --- | --- |"]
    for label, key in (("estimated", "estimated_betas"), ("paper", "paper_betas")):
        c = document["design_conditions"][key]
        lines.append(
            f"| {label} | {c['lambda_min_Q']:.4g} >= {c['required_Q']:.4g}: {_yes(c['rate_Q'])} "
            f"| {c['eta']:.3g} <= {c['eta_max']:.3g}: {_yes(c['tolerance'])} | {_yes(c['hold'])} |"
        )
    return "\n".join(lines) + "\n"


def _cell(key: str, value: Any) -> str:
    if value is None:
        return "-"
    if key == "met":
        return "yes" if value else "no"
    if key == "wall_time":
        return f"{value:.1f}"
    return f"{value:.4g}"


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


# ============================================================================== figures
def _figure_writers(runs: dict) -> dict[str, Callable[[Path], None]]:
    """The figures (Fig. 1-5 and the sampled scenarios' error norms), as writers."""
    from ..sim.plotting import compare, plot_errors, plot_overview, plot_reference
    from .scenario import build, load_scenario

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


def _text_writer(text: str) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_text(text)

    return write


def _mover(source: Path) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        os.replace(source, path)

    return write


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return _jsonable(value.item())
    return value
