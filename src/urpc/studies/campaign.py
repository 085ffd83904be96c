"""Verification campaigns: one scenario, many true plants, disturbances and initial states.

A campaign checks the guarantee at scale. Run ``i`` of ``runs`` draws, from its own seed:

* the **true parameters**: runs ``0 .. V-1`` are vertices of the box, the others uniform draws
  from it. ``V = 2 ** n_uncertain`` (every vertex) when that is ``<= runs``; otherwise ``runs // 2``
  distinct vertices picked at random. Only physically consistent points are kept: the
  pseudo-inertia ``J = [[Sigma, h], [h^T, m]]`` (Pinocchio's ``PseudoInertia``, ``Sigma =
  tr(I_O)/2 * 1 - I_O``) of every link box point must be positive semi-definite, which is the
  triangle inequality plus ``m >= 0``, and a massless point must carry no inertia at all. An
  inconsistent uniform draw is redrawn; an inconsistent vertex is replaced by a uniform draw.
  Both are counted (``rejected_draws``, ``rejected_vertices``);
* the **disturbance seed** of the run (the scenario's disturbance bound, a new draw sequence);
* the **initial state**: the scenario's ``q0`` plus an offset drawn uniformly in
  ``[-ic_spread * epsilon, ic_spread * epsilon]`` per joint (``ic_spread = 2``: the hull of the
  paper's IC1 ``q = 0`` and IC2 ``q = 2 epsilon (1, -1)``), and the scenario's ``qd0``.

The seeds derive from ``(seed, run index)`` alone through :class:`numpy.random.SeedSequence`
``.spawn`` (which runs are vertices, and which vertices, follows from the run count and the
seed), so a run's draws and result do not depend on the number of workers, on the scheduling
order, or on local versus Dask execution. Runs execute in parallel in a local
process pool (``workers``) or on an existing Dask cluster (``scheduler``); each worker builds the
robot, the box and the controller once per scenario and only swaps the true plant per run.

A run that diverges is recorded (``status = "diverged"``, not met), not raised.
"""

from __future__ import annotations

import concurrent.futures
import csv
import dataclasses
import json
import math
import multiprocessing
import os
import shutil
import sys
import threading
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pinocchio as pin

from ..errors import InputError, SimulationError
from ..model.uncertainty import ParameterBox
from .scenario import (
    Scenario,
    ScenarioSetup,
    build,
    build_controller,
    load_scenario,
    parse_scenario,
    simulate_setup,
)

#: Columns of ``runs.csv`` that carry metrics of the run (after the draw columns).
METRIC_COLUMNS = (
    "status", "met", "entry_time", "final_error", "final_error_over_epsilon",
    "max_error_after_entry", "torque_peak", "torque_rms", "torque_variation", "phi", "kappa",
)  # fmt: skip
#: File names written by :meth:`CampaignResult.save`.
RUNS_NAME, SUMMARY_NAME, HISTOGRAM_NAME = "runs.csv", "summary.json", "histogram.png"
#: Uniform draws tried per run before the box is declared (almost) nowhere physical.
MAX_DRAWS = 1000
#: Relative tolerance on the smallest pseudo-inertia eigenvalue (vertices sit on the boundary).
PSEUDO_INERTIA_TOLERANCE = 1e-12


# ============================================================================ draws
@dataclass(frozen=True)
class RunSpec:
    """What run ``index`` of a campaign draws (units in brackets).

    Attributes:
        index: Run index, ``0 .. runs - 1``.
        kind: ``"vertex"`` or ``"uniform"``.
        vertex: Vertex index (bit ``k`` picks the upper end of uncertain coordinate ``k``, as in
            :meth:`ParameterBox.vertex`), ``None`` for a uniform draw.
        seed: Seed of the run's disturbance sequence.
        point: True parameters, link or payload name -> its 10 box coordinates.
        q0: Initial joint positions [rad]; ``qd0``: velocities [rad/s].
        rejected: Physically inconsistent draws rejected before this one.
    """

    index: int
    kind: Literal["vertex", "uniform"]
    vertex: int | None
    seed: int
    point: Mapping[str, tuple[float, ...]]
    q0: tuple[float, ...]
    qd0: tuple[float, ...]
    rejected: int = 0


def physically_consistent(box: ParameterBox, point: Mapping[str, Any]) -> bool:
    """Whether every link point of ``point`` is a realizable rigid body: its pseudo-inertia
    matrix (Pinocchio's ``PseudoInertia``) is positive semi-definite, and a massless point
    carries no first or second moment either."""
    for name, values in point.items():
        parameters = box.link_box(name).standard_parameters(np.asarray(values, dtype=float))
        if not np.all(np.isfinite(parameters)):
            return False
        pseudo = pin.PseudoInertia.FromDynamicParameters(parameters).toMatrix()
        eigenvalues = np.linalg.eigvalsh(pseudo)
        scale = max(1.0, float(np.abs(eigenvalues).max()))
        if eigenvalues[0] < -PSEUDO_INERTIA_TOLERANCE * scale:
            return False
        if parameters[0] <= 0 and np.abs(pseudo).max() > PSEUDO_INERTIA_TOLERANCE * scale:
            return False
    return True


def draw_runs(
    setup: ScenarioSetup,
    runs: int,
    seed: int = 0,
    *,
    ic_spread: float = 2.0,
    vertex_runs: int | None = None,
) -> tuple[tuple[RunSpec, ...], dict[str, Any]]:
    """The draws of a campaign (see the module docstring for the rules).

    Args:
        setup: The built scenario (its box, ``q0``, ``qd0`` and ``epsilon`` are used).
        runs: Number of runs, >= 1.
        seed: Campaign seed, >= 0.
        ic_spread: Half-width of the initial-offset box, in units of ``epsilon``.
        vertex_runs: Number of vertex runs; ``None``: every vertex when ``2 ** n_uncertain <=
            runs``, else ``runs // 2`` random distinct vertices.

    Returns:
        The run specifications, and statistics: ``vertices`` (vertex runs), ``vertex_total``
        (``2 ** n_uncertain``), ``rejected_draws``, ``rejected_vertices``.

    Raises:
        InputError: bad counts, or no physically consistent point in :data:`MAX_DRAWS` draws.
    """
    box = setup.box
    runs = _count("runs", runs, 1)
    seed = _count("seed", seed, 0)
    if not (math.isfinite(ic_spread) and ic_spread >= 0):
        raise InputError(f"{ic_spread!r} must be a finite number >= 0 [epsilon]", field="ic_spread")
    total = 2**box.n_uncertain
    run_sequence, selection_sequence = np.random.SeedSequence(seed).spawn(2)
    if vertex_runs is None:
        vertex_runs = total if total <= runs else runs // 2
    vertex_runs = min(_count("vertex_runs", vertex_runs, 0), runs, total)
    if vertex_runs == total:
        candidates = iter(range(total))
    else:
        candidates = _random_vertices(box.n_uncertain, np.random.default_rng(selection_sequence))
    epsilon = setup.scenario.epsilon
    specs: list[RunSpec] = []
    rejected_vertices = 0
    for index, run_seed in enumerate(run_sequence.spawn(runs)):
        parameters_seed, disturbance_seed = run_seed.spawn(2)
        rng = np.random.default_rng(parameters_seed)
        kind, vertex, point, rejected = "uniform", None, None, 0
        if index < vertex_runs:
            for candidate in candidates:
                if physically_consistent(box, box.vertex(candidate)):
                    kind, vertex, point = "vertex", candidate, box.vertex(candidate)
                    break
                rejected_vertices += 1
                if vertex_runs == total:
                    break  # every vertex has its slot: an inconsistent one becomes uniform
        if point is None:
            point, rejected = _consistent_draw(box, rng)
        offset = rng.uniform(-ic_spread * epsilon, ic_spread * epsilon, size=setup.q0.shape)
        specs.append(
            RunSpec(
                index=index,
                kind=kind,  # type: ignore[arg-type]
                vertex=vertex,
                seed=int(disturbance_seed.generate_state(1, np.uint64)[0]),
                point={name: tuple(float(v) for v in values) for name, values in point.items()},
                q0=tuple(float(v) for v in setup.q0 + offset),
                qd0=tuple(float(v) for v in setup.qd0),
                rejected=rejected,
            )
        )
    stats = {
        "vertices": sum(spec.kind == "vertex" for spec in specs),
        "vertex_total": total,
        "rejected_draws": sum(spec.rejected for spec in specs),
        "rejected_vertices": rejected_vertices,
    }
    return tuple(specs), stats


def _random_vertices(n_uncertain: int, rng: np.random.Generator):
    """Distinct random vertex indices (bits drawn one per uncertain coordinate)."""
    seen: set[int] = set()
    while len(seen) < 2**n_uncertain:
        bits = rng.integers(0, 2, size=n_uncertain)
        index = sum(int(b) << k for k, b in enumerate(bits))
        if index not in seen:
            seen.add(index)
            yield index


def _consistent_draw(
    box: ParameterBox, rng: np.random.Generator
) -> tuple[dict[str, np.ndarray], int]:
    for rejected in range(MAX_DRAWS):
        point = box.sample(rng)
        if physically_consistent(box, point):
            return point, rejected
    raise InputError(
        f"no physically consistent point in {MAX_DRAWS} uniform draws from the box (pseudo-inertia "
        "not positive semi-definite): tighten the inertia intervals so that the triangle "
        "inequality holds",
        source=box.source,
        field="links",
    )


def _count(name: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InputError(f"{value!r} must be an integer >= {minimum}", field=name)
    return int(value)


# ============================================================================ one run
@dataclass(frozen=True)
class _Task:
    """One run as shipped to a worker: plain data only (a Scenario holds mappingproxies, which
    do not pickle, so the scenario travels as its document and is re-parsed once per worker)."""

    document: str
    source: str | None
    spec: RunSpec


@dataclass(frozen=True)
class RunOutcome:
    """One run's draws and metrics (see :mod:`urpc.sim.metrics`); ``status`` is ``"ok"`` or
    ``"diverged"`` (then ``message`` says where, and ``met`` is false). ``cpu_time`` [s] is the
    CPU time the run took on its worker thread (unlike wall time, it does not grow when other
    programs share the cores)."""

    spec: RunSpec
    status: Literal["ok", "diverged"]
    metrics: Mapping[str, Any]
    message: str = ""
    cpu_time: float = math.nan

    @property
    def met(self) -> bool:
        return bool(self.status == "ok" and self.metrics["met"])


_local = threading.local()  # per thread: Pinocchio data in robots and bounds are scratch space


def _prepared(document: str, source: str | None) -> tuple[ScenarioSetup, Any]:
    cache = getattr(_local, "prepared", None)
    if cache is None:
        cache = _local.prepared = {}
    key = (document, source)
    if key not in cache:
        scenario = parse_scenario(json.loads(document), source=source)
        setup = build(scenario)
        cache.clear()
        cache[key] = (setup, build_controller(setup))
    return cache[key]


def run_one(task: _Task) -> RunOutcome:
    """Simulate one run of a campaign (the function that workers execute): the scenario's setup
    with the run's true plant, initial state and disturbance seed."""
    start = time.thread_time()
    setup, controller = _prepared(task.document, task.source)
    spec = task.spec
    point = {name: np.array(values) for name, values in spec.point.items()}
    run_setup = dataclasses.replace(
        setup,
        scenario=dataclasses.replace(setup.scenario, seed=spec.seed),
        plant=setup.box.plant(setup.robot, point),
        true_point=point,
        true_description=f"campaign run {spec.index} ({spec.kind} of the box)",
        q0=np.array(spec.q0),
        qd0=np.array(spec.qd0),
    )
    try:
        # A diverging run overflows on its way to the divergence check; it is recorded, not noise.
        with np.errstate(over="ignore", invalid="ignore"):
            result = simulate_setup(run_setup, controller)
    except SimulationError as exc:
        return RunOutcome(spec, "diverged", {"met": False}, str(exc), time.thread_time() - start)
    return RunOutcome(spec, "ok", dict(result.metrics), "", time.thread_time() - start)


# ============================================================================ campaign
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
                row[f"{link}.{field}"] = spec.point[link][k]
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
        one unshared core).
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
        }

    def plot(self):
        """Histograms of ``final_error / epsilon`` and ``entry_time``, vertex and uniform runs
        stacked, with the ``epsilon`` line and the entry deadline (a headless matplotlib
        :class:`~matplotlib.figure.Figure`)."""
        return plot_campaign(self)

    def save(self, directory: str | Path) -> Path:
        """Write ``runs.csv``, ``summary.json`` and ``histogram.png`` into ``directory``,
        atomically: everything is written in a temporary sibling folder first, then renamed into
        place (an existing folder receives each file by ``os.replace``).

        Raises:
            InputError: the folder cannot be written (names it).
        """
        return write_outputs(self, Path(directory))


def _mean(values) -> float | None:
    numbers = [v for v in values if v is not None]
    return float(np.mean(numbers)) if numbers else None


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
    workers = _count("workers", workers, 1)
    setup = build(scenario)
    build_controller(setup)  # bad controller options fail here, before any worker starts
    specs, draws = draw_runs(setup, runs, seed, ic_spread=ic_spread, vertex_runs=vertex_runs)
    document = json.dumps(scenario.to_dict(), sort_keys=True)
    source = None if scenario.source is None else str(scenario.source)
    tasks = [_Task(document, source, spec) for spec in specs]
    report = _Progress(progress, len(tasks))
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
    finally:
        report.close()
    outcomes.sort(key=lambda o: o.spec.index)
    names = tuple(
        (b.link, b.fields[k], int(k)) for b in setup.box.links for k in np.flatnonzero(b.uncertain)
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
    )


def _run_pool(tasks: Sequence[_Task], workers: int, report: _Progress) -> list[RunOutcome]:
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
    tasks: Sequence[_Task], address: str, timeout: float, report: _Progress
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


class _Progress:
    """Progress of a campaign: a tqdm bar on stderr (``True``), a callable ``(done, total)``, or
    nothing. The bar appears at :meth:`start`, once the workers are reachable."""

    def __init__(self, progress: Any, total: int):
        if not (progress is None or isinstance(progress, bool) or callable(progress)):
            raise InputError(
                f"{progress!r} is not a progress reporter; give True or a callable (done, total)",
                field="progress",
            )
        self._progress, self._total, self._done, self._bar = progress, total, 0, None

    def start(self) -> None:
        if self._progress is True and self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(total=self._total, file=sys.stderr, unit="run", desc="campaign")

    def advance(self) -> None:
        self._done += 1
        if self._bar is not None:
            self._bar.update(1)
        elif callable(self._progress):
            self._progress(self._done, self._total)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


# ============================================================================ outputs
def check_writable(directory: str | Path) -> Path:
    """Check, without creating anything, that ``directory`` can be written (it exists as a
    writable folder, or its nearest existing ancestor is one); returns it as an absolute path.

    Raises:
        InputError: naming the folder that is in the way.
    """
    directory = Path(directory).expanduser().absolute()
    if directory.exists() and not directory.is_dir():
        raise InputError(
            "exists and is not a folder; give a folder for the outputs", source=directory
        )
    ancestor = directory.parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir() or not os.access(ancestor, os.W_OK | os.X_OK):
        raise InputError(
            f"cannot create the output folder: '{ancestor}' is not a writable folder; choose "
            "another --out",
            source=directory,
        )
    return directory


def write_outputs(result: CampaignResult, directory: Path) -> Path:
    """Write ``runs.csv``, ``summary.json`` and ``histogram.png`` atomically (see
    :meth:`CampaignResult.save`)."""
    directory = check_writable(directory)
    staging = directory.parent / f".{directory.name}.{uuid.uuid4().hex}.tmp"
    writers = {
        RUNS_NAME: _write_csv,
        SUMMARY_NAME: _write_summary,
        HISTOGRAM_NAME: lambda r, path: r.plot().savefig(path, dpi=100),
    }
    try:
        staging.mkdir(parents=True)
        for name, write in writers.items():
            write(result, staging / name)
        if directory.is_dir():
            for name in writers:
                os.replace(staging / name, directory / name)
            staging.rmdir()
        else:
            os.rename(staging, directory)
    except OSError as exc:
        shutil.rmtree(staging, ignore_errors=True)
        raise InputError(f"cannot write the campaign outputs ({exc})", source=directory) from None
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return directory


def _write_csv(result: CampaignResult, path: Path) -> None:
    rows = result.rows()
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(rows[0].keys())
        for row in rows:
            writer.writerow(_cell(value) for value in row.values())


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, float | np.floating):
        return repr(float(value))  # shortest text that reads back to the same double
    return str(value)


def _write_summary(result: CampaignResult, path: Path) -> None:
    with path.open("w") as stream:
        json.dump(result.summary(), stream, indent=2, allow_nan=False)
        stream.write("\n")


def plot_campaign(result: CampaignResult):
    """See :meth:`CampaignResult.plot`."""
    from matplotlib.figure import Figure

    rows = [r for r in result.rows() if r["status"] == "ok"]
    summary = result.summary()
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
        xlabel="final error / epsilon  (max ||e|| over the last second)",
        ylabel="runs",
        title=f"final error, worst {_fmt(summary['worst_final_error_over_epsilon'])} epsilon",
    )

    deadline = 0.75 * result.scenario.duration
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
        xlabel="entry time [s]  (last entry into ||e|| < epsilon)",
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
        f"Campaign {result.scenario.name}: {result.runs} runs "
        f"({summary['vertex_runs']} vertices, {summary['uniform_runs']} uniform), met "
        f"{summary['met']}/{result.runs}, seed {result.seed}"
    )
    return figure


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"
