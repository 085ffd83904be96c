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

With an output folder, each run is recorded as it finishes in ``runs.sqlite`` (``store``:
append-only, committed per run, the folder locked while the campaign runs); the outputs are built
from the records, and an interrupted or killed campaign resumes (``resume=True``, ``urpc campaign
--resume``) to results bit-identical to an uninterrupted one. Ctrl-C terminates the workers at
once (:mod:`urpc.studies.pool`) and raises :class:`CampaignInterrupted`.

Modules: ``draws`` (what each run draws), ``worker`` (one run on a worker), ``run``
(:func:`run_campaign`: local pool or Dask), ``progress``, ``result`` (:class:`CampaignResult`),
``figures`` and ``outputs`` (the files, written atomically), ``store`` (the records).
"""

from ...model.parameter_point import MAX_DRAWS, PSEUDO_INERTIA_TOLERANCE, physically_consistent
from .draws import RunSpec, VertexRunsWarning, draw_runs
from .figures import plot_campaign
from .outputs import HISTOGRAM_NAME, RUNS_NAME, SUMMARY_NAME, check_writable
from .result import METRIC_COLUMNS, CampaignResult
from .run import CampaignInterrupted, campaign_settings, run_campaign
from .store import LOCK_NAME, STORE_NAME, CampaignStore
from .worker import RunOutcome, RunTask, run_one

__all__ = [
    "HISTOGRAM_NAME",
    "LOCK_NAME",
    "STORE_NAME",
    "CampaignInterrupted",
    "CampaignStore",
    "campaign_settings",
    "MAX_DRAWS",
    "METRIC_COLUMNS",
    "PSEUDO_INERTIA_TOLERANCE",
    "RUNS_NAME",
    "SUMMARY_NAME",
    "CampaignResult",
    "RunOutcome",
    "RunSpec",
    "RunTask",
    "VertexRunsWarning",
    "check_writable",
    "draw_runs",
    "physically_consistent",
    "plot_campaign",
    "run_campaign",
    "run_one",
]
