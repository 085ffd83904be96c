"""The certificate of a synthesized controller: for which ``epsilon`` and which sample period the
tracking guarantee holds, and which condition fails when it does not.

Continuous time: the gain conditions of Theorems 1-2 of the paper (Theorem 2: any ``epsilon``;
Theorem 1: ``||r|| <= sqrt(lambda_max / lambda_min) / kappa_P``). Under a zero-order hold of period
``T`` with the implicit law of :mod:`urpc.control.interval`: the discrete-time argument of
``docs/sampled-data.md``, computed by :mod:`urpc.control.sampled_floor`. In the metric of the true
inertia, with the held loop's equilibrium ``r* = T M_L^-1 w + w / D`` for a frozen mismatch and
``r = r* + delta``::

    ||delta+||_M <= (1 - a + b) ||delta||_M + f + b ||r*||_M
    a = beta D T / (D T + beta lambda_U)               contraction of the implicit feedback
    b = T (K (1/2 + nu) + (1 + nu) Gamma v)             Kr and Coriolis terms, proportional to r
    f = T d / sqrt(lambda_L) + sqrt(lambda_U) T |dr*/dt| T    disturbance, motion of r*

Once the adaptive gain reaches its ceiling ``phi_max`` (it does while ``||e|| >= epsilon``),
``||e|| <= ||r|| / min(Kr) =: epsilon_floor`` ultimately. A run ends below
``max(epsilon, epsilon_floor)``; the configuration is certified when ``epsilon_floor <= epsilon``
and every condition holds. The inertia bounds and the mismatch over the box are sound at every
grid point; the rest is evaluated on the grid (not an interval proof between grid points).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

from ..trajectories import Trajectory
from .interval import IntervalPassivityController
from .sampled_floor import FloorGrid


@dataclass(frozen=True)
class Condition:
    """One condition of the argument: ``holds`` when ``value`` satisfies ``limit``."""

    name: str
    holds: bool
    value: float
    limit: float
    explanation: str


@dataclass(frozen=True)
class Certificate:
    """What the guarantee covers for one controller, reference and disturbance.

    Attributes:
        certified: Every condition holds: ``||e||`` ends up below ``epsilon`` on every plant of
            the box (at the samples, for a sampled law).
        epsilon: The requested precision [rad].
        epsilon_floor: The smallest precision the argument guarantees at this period [rad]
            (0 in continuous time under Theorem 2; ``inf`` when no bound follows).
        max_sample_period: The largest period at which the implicit law is certified for
            ``epsilon`` [s] (0 when none is).
        sample_period: The controller's period [s], ``None`` in continuous time.
        law: ``"continuous"``, ``"implicit"`` or ``"paper"``.
        conditions: Every condition of the argument, failed ones first.
        figures: The quantities the floor is made of (``beta``, ``lambda_L`` ...), for reports.
    """

    certified: bool
    epsilon: float
    epsilon_floor: float
    max_sample_period: float
    sample_period: float | None
    law: str
    conditions: tuple[Condition, ...]
    figures: dict[str, float] = field(default_factory=dict)

    @property
    def failed(self) -> tuple[Condition, ...]:
        return tuple(c for c in self.conditions if not c.holds)

    def summary(self) -> str:
        """One line: certified or not, the floor, and the first failed condition."""
        period = (
            "continuous time" if self.sample_period is None else f"T = {self.sample_period:g} s"
        )
        head = (
            f"{'certified' if self.certified else 'NOT certified'} ({self.law} law, {period}): "
            f"epsilon = {self.epsilon:g} rad, floor = {self.epsilon_floor:.3g} rad, "
            f"max sample period {self.max_sample_period:.3g} s"
        )
        if self.certified:
            return head
        first = self.failed[0]
        return f"{head}; fails: {first.name} ({first.explanation})"

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready fields; a non-finite number (an infinite floor) becomes ``None``."""
        return _finite_or_none(asdict(self))


def certify(
    controller: IntervalPassivityController,
    trajectory: Trajectory,
    *,
    duration: float,
    disturbance_bound: float | None = None,
) -> Certificate:
    """The certificate of ``controller`` tracking ``trajectory`` over ``[0, duration]`` [s].

    Args:
        controller: A synthesized interval controller (its robot, box, gains, period and law).
        trajectory: The reference the guarantee is asked for.
        duration: The time span of the reference to cover [s].
        disturbance_bound: ``||d||`` bound [N m] the plant sees. Theorem 2 does not need it in
            continuous time, but the sampled-data floor does; defaults to the box's bound.
    """
    box = controller.bound.box
    d = box.disturbance_bound if disturbance_bound is None else float(disturbance_bound)
    conditions = _theorem_conditions(controller)
    law = "continuous" if controller.sample_period is None else controller.sampled_law
    grid = FloorGrid(controller, trajectory, duration)
    if d is None and law == "implicit":  # Theorem 2 needs no bound in continuous time
        conditions.append(
            Condition(
                "disturbance bound given", False, math.nan, math.nan,
                "the sampled-data floor needs ||d||: give the scenario's `disturbance` or "
                "--disturbance D",
            )
        )  # fmt: skip
    d = math.nan if d is None else d
    figures = grid.figures()
    max_period = grid.max_sample_period(controller.epsilon, d) if math.isfinite(d) else 0.0
    if controller.sample_period is None:
        floor = 0.0 if controller.adaptive else grid.theorem1_floor(controller.kappa_P)
    elif law == "paper":
        floor = math.inf
        limit = 2.0 * figures["lambda_L"] / controller.sample_period
        gain = math.inf if controller.adaptive else controller.phi_P
        conditions.append(
            Condition(
                "paper law: gain below the hold's stability limit 2 lambda_L / T",
                gain < limit, gain, limit,
                "the paper's gain grows without bound under Theorem 2 and diverges once D T > "
                "2 lambda: use the implicit sampled law (sampled_law: implicit)",
            )
        )  # fmt: skip
    else:
        floor, parts = grid.floor(controller.sample_period, d, controller.epsilon)
        figures.update(parts)
        conditions += _sampled_conditions(figures, floor, controller.epsilon, max_period)
    holds = all(c.holds for c in conditions) and floor <= controller.epsilon
    if controller.sample_period is None and not controller.adaptive:
        conditions.append(
            Condition(
                "Theorem 1 ultimate bound below epsilon", floor <= controller.epsilon, floor,
                controller.epsilon, "raise kappa_P or Kr, or use Theorem 2 (disturbance: unknown)",
            )
        )  # fmt: skip
    ordered = tuple(sorted(conditions, key=lambda c: c.holds))
    return Certificate(
        bool(holds), controller.epsilon, float(floor), float(max_period),
        controller.sample_period, law, ordered, figures,
    )  # fmt: skip


def _theorem_conditions(controller: IntervalPassivityController) -> list[Condition]:
    if controller.adaptive:
        specs = [
            ("Theorem 2: kappa_I > 0", controller.kappa_I, 0.0, "choose kappa_I > 0"),
            ("Theorem 2: phi_I > 0", controller.phi_I, 0.0, "choose phi_I > 0"),
        ]
        return [Condition(n, v > lim, v, lim, x) for n, v, lim, x in specs]
    specs = [
        ("Theorem 1: kappa_P >= 1", controller.kappa_P, 1.0, "choose kappa_P >= 1"),
        ("Theorem 1: phi_P >= 1", controller.phi_P, 1.0, "choose phi_P >= 1"),
    ]
    return [Condition(n, v >= lim, v, lim, x) for n, v, lim, x in specs]


def _sampled_conditions(
    figures: dict[str, float], floor: float, epsilon: float, max_period: float
) -> list[Condition]:
    return [
        Condition(
            "inertia lower bound M_L positive definite", figures["lambda_L"] > 0,
            figures["lambda_L"], 0.0,
            "the box allows a joint with no inertia: narrow the mass/inertia intervals",
        ),
        Condition(
            "relative inertia bound beta > 0", figures["beta"] > 0, figures["beta"], 0.0,
            "the box's inertia bounds are vacuous: narrow the mass/inertia intervals",
        ),
        Condition(
            "contraction a exceeds the perturbation b (at r = 0)", figures["margin"] > 0,
            figures["margin"], 0.0,
            "shorten the sample period or lower Kr (b grows with T Kr and T |qd|)",
        ),
        Condition(
            "ultimate bound below epsilon", floor <= epsilon, floor, epsilon,
            (f"raise epsilon to {floor:.3g} rad or shorten" if math.isfinite(floor)
             else "no epsilon is guaranteed at this period: shorten")
            + f" the period to {max_period:.3g} s",
        ),
    ]  # fmt: skip


def _finite_or_none(value):
    if isinstance(value, dict):
        return {key: _finite_or_none(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_none(item) for item in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
