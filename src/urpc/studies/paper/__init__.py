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
has finished (:func:`urpc.atomic.write_files`).

Modules: ``runs`` (the twelve runs in worker processes), ``report`` (``results.json`` and
``results.md``), ``figures`` and ``reproduce`` (:func:`reproduce_paper`).
"""

from .report import TABLE_METRICS, results_markdown
from .reproduce import DEFAULT_OUT_DIR, reproduce_paper
from .runs import PAPER_CONTROLLERS, PAPER_RUNS, scenario_name

__all__ = [
    "DEFAULT_OUT_DIR",
    "PAPER_CONTROLLERS",
    "PAPER_RUNS",
    "TABLE_METRICS",
    "reproduce_paper",
    "results_markdown",
    "scenario_name",
]
