"""What each run of a campaign draws: its true parameters (a vertex of the box or a uniform draw,
physically consistent), its disturbance seed and its initial state, from ``(seed, run index)``
alone (rules in :mod:`urpc.studies.campaign`)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ...errors import InputError
from ...model.parameter_point import (
    MAX_DRAWS,
    physically_consistent,
    sample_rigid_point,
)
from ...model.point import JOINTS, ParameterPoint
from ...model.uncertainty import ParameterBox
from ...validation import checked_count
from ...wording import count
from ..scenario import ScenarioSetup

#: The largest initial offset a campaign draws per joint [rad or m]: ``ic_spread * epsilon``.
MAX_OFFSET = 1.0


class VertexRunsWarning(UserWarning):
    """More vertex runs were asked for than the campaign has runs, or the box vertices."""


@dataclass(frozen=True)
class RunSpec:
    """What run ``index`` of a campaign draws (units in brackets).

    Attributes:
        index: Run index, ``0 .. runs - 1``.
        kind: ``"vertex"`` or ``"uniform"``.
        vertex: Vertex index (bit ``k`` picks the upper end of uncertain coordinate ``k``, as in
            :meth:`ParameterBox.vertex`), ``None`` for a uniform draw.
        seed: Seed of the run's disturbance sequence.
        point: True parameters, link or payload name -> its 10 box coordinates, and
            ``"<joints>"`` -> the ``(3, dof)`` joint parameters row by row, when drawn
            (:attr:`parameter_point` gives the :class:`~urpc.model.point.ParameterPoint`).
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

    @property
    def parameter_point(self) -> ParameterPoint:
        """The run's true parameters as a :class:`~urpc.model.point.ParameterPoint`."""
        point = dict(self.point)
        if JOINTS in point:  # stored row by row
            point[JOINTS] = np.reshape(point[JOINTS], (3, -1))
        return ParameterPoint.coerce(point)


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
    runs = checked_count("runs", runs, 1)
    seed = checked_count("seed", seed, 0)
    if not (math.isfinite(ic_spread) and ic_spread >= 0):
        raise InputError(f"{ic_spread!r} must be a finite number >= 0 [epsilon]", field="ic_spread")
    epsilon = setup.scenario.epsilon
    if ic_spread * epsilon > MAX_OFFSET:
        raise InputError(
            f"{ic_spread:g} epsilon = {ic_spread * epsilon:.3g} per joint: the initial "
            f"offsets are a perturbation of the reference's start, at most {MAX_OFFSET:g} rad "
            f"(or m); give at most {MAX_OFFSET / epsilon:.3g}",
            field="ic_spread",
        )
    total = 2**box.n_uncertain
    run_sequence, selection_sequence = np.random.SeedSequence(seed).spawn(2)
    if vertex_runs is None:
        vertex_runs = total if total <= runs else runs // 2
    requested = checked_count("vertex_runs", vertex_runs, 0)
    vertex_runs = min(requested, runs, total)
    if requested > vertex_runs:
        limit = f"the {count(runs, 'run')}" if requested > runs else f"the box's {total} vertices"
        warnings.warn(
            f"vertex_runs {requested} exceeds {limit}: runs only {vertex_runs} vertex "
            f"{'run' if vertex_runs == 1 else 'runs'}",
            VertexRunsWarning,
            stacklevel=2,
        )
    if vertex_runs == total:
        candidates = iter(range(total))
    else:
        candidates = box.random_vertices(np.random.default_rng(selection_sequence))
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
                point={k: tuple(np.ravel(v).tolist()) for k, v in point.as_dict().items()},
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


def _consistent_draw(
    box: ParameterBox, rng: np.random.Generator
) -> tuple[dict[str, np.ndarray], int]:
    return sample_rigid_point(box, rng, MAX_DRAWS)
