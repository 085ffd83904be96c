"""Timing and tightness figures of the bound methods (``docs/bounds.md``).

:func:`bench_bounds` times one evaluation of ``rho`` (Slotine-Li regressor included) per method and
robot, next to one nominal ``pinocchio.rnea`` call timed in the same run, so that the ratio carries
over to other machines. :func:`tightness` measures ``width(enclosure) / width(sampled inner hull)``
against plants built with Pinocchio at dense parameter samples (uniform draws and vertices).

The benchmark boxes (:func:`benchmark_box`): for the RR arm the paper's Table I box shipped with
the robot; for the UR5 and the Panda a physical box on the child link of every joint (+-10 % mass,
+-0.01 m on each CoM coordinate, +-10 % on the diagonal of the inertia about the CoM), so that the
``vertex`` method works on ``N`` links by ``N`` joints.
"""

from __future__ import annotations

import copy
import gc
import itertools
import math
import os
import platform
import statistics
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..bounds import METHODS, BoundMethod, make_bound
from ..bounds.vertex import VertexBound
from ..errors import InputError
from ..model.catalog import default_uncertainty
from ..model.robot import Robot, load_robot
from ..model.uncertainty import LinkBox, ParameterBox, load_uncertainty, parse_uncertainty

#: The robots of the figures; the Panda's fingers are locked (7 arm joints).
BENCHMARK_ROBOTS = ("rr_planar", "ur5", "panda")
_LOCKED = {"panda": ["panda_finger_joint1", "panda_finger_joint2"]}
#: Extra method variants, benchmarked next to the registered methods.
VARIANTS: dict[str, Callable[[Robot, ParameterBox], BoundMethod]] = {
    "vertex-plain": lambda robot, box: VertexBound(robot, box, slope_margin=False),
}
#: Uncertainty of every link of the UR5 and Panda benchmark boxes (the uncertainty file format).
ALL_LINKS_ENTRY = {
    "mass": "10%",
    **{f"com_{axis}": "+-0.01" for axis in "xyz"},
    **{f"i{axis}{axis}": "10%" for axis in "xyz"},
}


def benchmark_robot(name: str) -> Robot:
    """A robot of the figures (the Panda with its fingers locked)."""
    return load_robot(name, locked_joints=_LOCKED.get(name, ()))


def benchmark_box(robot: Robot) -> ParameterBox:
    """The RR arm's shipped Table I box; else :data:`ALL_LINKS_ENTRY` on the child link of every
    joint (the link whose frame is the joint frame): ``N`` links for ``N`` joints."""
    if robot.name == "rr_planar":
        return load_uncertainty(default_uncertainty("rr_planar"), robot)
    links = {
        link.name: dict(ALL_LINKS_ENTRY)
        for link in robot.links
        if link.joint_index > 0 and link.placement.isIdentity() and link.inertia.mass > 0
    }
    return parse_uncertainty({"links": links}, robot)


def make_method(name: str, robot: Robot, box: ParameterBox) -> BoundMethod:
    """A registered method (:data:`urpc.bounds.METHODS`) or a :data:`VARIANTS` entry.

    Raises:
        InputError: unknown name (the message lists the valid ones).
    """
    if name in VARIANTS:
        return VARIANTS[name](robot, box)
    if name not in METHODS:
        valid = ", ".join([*METHODS, *VARIANTS])
        raise InputError(f"unknown bound method '{name}'; valid: {valid}", field="method")
    return make_bound(name, robot, box)


# ============================================================================== timing
def time_calls(
    functions: dict[str, Callable[[], object]], repeats: int = 51, batch_seconds: float = 2e-3
) -> dict[str, float]:
    """Median over ``repeats`` timed batches of the time of one call of each function [s].

    Time is the CPU time of the calling thread (``time.thread_time``), so that other processes
    sharing the machine do not count; batches of the functions alternate (round robin), so that
    what remains of their load (shared caches) hits all of them alike. The batch size of each
    function makes a batch last about ``batch_seconds``."""
    calls = {}
    for name, function in functions.items():
        function()  # warm up caches and lazy allocations
        start = time.thread_time()
        function()
        calls[name] = max(1, int(batch_seconds / max(time.thread_time() - start, 1e-7)))
    samples: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(repeats):
        for name, function in functions.items():
            n = calls[name]
            start = time.thread_time()
            for _ in range(n):
                function()
            samples[name].append((time.thread_time() - start) / n)
    return {name: statistics.median(values) for name, values in samples.items()}


def bench_bounds(
    robots: Sequence[str] = BENCHMARK_ROBOTS,
    methods: Sequence[str] | None = None,
    repeats: int = 51,
    seed: int = 0,
    extra_calls: Callable[[str], dict[str, Callable[[], object]]] | None = None,
) -> dict[str, dict]:
    """Time one ``rho`` evaluation (``Y_SL`` included) per robot and method.

    Args:
        robots: Robot names (:func:`benchmark_robot`), each with its :func:`benchmark_box`.
        methods: Method names (registered or :data:`VARIANTS`); ``None``: all registered ones.
        repeats: Timed batches per figure (the median is reported).
        seed: Seed of the (fixed) state at which ``rho`` is evaluated.
        extra_calls: ``robot name -> {name: function}``: more calls to time per robot, in the
            same interleaved batches as ``rho`` and RNEA (their ratios are then side by side).

    Returns:
        ``{"rho": {robot: {method: seconds}}, "rho_over_rnea": {robot: {method: ratio}},
        "rnea": {robot: seconds}, "dof": {robot: n}, "scaling": {robot: {"dof": n, "links":
        n_links, "vertex": seconds}}}`` (``scaling`` when ``vertex`` is timed), seconds per call;
        with ``extra_calls`` also ``"extra": {robot: {name: seconds}}``.
    """
    names = list(METHODS) if methods is None else list(methods)
    result: dict[str, dict] = {"rho": {}, "rho_over_rnea": {}, "rnea": {}, "scaling": {}, "dof": {}}
    if extra_calls is not None:
        result["extra"] = {}
    rng = np.random.default_rng(seed)
    for robot_name in robots:
        robot = benchmark_robot(robot_name)
        box = benchmark_box(robot)
        extra = {} if extra_calls is None else extra_calls(robot_name)
        timings = _time_robot(robot, box, names, repeats, rng, extra)
        if extra_calls is not None:
            result["extra"][robot_name] = {name: timings.pop(name) for name in extra}
        rnea = timings.pop("rnea")
        result["rnea"][robot_name] = rnea
        result["dof"][robot_name] = robot.dof
        result["rho"][robot_name] = timings
        result["rho_over_rnea"][robot_name] = {name: t / rnea for name, t in timings.items()}
        if "vertex" in timings:
            result["scaling"][robot_name] = {
                "dof": robot.dof,
                "links": len(box.uncertain_links),
                "vertex": timings["vertex"],
            }
    return result


def _time_robot(
    robot: Robot,
    box: ParameterBox,
    names: list[str],
    repeats: int,
    rng: np.random.Generator,
    extra: dict[str, Callable[[], object]] | None = None,
) -> dict[str, float]:
    """Seconds per ``rho`` call of each method, per nominal RNEA call (key ``rnea``) and per call
    of each ``extra`` function (its key), all in the same interleaved batches."""
    nominal = box.nominal_robot(robot)
    q, qd, qd_a = (rng.uniform(-1.0, 1.0, robot.dof) for _ in range(3))
    qdd_a = 5.0 * rng.uniform(-1.0, 1.0, robot.dof)
    data = nominal.model.createData()
    config = nominal.configuration(q)
    functions = {"rnea": lambda: pin.rnea(nominal.model, data, config, qd, qdd_a)}
    for name in names:
        method = make_method(name, robot, box)
        functions[name] = lambda m=method: m.rho(q, qd, qd_a, qdd_a)
    clash = set(extra or {}) & set(functions)
    if clash:
        raise ValueError(f"extra calls {sorted(clash)} clash with the method names or 'rnea'")
    functions.update(extra or {})
    return time_calls(functions, repeats)


def format_timings(result: dict[str, dict]) -> str:
    """A Markdown table of :func:`bench_bounds` results (microseconds, and ratios to RNEA),
    followed by the ``vertex scaling`` line when ``vertex`` was timed."""
    robots = list(result["rho"])
    methods = list(dict.fromkeys(m for r in robots for m in result["rho"][r]))
    lines = [
        "| robot | dof | RNEA [us] | " + " | ".join(f"{m} [us] (x RNEA)" for m in methods) + " |",
        "|---" * (3 + len(methods)) + "|",
    ]
    for robot in robots:
        dof = result["dof"][robot]
        cells = [
            f"{1e6 * result['rho'][robot][m]:.1f} ({result['rho_over_rnea'][robot][m]:.1f})"
            for m in methods
        ]
        lines.append(
            f"| {robot} | {dof} | {1e6 * result['rnea'][robot]:.2f} | " + " | ".join(cells) + " |"
        )
    if result["scaling"]:
        scaling = ", ".join(
            f"{s['dof']} joints x {s['links']} links: {1e6 * s['vertex']:.1f} us"
            for s in result["scaling"].values()
        )
        lines += ["", f"vertex scaling: {scaling}"]
    return "\n".join(lines)


# ============================================================================== full suite
#: Methods of the suite's ``rho`` figures.
SUITE_METHODS = ("hull", "vertex", "rigorous")
#: The scenario whose controller, box and settings each robot's control step and synthesis use:
#: the robot's 1 kHz scenario (sampled-data gain limit on); for the RR arm, scenario 3 (the paper's
#: law unchanged).
CONTROL_SCENARIOS = {
    "rr_planar": "rr_planar/s3_ic1",
    "ur5": "ur5/sampled",
    "panda": "panda/sampled",
}
#: The paper's scenarios 2 (10 kHz) and 3 (1 kHz) whose simulation speed is measured.
SIM_SCENARIOS = ("rr_planar/s2_ic1", "rr_planar/s3_ic1")
#: Shipped modular assemblies whose synthesis (compose + load + synthesize) is timed.
SYNTHESIS_ASSEMBLIES = ("arm_3dof", "arm_4dof", "arm_4dof_vacuum")
#: The scenario of the campaign-throughput figure.
CAMPAIGN_SCENARIO = "rr_planar/s3_ic1"
#: Top-level keys of :func:`run_benchmarks`.
SUITE_KEYS = (
    "machine", "rnea", "rho", "rho_over_rnea", "control_step", "sim_speed", "synthesis",
    "campaign_runs_per_minute",
)  # fmt: skip


@dataclass(frozen=True)
class SuiteSettings:
    """What :func:`run_benchmarks` measures, and how long (durations in [s]).

    Attributes:
        robots: Robots of the ``rho``, RNEA, control-step and synthesis figures.
        methods: Bound methods of the ``rho`` figures.
        repeats: Timed batches of the ``rho``, RNEA and control-step figures (median kept).
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
        """Fewer repeats, 2 s simulations, a campaign of 4 runs of 2 s; ``changes`` on top."""
        quick = dict(
            repeats=21,
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


def machine_info() -> dict[str, object]:
    """CPU count, processor, load average, Python, numpy and Pinocchio versions, date (UTC)."""
    processor = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                processor = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        available = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        available = os.cpu_count()
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except OSError:
        load = None
    return {
        "cpu_count": os.cpu_count(),
        "cpus_available": available,
        "processor": processor,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "pinocchio": pin.__version__,
        "load_average": load,
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }


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
    controllers = {name: _control_step_call(name) for name in settings.robots}
    bounds = bench_bounds(
        settings.robots,
        settings.methods,
        settings.repeats,
        extra_calls=lambda name: {"control_step": controllers[name]},
    )
    control_step = {name: bounds["extra"][name]["control_step"] for name in settings.robots}

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
        synthesis[f"assembly/{name}"] = _assembly_synthesis_time(name, settings.synthesis_repeats)

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
        "sim_speed": sim_speed,
        "synthesis": synthesis,
        "campaign_runs_per_minute": runs_per_minute,
    }


def control_setup(robot_name: str):
    """The scenario setup and the synthesized controller of ``robot_name``'s
    :data:`CONTROL_SCENARIOS` entry, and a fixed state ``(t, q, qd, reference, state)`` on its
    trajectory: ``t = 1.3`` s, ``q = q_d + e`` with ``||e|| = 2 epsilon`` (alternating signs),
    ``qd = qd_d``, the gain integral ``s = 0.05`` rad s (Theorem 2).

    Raises:
        InputError: a robot without an entry (the message lists them).
    """
    from .scenario import build, build_controller, load_scenario

    setup = build(load_scenario(_control_scenario(robot_name)))
    controller = build_controller(setup, "interval")
    t = 1.3
    reference = setup.trajectory.reference(t)
    dof = setup.robot.dof
    signs = np.where(np.arange(dof) % 2 == 0, 1.0, -1.0)
    q = reference.q + 2.0 * setup.scenario.epsilon * signs / np.sqrt(dof)
    qd = reference.qd.copy()
    state = controller.initial_state() + 0.05
    return setup, controller, (t, q, qd, reference, state)


def _control_scenario(robot_name: str) -> str:
    """The :data:`CONTROL_SCENARIOS` entry of a robot.

    Raises:
        InputError: a robot without an entry (the message lists them).
    """
    if robot_name not in CONTROL_SCENARIOS:
        valid = ", ".join(CONTROL_SCENARIOS)
        raise InputError(
            f"no control scenario for robot '{robot_name}'; valid: {valid}", field="robot"
        )
    return CONTROL_SCENARIOS[robot_name]


def _control_step_call(robot_name: str) -> Callable[[], object]:
    _, controller, args = control_setup(robot_name)
    return lambda: controller.output(*args)


def profile_control_step(
    robots: Sequence[str] = BENCHMARK_ROBOTS, repeats: int = 101
) -> dict[str, dict[str, float]]:
    """Where one control step's time goes, per robot [s per call], timed side by side.

    Parts of :meth:`IntervalPassivityController.output` (with the default, regressor-based
    method): ``regressor`` (``Y_SL``, the Pinocchio regressor calls), ``bound`` (the enclosure
    from ``Y_SL``), ``nominal`` (``Y_SL pi0``), ``gain_limit`` (``M0(q)`` by CRBA, its ``eigh``
    and the modal product; only with the sampled-data gain limit), of which ``inertia``
    (:meth:`Robot.M`: CRBA and symmetrization), ``crba`` (the bare Pinocchio call) and ``eigh``
    alone; ``arithmetic`` (a replica of the array arithmetic of ``output`` around those calls:
    ``e``, ``qd_a``, ``qdd_a``, ``r``, ``rho``, its norm, the gain, the sum); ``other`` =
    ``output`` minus the parts (call overhead, and what the parts lose when they run together
    rather than alone); ``output_without_gain_limit`` (the same step with the paper's law, so
    that the difference is the gain limit's cost inside the step); and ``rnea`` for scale.
    """
    return {robot_name: _profile_robot(robot_name, repeats) for robot_name in robots}


def _profile_robot(robot_name: str, repeats: int) -> dict[str, float]:
    _, controller, args = control_setup(robot_name)
    t, q, qd, reference, state = args
    bound, robot = controller.bound, controller.robot
    if not bound.uses_regressor:
        raise InputError(
            f"the {bound.name} method has no regressor path to profile", field="method"
        )
    e, ed = reference.q - q, reference.qd - qd
    qd_a, qdd_a = reference.qd + controller.Kr * e, reference.qdd + controller.Kr * ed
    r = ed + controller.Kr * e
    Y = bound.regressor(q, qd, qd_a, qdd_a)
    pi0 = np.asarray(robot.nominal_parameters, dtype=float)
    lower, upper = bound.enclose_regressor(Y)
    nominal = Y @ pi0
    Kr = controller.Kr
    kappa_P, kappa_I, phi_P, phi_I = (
        controller.kappa_P,
        controller.kappa_I,
        controller.phi_P,
        controller.phi_I,
    )

    def arithmetic():
        # A replica of output()'s own array arithmetic around the calls timed separately.
        e = reference.q - q
        ed = reference.qd - qd
        Kr_e = Kr * e
        _ = reference.qd + Kr_e, reference.qdd + Kr * ed
        r = ed + Kr_e
        rho = np.maximum(-lower, upper)
        rho_norm = math.sqrt(rho @ rho)
        s = state[0]
        gain = (kappa_P + kappa_I * s) * rho_norm + phi_P + phi_I * s
        return nominal + gain * r

    data = robot.model.createData()
    config = robot.configuration(q)
    M = robot.M(q)
    functions: dict[str, Callable[[], object]] = {
        "output": lambda: controller.output(*args),
        "regressor": lambda: bound.regressor(q, qd, qd_a, qdd_a),
        "bound": lambda: bound.enclose_regressor(Y),
        "nominal": lambda: Y @ pi0,
        "arithmetic": arithmetic,
        "rnea": lambda: pin.rnea(robot.model, data, config, qd, qdd_a),
    }
    if controller.sample_period is not None:
        # The private method is exactly what output() runs for the gain limit.
        functions["gain_limit"] = lambda: controller._sampled_feedback(q, 1e3, r)
        unlimited = copy.copy(controller)  # shares the bound method; only the period differs
        unlimited.sample_period = None
        functions["output_without_gain_limit"] = lambda: unlimited.output(*args)
        functions["inertia"] = lambda: robot.M(q)
        functions["crba"] = lambda: pin.crba(robot.model, data, config)
        functions["eigh"] = lambda: np.linalg.eigh(M)
    times = time_calls(functions, repeats)
    parts = ("regressor", "bound", "nominal", "arithmetic", "gain_limit")
    times["other"] = times["output"] - sum(times.get(name, 0.0) for name in parts)
    return times


#: Columns of :func:`format_profile`: key, heading.
PROFILE_COLUMNS = (
    ("output", "control step"),
    ("output_without_gain_limit", "step without gain limit"),
    ("regressor", "regressor Y_SL"),
    ("bound", "bound from Y_SL"),
    ("nominal", "nominal Y_SL pi0"),
    ("arithmetic", "array arithmetic"),
    ("gain_limit", "gain limit"),
    ("inertia", "of which M0(q)"),
    ("crba", "of which bare crba"),
    ("eigh", "of which eigh"),
    ("other", "other"),
    ("rnea", "RNEA"),
)


def format_profile(profile: dict[str, dict[str, float]]) -> str:
    """A Markdown table of :func:`profile_control_step`: microseconds and share of the step."""
    lines = [
        "| robot | " + " | ".join(f"{heading} [us]" for _, heading in PROFILE_COLUMNS) + " |",
        "|---" * (1 + len(PROFILE_COLUMNS)) + "|",
    ]
    for robot, times in profile.items():
        cells = []
        for key, _ in PROFILE_COLUMNS:
            if key not in times:
                cells.append("-")
            elif key in ("output", "output_without_gain_limit", "rnea"):
                cells.append(f"{1e6 * times[key]:.1f}")
            else:
                cells.append(f"{1e6 * times[key]:.1f} ({100 * times[key] / times['output']:.0f} %)")
        lines.append(f"| {robot} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def simulation_speed(scenario_name: str, duration: float | None = None) -> float:
    """Simulated seconds per wall second of one run of a scenario (``duration``: overrides the
    scenario's [s]); the wall time of :func:`urpc.studies.scenario.simulate_setup` alone."""
    from .scenario import build, build_controller, load_scenario, simulate_setup

    scenario = load_scenario(scenario_name).with_overrides(duration=duration)
    setup = build(scenario)
    controller = build_controller(setup)
    gc.collect()
    start = time.perf_counter()
    simulate_setup(setup, controller)
    return scenario.duration / (time.perf_counter() - start)


def synthesis_time(robot_name: str, repeats: int = 7) -> float:
    """Median wall time [s] of ``load_robot + load_uncertainty + synthesize`` with the settings
    of the robot's :data:`CONTROL_SCENARIOS` entry (after one untimed warm-up run)."""
    from ..control.synthesis import synthesize
    from .scenario import interval_synthesis_options, load_scenario

    scenario = load_scenario(_control_scenario(robot_name))
    options = interval_synthesis_options(scenario)

    def chain() -> None:
        robot = load_robot(scenario.robot, scenario.locked_joints)
        box = load_uncertainty(scenario.uncertainty, robot)
        synthesize(robot, box, scenario.epsilon, **options)

    chain()  # warm-up: imports and the example-robot-data lookup happen once per process
    samples = []
    for _ in range(repeats):
        gc.collect()
        start = time.perf_counter()
        chain()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def _assembly_synthesis_time(name: str, repeats: int) -> float:
    from .demo import synthesize_configuration

    return synthesize_configuration(name, repeats=repeats).timing.total


def campaign_throughput(
    scenario_name: str, runs: int, workers: int = 2, duration: float | None = None
) -> float:
    """Runs per minute of :func:`urpc.studies.campaign.run_campaign` (wall time, process start-up
    included); ``duration`` overrides the scenario's [s]."""
    from .campaign import run_campaign
    from .scenario import load_scenario

    scenario = load_scenario(scenario_name).with_overrides(duration=duration)
    start = time.perf_counter()
    result = run_campaign(scenario, runs, workers=workers, seed=0)
    return 60.0 * result.runs / (time.perf_counter() - start)


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


def format_machine(machine: dict) -> str:
    """One line: processor, CPUs, load average, versions and date."""
    load = machine.get("load_average")
    end = machine.get("load_average_end")
    load_text = "n/a" if load is None else ", ".join(f"{x:g}" for x in load)
    if end is not None:
        load_text += " (start); " + ", ".join(f"{x:g}" for x in end) + " (end)"
    return (
        f"{machine['processor']}, {machine['cpus_available']} of {machine['cpu_count']} CPUs, "
        f"load average {load_text}; Python {machine['python']}, numpy {machine['numpy']}, "
        f"Pinocchio {machine['pinocchio']}; {machine['date']}"
    )


# ============================================================================== tightness
@dataclass(frozen=True)
class Tightness:
    """``width(enclosure) / width(sampled inner hull)`` of one method on one box.

    Attributes:
        median, worst: Over states and joints (joints the box cannot move are left out).
        ratios: Every ratio, ``states x joints`` (``nan`` for the joints left out).
    """

    median: float
    worst: float
    ratios: np.ndarray


def sample_points(box: ParameterBox, rng: np.random.Generator, n_uniform: int, n_vertices: int):
    """Uniform draws of ``box``, plus all its vertices (``2^n <= 1024``) or ``n_vertices`` random
    ones."""
    points = [box.sample(rng) for _ in range(n_uniform)]
    n = box.n_uncertain
    if n <= 10:
        points += [box.vertex(k) for k in range(2**n)]
    else:
        points += [box.vertex(int(k)) for k in rng.integers(0, 2**n, size=n_vertices)]
    return points


def tightness(
    robot: Robot,
    box: ParameterBox,
    methods: Iterable[str],
    n_states: int = 20,
    n_uniform: int = 300,
    n_vertices: int = 300,
    seed: int = 0,
    com_grid: int = 5,
) -> dict[str, Tightness]:
    """Width ratios of ``methods`` against a sampled inner hull of ``w`` at random states.

    ``w = (M - M0) qdd_a + (C - C0) qd_a + g - g0`` per sample, with the plant built at the
    sample (``box.plant``) and Pinocchio's ``crba``, ``computeCoriolisMatrix``,
    ``computeGeneralizedGravity``; states: ``q`` uniform in [-pi, pi] [rad], ``qd``, ``qd_a``
    normal [rad/s], ``qdd_a`` normal times 5 [rad/s^2].

    The samples: uniform draws of the box and its vertices (:func:`sample_points`), and, because
    random draws of a box with many coordinates rarely come near its extremes, two assembled
    points per joint and state. They are built link by link from samples that vary one part of
    one link (the other links and parts nominal): mass and CoM on a grid (both mass ends,
    ``com_grid`` points per uncertain CoM axis, ends included), the inertia about the CoM at its
    vertices, a barycentric box at its vertices. Each part takes the sample that maximizes
    (minimizes) ``w_i``; ``w`` is linear in the inertia about the CoM and link parameters are
    independent, so these choices combine, and the assembled point is evaluated on its own plant
    like the others. A joint whose sampled width is below 1e-6 of the widest joint's is left out.
    """
    rng = np.random.default_rng(seed)
    nominal = box.nominal_robot(robot)
    plants = [box.plant(robot, p) for p in sample_points(box, rng, n_uniform, n_vertices)]
    parts = [part for b in box.uncertain_links for part in _link_parts(b, com_grid)]
    part_plants = [[box.plant(robot, {name: c}) for c in points] for name, _, points in parts]
    bounds = {name: make_method(name, robot, box) for name in methods}
    ratios: dict[str, list[np.ndarray]] = {name: [] for name in bounds}

    def mismatch(plant, q, qd, qd_a, qdd_a, M0, C0, g0):
        return (plant.M(q) - M0) @ qdd_a + (plant.C(q, qd) - C0) @ qd_a + plant.g(q) - g0

    for _ in range(n_states):
        q = rng.uniform(-np.pi, np.pi, robot.dof)
        qd, qd_a = rng.normal(size=robot.dof), rng.normal(size=robot.dof)
        qdd_a = 5.0 * rng.normal(size=robot.dof)
        state = (q, qd, qd_a, qdd_a, nominal.M(q), nominal.C(q, qd), nominal.g(q))
        w = [mismatch(p, *state) for p in plants]
        part_w = [np.array([mismatch(p, *state) for p in group]) for group in part_plants]
        for i in range(robot.dof if parts else 0):
            for pick in (np.argmax, np.argmin):
                point = {b.link: b.nominal.copy() for b in box.uncertain_links}
                for (name, indices, points), values in zip(parts, part_w, strict=True):
                    point[name][indices] = points[int(pick(values[:, i]))][indices]
                w.append(mismatch(box.plant(robot, point), *state))
        w = np.array(w)
        sampled = w.max(axis=0) - w.min(axis=0)
        moved = sampled > 1e-6 * max(sampled.max(), 1e-300)
        for name, bound in bounds.items():
            lower, upper = bound.enclose(q, qd, qd_a, qdd_a)
            ratio = np.full(robot.dof, np.nan)
            ratio[moved] = (upper - lower)[moved] / sampled[moved]
            ratios[name].append(ratio)
    result = {}
    for name, rows in ratios.items():
        table = np.array(rows)
        finite = table[np.isfinite(table)]
        result[name] = Tightness(float(np.median(finite)), float(finite.max()), table)
    return result


def _link_parts(link_box: LinkBox, com_grid: int) -> list[tuple[str, slice, list[np.ndarray]]]:
    """``(link, coordinate slice, points)`` of the independently varied parts of a link box:
    mass and CoM on a grid and the inertia about the CoM at its vertices (physical), or all the
    coordinates at their vertices (barycentric); points are full coordinate vectors."""
    if link_box.kind == "barycentric":
        return [(link_box.link, slice(0, 10), _grid(link_box, dict.fromkeys(range(10), 2)))]
    mass_and_com = {0: 2, 1: com_grid, 2: com_grid, 3: com_grid}
    return [
        (link_box.link, slice(0, 4), _grid(link_box, mass_and_com)),
        (link_box.link, slice(4, 10), _grid(link_box, dict.fromkeys(range(4, 10), 2))),
    ]


def _grid(link_box: LinkBox, counts: dict[int, int]) -> list[np.ndarray]:
    """Points of ``link_box`` on a grid: ``counts[k]`` evenly spaced values (ends included) of
    each uncertain coordinate ``k``, the other coordinates nominal."""
    axes = [
        np.linspace(link_box.lower[k], link_box.upper[k], n)
        if link_box.upper[k] > link_box.lower[k]
        else np.array([link_box.nominal[k]])
        for k, n in counts.items()
    ]
    points = []
    for values in itertools.product(*axes):
        point = link_box.nominal.copy()
        point[list(counts)] = values
        points.append(point)
    return points
