"""The paper's twelve runs (Table II scenarios 1-3, IC1 and IC2, both controllers), one per worker
process, and their progress."""

from __future__ import annotations

from concurrent.futures import as_completed
from dataclasses import asdict
from typing import Any

from ...sim.progress import Progress, report_labelled
from ..pool import submit_all, worker_pool

#: The paper's scenarios (Table II number, initial condition) in report order.
PAPER_RUNS = tuple((number, ic) for number in (1, 2, 3) for ic in (1, 2))
#: The two controllers the paper compares.
PAPER_CONTROLLERS = ("interval", "r-alpha")

_ROBOT = "rr_planar"


def scenario_name(number: int, ic: int) -> str:
    """The shipped scenario of Table II scenario ``number`` with initial condition ``ic``."""
    return f"{_ROBOT}/s{number}_ic{ic}"


def run_one(number: int, ic: int, controller: str, duration: float | None) -> dict:
    """One run (in a worker process): simulate, return the result and what the report needs (the
    parent writes every file at once: a killed reproduction leaves no scratch folder)."""
    from ..scenario import build, build_controller, load_scenario, simulate_setup

    scenario = load_scenario(scenario_name(number, ic))
    if duration is not None:
        scenario = scenario.with_overrides(duration=duration)
    setup = build(scenario)
    law = build_controller(setup, controller)
    result = simulate_setup(setup, law)
    folder = f"s{number}_ic{ic}-{controller}"
    run = {"result": result, "folder": folder}
    if controller == "r-alpha":
        betas = law.betas
        run["betas"] = {**betas.as_dict(), "n_samples": betas.n_samples, "seed": betas.seed}
        run["design_conditions"] = design_conditions(law)
        run["gains"] = {
            "r": law.r,
            "alpha": law.alpha,
            "Lambda": law.Lambda.tolist(),
            "Q": law.Q.tolist(),
            "eta": law.eta,
        }
    return run


def _run_job(arguments: tuple) -> dict:
    return run_one(*arguments)


def run_all(jobs, duration, workers: int, reporter) -> dict:
    runs = {}
    if workers == 1:
        with reporter:
            for job in jobs:
                runs[job] = run_one(*job, duration)
                reporter.done(_label(job))
        return runs
    # Workers ignore Ctrl-C and are terminated at once when this parent is interrupted.
    with worker_pool(workers) as pool:
        jobs = list(jobs)
        submitted = submit_all(pool, _run_job, [(*job, duration) for job in jobs])
        futures = dict(zip(submitted, jobs, strict=True))
        reporter.open()
        try:
            for future in as_completed(futures):
                job = futures[future]
                runs[job] = future.result()
                reporter.done(_label(job))
        except BaseException:
            reporter.close(failed=True)  # no bar left above the error line
            raise
        finally:
            reporter.close()
    return runs


def _label(job) -> str:
    number, ic, controller = job
    return f"scenario {number} IC{ic} {controller}"


class RunReporter(Progress):
    """Progress over runs: a tqdm bar on stderr, a callable ``(finished, total, label)``, or
    nothing (:class:`urpc.sim.progress.Progress`)."""

    def __init__(self, progress, total: int):
        super().__init__(
            progress, total, description="reproduce-paper", unit="run", report=report_labelled
        )

    def open(self) -> None:
        self.start()

    def done(self, label: str) -> None:
        """One more run finished, named ``label``."""
        self.advance(1, label)


def design_conditions(controller) -> dict[str, Any]:
    conditions = controller.design_conditions()
    return {
        **asdict(conditions),
        "rate_Lambda": conditions.rate_Lambda,
        "rate_Q": conditions.rate_Q,
        "tolerance": conditions.tolerance,
        "hold": conditions.hold,
    }
