"""One run of a campaign, as a worker executes it: the scenario built once per worker thread, the
run's true plant, initial state and disturbance seed swapped in."""

from __future__ import annotations

import dataclasses
import json
import math
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ...errors import SimulationError
from ..scenario import ScenarioSetup, build, build_controller, parse_scenario, simulate_setup
from .draws import RunSpec


@dataclass(frozen=True)
class RunTask:
    """One run as shipped to a worker: plain data only (the scenario travels as its document,
    which also keys the worker's cache of built setups, and is re-parsed once per worker)."""

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


def run_one(task: RunTask) -> RunOutcome:
    """Simulate one run of a campaign (the function that workers execute): the scenario's setup
    with the run's true plant, initial state and disturbance seed."""
    start = time.thread_time()
    setup, controller = _prepared(task.document, task.source)
    spec = task.spec
    point = spec.parameter_point
    run_setup = dataclasses.replace(
        setup,
        scenario=setup.scenario.model_copy(update={"seed": spec.seed}),
        plant=setup.box.plant(point),
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
