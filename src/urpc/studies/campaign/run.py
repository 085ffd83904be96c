"""Running a campaign: the draws, then the runs in a local process pool or on a Dask cluster."""

from __future__ import annotations

import concurrent.futures
import json
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ... import __version__
from ...atomic import check_writable
from ...control.certificate_cache import CertificateCache
from ...errors import InputError
from ...model.parameter_box import JOINTS
from ...validation import checked_count
from ..certification import guarantee_of
from ..pool import submit_all, worker_pool
from ..scenario import Scenario, build, build_controller, load_scenario
from .draws import draw_runs
from .progress import CampaignProgress
from .result import CampaignResult
from .store import LOCK_NAME, STORE_NAME, CampaignStore
from .worker import RunOutcome, RunTask, run_one

#: The most runs of one campaign: their draws are made, and held, before the first run starts.
MAX_RUNS = 100_000


class CampaignInterrupted(KeyboardInterrupt):
    """A campaign stopped by Ctrl-C (SIGINT): the workers are stopped, the finished runs are kept
    in the records of ``directory`` (``None`` without ``out``) and ``--resume`` continues it.

    Attributes:
        done: Runs recorded, of ``total``.
        directory: The campaign folder, or ``None``.
    """

    def __init__(self, done: int, total: int, directory: Path | None):
        super().__init__(f"campaign interrupted: {done} of {total} runs done")
        self.done, self.total, self.directory = done, total, directory


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
    out: str | Path | None = None,
    resume: bool = False,
    certify: bool = True,
    certificate_cache: bool | CertificateCache = True,
    refresh_certificate: bool = False,
) -> CampaignResult:
    """Run ``runs`` closed-loop simulations of ``scenario`` with drawn true parameters,
    disturbance seeds and initial states (rules in the module docstring), in parallel.

    With ``out``, every run is recorded in ``out/runs.sqlite`` as it finishes
    (:mod:`urpc.studies.campaign.store`), the folder is locked for the campaign, and the outputs
    (``runs.csv``, ``summary.json``, ``histogram.png``) are built from the records at the end;
    ``resume=True`` continues the campaign recorded there (same settings), running only the
    runs not yet recorded: the result is bit-identical to an uninterrupted campaign.

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
        out: Campaign folder for the records and the outputs, or ``None`` (nothing written).
        resume: Continue the campaign recorded in ``out``.
        certify: Compute the scenario's certificate first (once for every run); ``False``
            records ``certified: None``, ``not_certified: "not computed (--no-certify)"``.
        certificate_cache: ``True`` (the default folder), a
            :class:`~urpc.control.certificate_cache.CertificateCache`, or ``False``: where the
            certificate is read from when this configuration's was computed before.
        refresh_certificate: Compute the certificate even when cached, and replace the record.

    Raises:
        InputError: a bad argument or scenario, an unreachable scheduler; with ``out``: a folder
            in use by another campaign, records without ``resume``, records of other settings.
        CampaignInterrupted: Ctrl-C; the finished runs are kept in ``out``.
    """
    start = time.perf_counter()
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    workers = checked_count("workers", workers, 1)
    runs = checked_count("runs", runs, 1)
    if runs > MAX_RUNS:
        raise InputError(
            f"{runs} runs: at most {MAX_RUNS} in one campaign (every run is drawn before the "
            "first starts); split it into campaigns of other seeds",
            field="runs",
        )
    seed = checked_count("seed", seed, 0)
    if isinstance(ic_spread, bool) or not isinstance(ic_spread, int | float | np.floating):
        raise InputError(f"{ic_spread!r} must be a finite number >= 0 [epsilon]", field="ic_spread")
    store = None
    settings = campaign_settings(scenario, runs, seed, ic_spread, vertex_runs)
    if out is not None:
        out = check_writable(out)
        if (out / STORE_NAME).exists() or (out / LOCK_NAME).exists():
            store = CampaignStore.open(out, settings, resume=resume)  # refuse at once
    try:
        setup = build(scenario)
        # Bad controller options fail here, before any worker starts; one certificate for all.
        guarantee = guarantee_of(
            setup,
            build_controller(setup),
            certify=certify,
            cache=certificate_cache,
            refresh=refresh_certificate,
            progress=progress is True,  # a callable counts runs, not the certificate's stages
        )
        specs, draws = draw_runs(setup, runs, seed, ic_spread=ic_spread, vertex_runs=vertex_runs)
        if out is not None and store is None:
            store = CampaignStore.open(out, settings, resume=resume)
        outcomes = _execute(scenario, specs, store, workers, scheduler, connect_timeout, progress)
        result = CampaignResult(
            scenario=scenario,
            outcomes=outcomes,
            seed=int(seed),
            draws=draws,
            parameter_names=_parameter_names(setup),
            joint_names=setup.robot.joint_names,
            workers=None if scheduler is not None else workers,
            scheduler=scheduler,
            wall_time=time.perf_counter() - start,
            certificate=guarantee.fields,
            certificate_source=guarantee.source_line,
        )
        if store is not None:
            result.save(out)  # still under the folder's lock
            store.mark_finished()
    except BaseException:
        if store is not None:
            store.discard()  # nothing recorded: nothing left behind
        raise
    if store is not None:
        store.close()
    return result


def campaign_settings(
    scenario: Scenario, runs: int, seed: int, ic_spread: float, vertex_runs: int | None
) -> dict[str, Any]:
    """What determines a campaign's runs (a resumed campaign must have the same)."""
    document = json.loads(json.dumps(scenario.to_dict(), sort_keys=True))
    if document.get("disturbance_model") == "ball":  # the default: records made before it match
        del document["disturbance_model"]
    return {
        "urpc": __version__,
        "scenario": document,
        "scenario_file": None if scenario.source is None else str(scenario.source),
        "runs": runs,
        "seed": seed,
        "ic_spread": float(ic_spread),
        "vertex_runs": vertex_runs,
    }


def _execute(scenario, specs, store, workers, scheduler, connect_timeout, progress):
    """Run what is not recorded yet; every outcome is recorded as it arrives. Returns all the
    outcomes in run order (those of the records when there is a store: what is reported is
    what is recorded)."""
    done = {} if store is None else store.outcomes()
    for index, outcome in done.items():
        if index >= len(specs) or outcome.spec != specs[index]:
            raise InputError(
                f"the recorded run {index} does not match its draw (recorded by another version "
                f"of urpc?); delete {STORE_NAME} to start over, or give another --out",
                source=store.directory,
            )
    document = json.dumps(scenario.to_dict(), sort_keys=True)
    source = None if scenario.source is None else str(scenario.source)
    tasks = [RunTask(document, source, spec) for spec in specs if spec.index not in done]
    collected = dict(done)
    report = CampaignProgress(progress, len(specs))

    def record(outcome: RunOutcome) -> None:
        if store is not None:
            store.add(outcome)
        collected[outcome.spec.index] = outcome
        report.advance()

    try:
        if not tasks:
            pass
        elif scheduler is not None:
            _run_dask(tasks, scheduler, connect_timeout, report, record, len(done))
        elif workers == 1:
            _start(report, len(done))
            for task in tasks:
                record(run_one(task))
        else:
            _run_pool(tasks, workers, report, record, len(done))
    except KeyboardInterrupt:
        report.close(failed=True)
        directory = None if store is None else store.directory
        # What the store holds: the interrupt may fall between a run's commit and its count.
        recorded = len(collected) if store is None else store.count()
        raise CampaignInterrupted(recorded, len(specs), directory) from None
    except BaseException:
        report.close(failed=True)  # no bar left above the error line
        raise
    finally:
        report.close()
    if store is not None:
        collected = store.outcomes()
    return tuple(collected[index] for index in range(len(specs)))


def _start(report: CampaignProgress, done: int) -> None:
    report.start()
    if done:
        report.advance(done)


def _parameter_names(setup) -> tuple[tuple[str, str, int], ...]:
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
    return names


def _run_pool(tasks: Sequence[RunTask], workers: int, report, record, done: int) -> None:
    # "spawn": fresh interpreters on every platform (no fork of a threaded parent). The pool's
    # workers ignore Ctrl-C and are terminated at once when this parent is interrupted.
    with worker_pool(workers, start_method="spawn") as pool:
        futures = submit_all(pool, run_one, tasks)
        _start(report, done)
        for future in concurrent.futures.as_completed(futures):
            record(future.result())


def _run_dask(
    tasks: Sequence[RunTask], address: str, timeout: float, report: CampaignProgress, record, done
) -> None:
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
        if protocol not in ("tcp", "tls"):  # Dask's other comms are in-process or need extras
            raise ValueError(f"the protocol '{protocol}' is not tcp:// or tls://")
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
    try:
        futures = client.map(run_one, tasks, pure=False)
        _start(report, done)
        try:
            with client.as_current():  # as_completed looks up the current client
                for future in as_completed(futures):
                    record(future.result())
        except BaseException:
            client.cancel(futures)
            raise
    finally:
        client.close()
