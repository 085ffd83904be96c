"""Timing and tightness figures of the bound methods (``docs/bounds.md``), and the performance suite
(``docs/performance.md``).

:func:`bench_bounds` times one evaluation of ``rho`` (Slotine-Li regressor included) per method and
robot, next to one nominal ``pinocchio.rnea`` call timed in the same run, so that the ratio carries
over to other machines. :func:`tightness` measures ``width(enclosure) / width(sampled inner hull)``
against plants built with Pinocchio at dense parameter samples (uniform draws and vertices).

The benchmark boxes (:func:`benchmark_box`): for the RR arm the paper's Table I box shipped with
the robot; for the UR5 and the Panda a physical box on the child link of every joint (+-10 % mass,
+-0.01 m on each CoM coordinate, +-10 % on the diagonal of the inertia about the CoM), so that the
``vertex`` method works on ``N`` links by ``N`` joints.

Modules: ``robots`` (robots, boxes, methods by name), ``timing`` (interleaved CPU timing),
``bound_timing`` (the ``rho`` figures), ``control_step`` (a control step and its profile),
``loop_latency`` (the robot control loop's step: p50 / p99 / p99.9 / max next to one RNEA),
``throughput`` (simulation, synthesis, campaign wall times), ``machine``, ``suite`` (``urpc
bench``: settings, targets, the run and its table) and ``tightness``.
"""

from .bound_timing import bench_bounds, format_timings
from .control_step import (
    CONTROL_SCENARIOS,
    DRIVE_ROBOTS,
    PROFILE_COLUMNS,
    control_setup,
    format_profile,
    profile_control_step,
)
from .loop_latency import DEFAULT_LOOP_STEPS, LATENCY_KEYS, format_latency, loop_latency
from .machine import format_machine, machine_info
from .robots import (
    ALL_LINKS_ENTRY,
    BENCHMARK_ROBOTS,
    VARIANTS,
    benchmark_box,
    benchmark_robot,
    make_method,
)
from .suite import (
    CAMPAIGN_SCENARIO,
    SIM_SCENARIOS,
    SUITE_KEYS,
    SUITE_METHODS,
    SYNTHESIS_ASSEMBLIES,
    SYNTHESIS_TARGET,
    TARGETS,
    SuiteSettings,
    Target,
    format_benchmarks,
    run_benchmarks,
)
from .throughput import campaign_throughput, simulation_speed, synthesis_time
from .tightness import Tightness, sample_points, tightness
from .timing import time_calls

__all__ = [
    "DRIVE_ROBOTS",
    "ALL_LINKS_ENTRY",
    "BENCHMARK_ROBOTS",
    "CAMPAIGN_SCENARIO",
    "CONTROL_SCENARIOS",
    "DEFAULT_LOOP_STEPS",
    "LATENCY_KEYS",
    "PROFILE_COLUMNS",
    "SIM_SCENARIOS",
    "SUITE_KEYS",
    "SUITE_METHODS",
    "SYNTHESIS_ASSEMBLIES",
    "SYNTHESIS_TARGET",
    "TARGETS",
    "VARIANTS",
    "SuiteSettings",
    "Target",
    "Tightness",
    "bench_bounds",
    "benchmark_box",
    "benchmark_robot",
    "campaign_throughput",
    "control_setup",
    "format_benchmarks",
    "format_latency",
    "format_machine",
    "format_profile",
    "format_timings",
    "loop_latency",
    "machine_info",
    "make_method",
    "profile_control_step",
    "run_benchmarks",
    "sample_points",
    "simulation_speed",
    "synthesis_time",
    "tightness",
    "time_calls",
]
