"""Certified synthesis of ``Kr``: the error gain whose certificate is best at the requested period.

``Kr`` trades two parts of the sampled-data floor (docs/sampled-data.md §2): the floor is the
bound of ``||r||`` divided by ``min Kr``, so a larger gain divides the quasi-static error and the
disturbance's response, while the perturbation ``b`` of a period grows with ``T Kr`` and the
mismatch with ``Kr`` (``qd_a = qd_d + Kr e``, ``qdd_a`` holds ``Kr ed``). The best gain depends on
the arm, the box, the reference and the period, so it is searched, not tuned by hand: each
candidate is synthesized and certified, and the best certificate wins (certified with the lowest
floor; if none is certified, the largest certified period, then the lowest floor).

The candidates are uniform gains. Per-joint gains cannot do better under this argument: the
floor divides by ``min Kr`` and every other term grows with each joint's gain (``K_r = max Kr``,
times ``sqrt(lambda_U / lambda_L)`` when ``Kr`` is not uniform), so the uniform gain at the
minimum certifies no higher floor and no shorter period (docs/sampled-data.md §3, "Choosing
``Kr`` and the gain ceiling").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from ..errors import InputError
from ..jsonsafe import jsonable
from ..names import KR_CANDIDATES  # the default of synthesis, 3 / sqrt(epsilon), is 30 at 1e-2
from ..trajectories import Trajectory
from .certificate import Certificate, certify
from .interval import IntervalPassivityController


@dataclass(frozen=True)
class GainTrial:
    """One candidate: its gain [1/s] and its certificate."""

    Kr: float
    certificate: Certificate

    def to_dict(self) -> dict:
        """JSON-ready (an infinite floor becomes ``None``)."""
        c = self.certificate
        return jsonable(
            {
                "Kr": self.Kr,
                "certified": c.certified,
                "epsilon_floor": c.epsilon_floor,
                "max_sample_period": c.max_sample_period,
                "dominant_term": c.figures.get("dominant_term"),
            }
        )


@dataclass(frozen=True)
class GainSearch:
    """The outcome: the best trial, its controller, and every trial in the order tried."""

    best: GainTrial
    controller: IntervalPassivityController
    trials: tuple[GainTrial, ...]

    def to_dict(self) -> dict:
        return {"best_Kr": self.best.Kr, "trials": [t.to_dict() for t in self.trials]}


def _rank(trial: GainTrial) -> tuple:
    """Smaller is better: certified first, then the lower floor, then the longer period."""
    c = trial.certificate
    if c.certified:
        return (0, c.epsilon_floor, -c.max_sample_period)
    return (1, -c.max_sample_period, c.epsilon_floor)


def best_gain(
    certify_with: Callable[[float], tuple[IntervalPassivityController, Certificate]],
    candidates: Sequence[float] = KR_CANDIDATES,
    progress: Callable[[GainTrial], None] | None = None,
) -> GainSearch:
    """Certify ``certify_with(Kr)`` for each candidate and keep the best certificate.

    Args:
        certify_with: Synthesizes the controller for a uniform ``Kr`` [1/s] and certifies it.
        candidates: The gains to try [1/s], each finite and > 0.
        progress: Called with each trial as soon as it is certified.

    Raises:
        InputError: no candidates, or a candidate that is not a positive finite number.
    """
    gains = [float(k) for k in candidates]
    if not gains or not all(math.isfinite(k) and k > 0 for k in gains):
        raise InputError(
            f"{list(candidates)!r}: give one or more positive finite gains [1/s]", field="Kr"
        )
    trials, controllers = [], []
    for Kr in gains:
        controller, certificate = certify_with(Kr)
        trial = GainTrial(Kr, certificate)
        trials.append(trial)
        controllers.append(controller)
        if progress is not None:
            progress(trial)
    index = min(range(len(trials)), key=lambda k: _rank(trials[k]))
    return GainSearch(trials[index], controllers[index], tuple(trials))


def search_gains(
    robot,
    box,
    epsilon: float,
    trajectory: Trajectory,
    *,
    duration: float,
    disturbance_bound: float | None = None,
    candidates: Sequence[float] = KR_CANDIDATES,
    progress: Callable[[GainTrial], None] | None = None,
    **synthesis_options,
) -> GainSearch:
    """The uniform ``Kr`` of :data:`KR_CANDIDATES` (or ``candidates``) whose certificate is best
    for ``trajectory`` over ``[0, duration]`` (the other arguments as in
    :func:`urpc.synthesize` and :func:`urpc.certify`; ``sample_period`` among the options)."""
    from .synthesis import synthesize

    if "Kr" in synthesis_options:
        raise InputError("Kr is what the search chooses: give candidates instead", field="Kr")

    def certify_with(Kr: float):
        controller = synthesize(robot, box, epsilon, Kr=Kr, **synthesis_options)
        certificate = certify(
            controller, trajectory, duration=duration, disturbance_bound=disturbance_bound
        )
        return controller, certificate

    return best_gain(certify_with, candidates, progress)
