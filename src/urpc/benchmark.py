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

import itertools
import statistics
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .bounds import METHODS, BoundMethod, make_bound
from .bounds.vertex import VertexBound
from .catalog import default_uncertainty
from .errors import InputError
from .robot import Robot, load_robot
from .uncertainty import LinkBox, ParameterBox, load_uncertainty, parse_uncertainty

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
) -> dict[str, dict]:
    """Time one ``rho`` evaluation (``Y_SL`` included) per robot and method.

    Args:
        robots: Robot names (:func:`benchmark_robot`), each with its :func:`benchmark_box`.
        methods: Method names (registered or :data:`VARIANTS`); ``None``: all registered ones.
        repeats: Timed batches per figure (the median is reported).
        seed: Seed of the (fixed) state at which ``rho`` is evaluated.

    Returns:
        ``{"rho": {robot: {method: seconds}}, "rho_over_rnea": {robot: {method: ratio}},
        "rnea": {robot: seconds}, "dof": {robot: n}, "scaling": {robot: {"dof": n, "links":
        n_links, "vertex": seconds}}}`` (``scaling`` when ``vertex`` is timed), seconds per call.
    """
    names = list(METHODS) if methods is None else list(methods)
    result: dict[str, dict] = {"rho": {}, "rho_over_rnea": {}, "rnea": {}, "scaling": {}, "dof": {}}
    rng = np.random.default_rng(seed)
    for robot_name in robots:
        robot = benchmark_robot(robot_name)
        box = benchmark_box(robot)
        timings = _time_robot(robot, box, names, repeats, rng)
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
    robot: Robot, box: ParameterBox, names: list[str], repeats: int, rng: np.random.Generator
) -> dict[str, float]:
    """Seconds per ``rho`` call of each method, and per nominal RNEA call (key ``rnea``)."""
    nominal = box.nominal_robot(robot)
    q, qd, qd_a = (rng.uniform(-1.0, 1.0, robot.dof) for _ in range(3))
    qdd_a = 5.0 * rng.uniform(-1.0, 1.0, robot.dof)
    data = nominal.model.createData()
    config = nominal.configuration(q)
    functions = {"rnea": lambda: pin.rnea(nominal.model, data, config, qd, qdd_a)}
    for name in names:
        method = make_method(name, robot, box)
        functions[name] = lambda m=method: m.rho(q, qd, qd_a, qdd_a)
    return time_calls(functions, repeats)


def format_timings(result: dict[str, dict]) -> str:
    """A Markdown table of :func:`bench_bounds` results (microseconds, and ratios to RNEA)."""
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
    return "\n".join(lines)


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
