"""The performance suite of ``urpc bench`` (``docs/performance.md``): its settings, its design targets,
the run and its Markdown table."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .bound_timing import bench_bounds
from .control_step import CONTROL_SCENARIOS, control_step_call
from .loop_latency import DEFAULT_LOOP_STEPS, loop_latency
from .machine import machine_info
from .robots import BENCHMARK_ROBOTS
from .throughput import (
    assembly_synthesis_time,
    campaign_throughput,
    simulation_speed,
    synthesis_time,
)

#: Methods of the suite's ``rho`` figures.
SUITE_METHODS = ("hull", "vertex", "rigorous")
#: The paper's scenarios 2 (10 kHz) and 3 (1 kHz) whose simulation speed is measured.
SIM_SCENARIOS = ("rr_planar/s2_ic1", "rr_planar/s3_ic1")
#: Shipped modular assemblies whose synthesis (compose + load + synthesize) is timed.
SYNTHESIS_ASSEMBLIES = ("arm_3dof", "arm_4dof", "arm_4dof_vacuum")
#: The scenario of the campaign-throughput figure.
CAMPAIGN_SCENARIO = "rr_planar/s3_ic1"
#: Top-level keys of :func:`run_benchmarks`.
SUITE_KEYS = (
    "machine", "rnea", "rho", "rho_over_rnea", "control_step", "loop_step", "sim_speed",
    "synthesis", "campaign_runs_per_minute",
)  # fmt: skip


@dataclass(frozen=True)
class SuiteSettings:
    """What :func:`run_benchmarks` measures, and how long (durations in [s]).

    Attributes:
        robots: Robots of the ``rho``, RNEA, control-step and synthesis figures.
        methods: Bound methods of the ``rho`` figures.
        repeats: Timed batches of the ``rho``, RNEA and control-step figures (median kept).
        loop_steps: Steps of the robot control loop timed per robot (the ``loop_step``
            percentiles; a few thousand keep the run short, ``urpc bench --loop-steps`` more).
        sim_scenarios: Shipped scenarios whose simulation speed is measured.
        sim_duration: Simulated time of each of them; ``None``: the scenario's own (10 s).
        synthesis_repeats: Timed repeats of each synthesis (median kept).
        assemblies: Shipped assemblies whose synthesis is timed (keys ``assembly/<name>``).
        campaign_scenario: Scenario of the campaign.
        campaign_runs: Runs of the campaign.
        campaign_workers: Worker processes of the campaign.
        campaign_duration: Simulated time of each campaign run; ``None``: the scenario's own.
    """

    robots: tuple[str, ...] = BENCHMARK_ROBOTS
    methods: tuple[str, ...] = SUITE_METHODS
    repeats: int = 101
    loop_steps: int = DEFAULT_LOOP_STEPS
    sim_scenarios: tuple[str, ...] = SIM_SCENARIOS
    sim_duration: float | None = None
    synthesis_repeats: int = 7
    assemblies: tuple[str, ...] = SYNTHESIS_ASSEMBLIES
    campaign_scenario: str = CAMPAIGN_SCENARIO
    campaign_runs: int = 8
    campaign_workers: int = 2
    campaign_duration: float | None = None

    @classmethod
    def quick(cls, **changes) -> SuiteSettings:
        """Fewer repeats, 1000 loop steps, 2 s simulations, a campaign of 4 runs of 2 s;
        ``changes`` on top."""
        quick = dict(
            repeats=21,
            loop_steps=1000,
            sim_duration=2.0,
            synthesis_repeats=3,
            campaign_runs=4,
            campaign_duration=2.0,
        )
        return cls(**{**quick, **changes})


@dataclass(frozen=True)
class Target:
    """A design target of a figure: ``value <= limit``, or ``value >= limit`` when ``at_least``
    (``limit`` in the figure's unit: seconds, or a ratio)."""

    limit: float
    at_least: bool = False

    def met(self, value: float) -> bool:
        return value >= self.limit if self.at_least else value <= self.limit


#: The targets of issues 3 and 6, by ``(figure, case)``; ``synthesis`` applies to every entry.
TARGETS: dict[tuple[str, str], Target] = {
    ("rho", "rr_planar/hull"): Target(10e-6),
    ("rho", "rr_planar/vertex"): Target(10e-6),
    ("rho", "panda/hull"): Target(15e-6),
    ("rho", "panda/vertex"): Target(25e-6),
    ("sim_speed", "rr_planar/s2_ic1"): Target(1.0, at_least=True),
}
#: Synthesis target [s] (issue 6: up to 7 modules).
SYNTHESIS_TARGET = Target(50e-3)


def run_benchmarks(
    quick: bool = False,
    progress: Callable[[str], object] | None = None,
    *,
    settings: SuiteSettings | None = None,
) -> dict[str, dict | float]:
    """The performance suite of ``urpc bench`` (``docs/performance.md``).

    Figures, in [s] unless stated:

    * ``rnea``, ``rho`` and ``control_step`` per robot, timed side by side in the same
      interleaved batches of thread CPU time (:func:`bench_bounds` with the control step as an
      extra call): one nominal ``pin.rnea``; one ``rho`` per method on the
      :func:`benchmark_box`; one :meth:`IntervalPassivityController.output` of the controller of
      the robot's :data:`CONTROL_SCENARIOS` entry (shipped box, default method). ``rho_over_rnea``
      is ``rho / rnea``, the figure that carries over between machines and loads.
    * ``loop_step`` per robot: :func:`loop_latency`, the wall-clock latency of
      :meth:`urpc.robot.loop.ControlLoop.step` over ``loop_steps`` consecutive steps of the same
      controller (``p50``, ``p99``, ``p99_9``, ``max``), next to one RNEA of the same arm timed
      the same way (``rnea``), and ``steps``.
    * ``sim_speed``: simulated seconds per wall second of :data:`SIM_SCENARIOS` (wall time of
      the simulation alone, after synthesis).
    * ``synthesis``: wall time (median) of ``load_robot + load_uncertainty + synthesize`` per
      robot with its control scenario's settings, and of
      :func:`urpc.studies.demo.synthesize_configuration` (compose + load + synthesize) per assembly
      (key ``assembly/<name>``).
    * ``campaign_runs_per_minute``: :func:`urpc.studies.campaign.run_campaign` on the campaign scenario
      with ``campaign_workers`` processes, ``60 runs / wall time`` (pool start-up included).
    * ``machine``: :func:`machine_info`, with ``load_average_end`` at the end.

    Args:
        quick: :meth:`SuiteSettings.quick` instead of the full settings.
        progress: Called with a short message as each part starts.
        settings: What to measure (overrides ``quick``).

    Raises:
        InputError: an unknown robot, method, scenario or assembly.
    """
    if settings is None:
        settings = SuiteSettings.quick() if quick else SuiteSettings()
    say = progress if progress is not None else (lambda message: None)
    machine = machine_info()

    say(f"rho, RNEA and control step ({len(settings.robots)} robots)")
    controllers = {name: control_step_call(name) for name in settings.robots}
    bounds = bench_bounds(
        settings.robots,
        settings.methods,
        settings.repeats,
        extra_calls=lambda name: {"control_step": controllers[name]},
    )
    control_step = {name: bounds["extra"][name]["control_step"] for name in settings.robots}

    loop_step = {}
    for name in settings.robots:
        say(f"loop step latency: {name}, {settings.loop_steps} steps")
        loop_step[name] = loop_latency(name, settings.loop_steps)

    sim_speed = {}
    for name in settings.sim_scenarios:
        say(f"simulation speed: {name}")
        sim_speed[name] = simulation_speed(name, settings.sim_duration)

    synthesis = {}
    for name in settings.robots:
        say(f"synthesis: {name}")
        synthesis[name] = synthesis_time(name, settings.synthesis_repeats)
    for name in settings.assemblies:
        say(f"synthesis: assembly {name}")
        synthesis[f"assembly/{name}"] = assembly_synthesis_time(name, settings.synthesis_repeats)

    say(
        f"campaign: {settings.campaign_runs} runs of {settings.campaign_scenario}, "
        f"{settings.campaign_workers} workers"
    )
    runs_per_minute = campaign_throughput(
        settings.campaign_scenario,
        settings.campaign_runs,
        settings.campaign_workers,
        settings.campaign_duration,
    )
    machine["load_average_end"] = machine_info()["load_average"]
    return {
        "machine": machine,
        "rnea": bounds["rnea"],
        "rho": bounds["rho"],
        "rho_over_rnea": bounds["rho_over_rnea"],
        "control_step": control_step,
        "loop_step": loop_step,
        "sim_speed": sim_speed,
        "synthesis": synthesis,
        "campaign_runs_per_minute": runs_per_minute,
    }


def format_benchmarks(result: dict, settings: SuiteSettings | None = None) -> str:
    """One Markdown table of :func:`run_benchmarks` results, with the :data:`TARGETS`."""
    rnea = result["rnea"]
    rows: list[tuple[str, str, str, str, str, str]] = []

    def add(figure: str, case: str, text: str, ratio: str, key: tuple[str, str], value: float):
        target = SYNTHESIS_TARGET if figure == "synthesis" else TARGETS.get(key)
        if target is None:
            rows.append((figure, case, text, ratio, "-", "-"))
            return
        unit = _target_text(key[0], target)
        rows.append((figure, case, text, ratio, unit, "met" if target.met(value) else "NOT met"))

    for robot, seconds in rnea.items():
        add("RNEA (nominal)", robot, f"{1e6 * seconds:.2f} us", "1", ("rnea", robot), seconds)
    for robot, methods in result["rho"].items():
        for method, seconds in methods.items():
            ratio = f"{result['rho_over_rnea'][robot][method]:.1f}"
            key = ("rho", f"{robot}/{method}")
            add("rho", f"{robot} / {method}", f"{1e6 * seconds:.1f} us", ratio, key, seconds)
    for robot, seconds in result["control_step"].items():
        case = f"{robot} ({CONTROL_SCENARIOS.get(robot, '?')})"
        ratio = f"{seconds / rnea[robot]:.1f}" if robot in rnea else "-"
        add("control step", case, f"{1e6 * seconds:.1f} us", ratio, ("control", robot), seconds)
    for robot, f in result.get("loop_step", {}).items():
        case = f"{robot}, {f['steps']} steps (p50 / p99 / p99.9 / max)"
        text = " / ".join(f"{1e6 * f[key]:.1f}" for key in ("p50", "p99", "p99_9", "max")) + " us"
        ratio = f"{f['p50'] / f['rnea']:.0f}"  # against the RNEA timed in the same way
        add("loop step", case, text, ratio, ("loop_step", robot), f["p50"])
    for scenario, speed in result["sim_speed"].items():
        duration = None if settings is None else settings.sim_duration
        case = scenario if duration is None else f"{scenario} ({duration:g} s run)"
        text = f"{speed:.2f} sim s / wall s"
        add("simulation speed", case, text, "-", ("sim_speed", scenario), speed)
    for name, seconds in result["synthesis"].items():
        add("synthesis", name, f"{1e3 * seconds:.1f} ms", "-", ("synthesis", name), seconds)
    case = "campaign"
    if settings is not None:
        duration = (
            "" if settings.campaign_duration is None else f" of {settings.campaign_duration:g} s"
        )
        case = (
            f"{settings.campaign_runs} runs{duration} of {settings.campaign_scenario}, "
            f"{settings.campaign_workers} workers"
        )
    runs = result["campaign_runs_per_minute"]
    add("campaign throughput", case, f"{runs:.1f} runs / min", "-", ("campaign", case), runs)
    lines = [
        "| figure | case | measured | x RNEA | target | met |",
        "|---|---|---|---|---|---|",
        *("| " + " | ".join(row) + " |" for row in rows),
    ]
    return "\n".join(lines)


def _target_text(figure: str, target: Target) -> str:
    sign = ">=" if target.at_least else "<="
    if figure == "rho":
        return f"{sign} {1e6 * target.limit:g} us"
    if figure == "synthesis":
        return f"{sign} {1e3 * target.limit:g} ms"
    return f"{sign} {target.limit:g}"
