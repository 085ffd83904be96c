"""Running a campaign: the draws, then the runs in a local process pool or on a Dask cluster."""

from __future__ import annotations

import concurrent.futures
import json
import multiprocessing
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.parameter_box import JOINTS
from ..certification import certificate_fields
from ..scenario import Scenario, build, build_controller, load_scenario
from .draws import checked_count, draw_runs
from .progress import CampaignProgress
from .result import CampaignResult
from .worker import RunOutcome, RunTask, run_one


def run_campaign(
    scenario: Scenario | str | Path,
    runs: int,
    *,
    workers: int = 2,
    scheduler: str | None = None,
    seed: int = 0,
    progress: bool | Callable[[int, int], Any] | None = None,
    ic_spread: float = 2.0,
    vertex_runs: int | None = None,
    connect_timeout: float = 10.0,
) -> CampaignResult:
    """Run ``runs`` closed-loop simulations of ``scenario`` with drawn true parameters,
    disturbance seeds and initial states (rules in the module docstring), in parallel.

    Args:
        scenario: A :class:`Scenario`, a scenario file or a shipped name (``rr_planar/s3_ic1``).
        runs: Number of runs, >= 1.
        workers: Local worker processes (1: run in this process); ignored with ``scheduler``.
        scheduler: Address of a running Dask scheduler (``tcp://host:8786``); its workers need
            urpc installed. ``None``: a local process pool.
        seed: Campaign seed; the same seed gives the same draws and results.
        progress: ``True`` for a tqdm bar on stderr, or a callable ``(done, total)``.
        ic_spread: Half-width of the initial-offset box [epsilon].
        vertex_runs: Number of vertex runs (default: see :func:`draw_runs`).
        connect_timeout: Time allowed to reach the Dask scheduler [s].

    Raises:
        InputError: a bad argument or scenario, an unreachable scheduler.
    """
    start = time.perf_counter()
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    workers = checked_count("workers", workers, 1)
    setup = build(scenario)
    # Bad controller options fail here, before any worker starts; one certificate for all runs.
    guarantee = certificate_fields(setup, build_controller(setup))
    specs, draws = draw_runs(setup, runs, seed, ic_spread=ic_spread, vertex_runs=vertex_runs)
    document = json.dumps(scenario.to_dict(), sort_keys=True)
    source = None if scenario.source is None else str(scenario.source)
    tasks = [RunTask(document, source, spec) for spec in specs]
    report = CampaignProgress(progress, len(tasks))
    try:
        if scheduler is not None:
            outcomes = _run_dask(tasks, scheduler, connect_timeout, report)
        elif workers == 1:
            report.start()
            outcomes = []
            for task in tasks:
                outcomes.append(run_one(task))
                report.advance()
        else:
            outcomes = _run_pool(tasks, workers, report)
    except BaseException:
        report.close(failed=True)  # no bar left above the error line
        raise
    finally:
        report.close()
    outcomes.sort(key=lambda o: o.spec.index)
    names = tuple(
        (b.link, b.fields[k], int(k)) for b in setup.box.links for k in np.flatnonzero(b.uncertain)
    )
    joints = setup.box.joints
    if joints is not None:  # the drives' draws: columns "joint.field", flat index into (3, dof)
        rows, columns = np.nonzero(joints.uncertain)
        names += tuple(
            (JOINTS, joints.name(r, c), int(r * joints.dof + c))
            for r, c in zip(rows, columns, strict=True)
        )
    return CampaignResult(
        scenario=scenario,
        outcomes=tuple(outcomes),
        seed=int(seed),
        draws=draws,
        parameter_names=names,
        joint_names=setup.robot.joint_names,
        workers=None if scheduler is not None else workers,
        scheduler=scheduler,
        wall_time=time.perf_counter() - start,
        certificate=guarantee,
    )


def _run_pool(tasks: Sequence[RunTask], workers: int, report: CampaignProgress) -> list[RunOutcome]:
    # "spawn": fresh interpreters on every platform (no fork of a threaded parent).
    context = multiprocessing.get_context("spawn")
    outcomes = []
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        futures = [pool.submit(run_one, task) for task in tasks]
        report.start()
        try:
            for future in concurrent.futures.as_completed(futures):
                outcomes.append(future.result())
                report.advance()
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
    return outcomes


def _run_dask(
    tasks: Sequence[RunTask], address: str, timeout: float, report: CampaignProgress
) -> list[RunOutcome]:
    try:
        from dask.distributed import Client, as_completed
        from distributed.comm import parse_address
        from distributed.comm.addressing import parse_host_port
    except ImportError:
        raise InputError(
            "--scheduler needs Dask: pip install 'dask[distributed]'", field="scheduler"
        ) from None
    hint = "start one with 'dask scheduler' and 'dask worker ADDRESS', or drop --scheduler"
    try:
        protocol, location = parse_address(address)
        if protocol in ("tcp", "tls"):
            parse_host_port(location)
    except ValueError as exc:
        raise InputError(
            f"'{address}' is not a scheduler address like tcp://127.0.0.1:8786 ({exc}); {hint}",
            field="scheduler",
        ) from None
    try:
        client = Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(
            f"cannot reach the Dask scheduler at '{address}' ({exc}); {hint}", field="scheduler"
        ) from None
    outcomes = []
    try:
        futures = client.map(run_one, tasks, pure=False)
        report.start()
        try:
            with client.as_current():  # as_completed looks up the current client
                for future in as_completed(futures):
                    outcomes.append(future.result())
                    report.advance()
        except BaseException:
            client.cancel(futures)
            raise
    finally:
        client.close()
    return outcomes
