"""Tightness of the bound methods: ``width(enclosure) / width(sampled inner hull)`` against plants
built with Pinocchio at dense parameter samples (uniform draws, vertices and assembled extremes)."""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ...model.robot import Robot
from ...model.uncertainty import LinkBox, ParameterBox
from .robots import make_method


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
        # Random bits, as a Python integer (more than 63 coordinates overflow numpy's integers).
        for bits in rng.integers(0, 2, size=(n_vertices, n)):
            points.append(box.vertex(sum(int(b) << j for j, b in enumerate(bits))))
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
