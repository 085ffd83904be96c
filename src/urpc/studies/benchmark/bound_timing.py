"""The ``rho`` figures: one evaluation per method and robot (Slotine-Li regressor included), next to
one nominal ``pinocchio.rnea`` call timed in the same batches, so that the ratio carries over to
other machines."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin

from ...bounds import METHODS
from ...model.robot import Robot
from ...model.uncertainty import ParameterBox
from .robots import BENCHMARK_ROBOTS, benchmark_box, benchmark_robot, make_method
from .timing import time_calls


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
