"""The certificate of a synthesized controller: for which ``epsilon`` and which sample period the
tracking guarantee holds, and which condition fails when it does not.

Continuous time: the gain conditions of Theorems 1-2 of the paper (Theorem 2: any ``epsilon``;
Theorem 1: ``||r|| <= sqrt(lambda_max / lambda_min) / kappa_P``). Under a zero-order hold of period
``T`` with the implicit law of :mod:`urpc.control.interval`: the discrete-time argument of
``docs/sampled-data.md`` §2, every quantity bounded over cells of time, the tube and the box by
:mod:`urpc.control.cells`. In the metric of the true inertia, with the held loop's equilibrium
``r* = T M_L^-1 w + w / D`` for a frozen mismatch and ``r = r* + r_d + delta``::

    ||delta+||_M <= (1 - a + b) ||delta||_M + f + b (||r*||_M + ||r_d||_M)
    a = beta D T / (D T + beta lambda_U)        contraction of the implicit feedback
    b = T (K (1/2 + nu) + Gamma + Gamma_Delta + Dv / lambda_L) + T mu / 2
                                                 Kr, Coriolis, Coriolis mismatch, damping, metric
    f = sqrt(lambda_U) T ||dr*/dt||               motion of r* within a period
    ||r_d|| <= T d tr((T K)^-1)                   the disturbance, any sequence ||d_k|| <= d

Once the adaptive gain reaches its ceiling ``phi_max`` (it does while ``||e|| >= epsilon``, for at
most ``s_max / epsilon`` seconds), ``||e|| <= ||r|| / min(Kr) =: epsilon_floor`` ultimately. A run
ends below ``max(epsilon, epsilon_floor)``; the configuration is certified when
``epsilon_floor <= epsilon`` and every condition holds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError
from ..jsonsafe import jsonable, non_finite_paths, restore_non_finite
from ..trajectories import Trajectory, check_trajectory_dof
from ..validation import number_in, positive_number
from .cells import CellFloor
from .certificate_report import advice, lightest_joint, torque_figures
from .interval import IntervalPassivityController
from .period_bound import PeriodBound

#: Version of the argument and of the :class:`Certificate` it returns. Bump it whenever a change
#: of this module, of :mod:`urpc.control.cells`, :mod:`urpc.control.cell_bounds`,
#: :mod:`urpc.control.period_bound` or :mod:`urpc.control.certificate_report` changes a
#: certificate (a bound, a condition, a figure, a default): the certificate cache
#: (:mod:`urpc.control.certificate_cache`) keys every record on it, so that no certificate of an
#: older argument is ever reused. (The key also holds urpc's version and a digest of its source.)
CERTIFICATE_VERSION = 2


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
            note = self.figures.get("torque_note")
            return head if note is None else f"{head}; {note}"
        first = self.failed[0]
        return f"{head}; fails: {first.name} ({first.explanation})"

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready fields; a non-finite number (an infinite floor) becomes ``None`` and
        ``non_finite`` maps its JSON Pointer (``/epsilon_floor``, ``/conditions/0/value``,
        ``/figures/margin``) to ``"inf"``, ``"-inf"`` or ``"nan"``, so that :meth:`from_dict`
        rebuilds the certificate exactly."""
        fields = asdict(self)
        return {**jsonable(fields), "non_finite": non_finite_paths(fields)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Certificate:
        """The certificate of :meth:`to_dict`'s fields, non-finite numbers restored.

        Raises:
            InputError: a field is missing or of the wrong kind (names it).
        """
        try:
            values = restore_non_finite(
                {k: v for k, v in data.items() if k != "non_finite"}, data.get("non_finite", {})
            )
            conditions = tuple(Condition(**c) for c in values["conditions"])
            return cls(
                bool(values["certified"]), float(values["epsilon"]),
                float(values["epsilon_floor"]), float(values["max_sample_period"]),
                None if values["sample_period"] is None else float(values["sample_period"]),
                str(values["law"]), conditions, dict(values.get("figures") or {}),
            )  # fmt: skip
        except KeyError as exc:
            raise InputError(f"a certificate needs '{exc.args[0]}'", field=exc.args[0]) from None
        except (TypeError, ValueError, AttributeError) as exc:
            raise InputError(f"not a certificate's fields ({exc})", field="certificate") from None


def certify(
    controller: IntervalPassivityController,
    trajectory: Trajectory,
    *,
    duration: float,
    disturbance_bound: float | None = None,
    cells: int | None = None,
    progress: Callable[[str], Any] | None = None,
) -> Certificate:
    """The certificate of ``controller`` tracking ``trajectory`` over ``[0, duration]`` [s].

    A pure computation (nothing is read or written); :func:`urpc.control.certificate_cache.
    cached_certify` computes it once per configuration and reuses it from a cache on disk.

    Args:
        controller: A synthesized interval controller (its robot, box, gains, period and law).
        trajectory: The reference the guarantee is asked for (it must give
            :meth:`~urpc.trajectories.Trajectory.jerk_bound`, as the shipped ones do).
        duration: The time span of the reference to cover [s].
        disturbance_bound: ``||d||`` bound [N m] the plant sees. Theorem 2 does not need it in
            continuous time, but the sampled-data floor does; defaults to the box's bound.
        cells: Number of cells of time (default: chosen from the reference's speed).
        progress: Called with one short line as each stage of the sampled-data search starts
            (``"enclosing 236 cells (||e|| <= 0.01, ||r|| <= 0.45)"``), or ``None``.
    """
    if not isinstance(controller, IntervalPassivityController):
        raise InputError(
            "the certificate is that of the interval controller (urpc.synthesize); got "
            f"{type(controller).__name__}",
            field="controller",
        )
    check_trajectory_dof(trajectory, controller.dof, controller.robot.name)
    duration = positive_number("duration", duration, "a finite number > 0 [s]")
    box = controller.bound.box
    if disturbance_bound is not None:
        disturbance_bound = number_in(
            "disturbance_bound", disturbance_bound, "a finite number >= 0 [N m]", lambda x: x >= 0
        )
    d = box.disturbance_bound if disturbance_bound is None else float(disturbance_bound)
    conditions = _theorem_conditions(controller)
    law = "continuous" if controller.sample_period is None else controller.sampled_law
    delay = int(getattr(controller, "delay", 0))
    if delay:  # the argument of docs/sampled-data.md §2 is for a torque acting at its sample
        conditions.append(
            Condition(
                "actuation delay counted by the argument", False, float(delay), 0.0,
                "the certificate covers a torque that acts over the period of its sample; the "
                "one-sample-delay law (delay: 1) predicts with the nominal model, whose error "
                "the argument does not bound yet: certify the configuration without delay",
            )
        )  # fmt: skip
    if d is None and law == "implicit":  # Theorem 2 needs no bound in continuous time
        conditions.append(
            Condition(
                "disturbance bound given", False, math.nan, math.nan,
                "the sampled-data floor needs ||d||: give the scenario's `disturbance` or "
                "--disturbance D",
            )
        )  # fmt: skip
    d = math.nan if d is None else d
    floor_of = CellFloor(controller, trajectory, duration, cells=cells)
    try:
        floor_of.trajectory.jerk_bound(np.zeros(1), np.full(1, float(duration)))
    except NotImplementedError as exc:
        raise InputError(str(exc), field="trajectory") from None
    figures: dict[str, Any] = {}
    max_period = 0.0
    if controller.sample_period is None:
        figures.update(floor_of.inertia_figures(0.0))
        floor = 0.0 if controller.adaptive else _theorem1_floor(figures, controller)
    elif law == "paper":
        figures.update(floor_of.inertia_figures(controller.sample_period))
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
        search = _SampledSearch(floor_of, controller, d, progress)
        floor, parts, quantities = search.floor()
        max_period = search.max_sample_period() if math.isfinite(d) else 0.0
        figures.update(floor_of.figures(quantities))
        figures.update(parts)
        figures.update(search.report(floor, parts, quantities))
        if math.isfinite(floor):
            figures.update(torque_figures(search.bound, controller, d, quantities, parts))
        conditions += _sampled_conditions(figures, floor, controller.epsilon, max_period)
    holds = all(c.holds for c in conditions) and floor <= controller.epsilon
    if not holds and law == "implicit":
        figures["advice"] = advice(figures, floor, controller, max_period)
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


class _SampledSearch:
    """The floor of the implicit law as a fixed point over tubes, and the largest period.

    Every evaluation bounds the quantities over the tube ``||e|| <= rho``, ``||r|| <= r_max``; a
    tube with ``floor(rho) <= rho`` and ``r_sup <= r_max`` is invariant once the gains have
    saturated, and the error ends up below ``floor(rho)``. The cells are widened by
    ``2 T``, so that the same enclosures serve every period up to ``2 T``."""

    def __init__(
        self,
        floor_of: CellFloor,
        controller: IntervalPassivityController,
        d: float,
        progress: Callable[[str], Any] | None = None,
    ):
        self.floor_of, self.controller, self.d = floor_of, controller, d
        self.bound = PeriodBound(floor_of)
        self.say = progress or (lambda message: None)
        self.T = controller.sample_period
        self.extension = 2.0 * self.T
        self.epsilon = controller.epsilon

    def enclose(self, tube: float, T: float | None = None) -> dict:
        """The cell quantities over the tube ``||e|| <= tube`` with ``||r|| <= r_max``, raising
        ``r_max`` until the bound of ``||r||`` at the least self-consistent tube lies inside it."""
        T = self.T if T is None else T
        r_max = 1.5 * float(self.controller.Kr.max()) * tube + 1e-6
        for _ in range(5):
            cells = self.floor_of.cells
            self.say(f"enclosing {cells} cells (||e|| <= {tube:.3g}, ||r|| <= {r_max:.3g})")
            quantities = self.floor_of.quantities(tube, r_max, self.extension)
            floor, parts, _ = self.least_tube(quantities, T)
            if not math.isfinite(floor) or parts["r_sup"] <= r_max:
                return quantities
            r_max = 1.25 * parts["r_sup"]
        return quantities

    def least_tube(self, quantities: dict, T: float) -> tuple[float, dict, float]:
        """The least ``rho <= tube`` with ``floor(rho) <= rho`` (the fixed point reached from
        ``rho = 0``, each quantity bounded over the enclosing tube), its floor and parts."""
        top = quantities["tube"]
        rho, floor, parts = 0.0, math.inf, {}
        for _ in range(60):
            floor, parts = self.bound.floor_at(T, self.d, quantities, rho)
            if not math.isfinite(floor) or floor > top:
                return math.inf, parts, rho
            if floor <= rho:
                return floor, parts, rho
            rho = min(top, max(floor * 1.0005, rho * 1.0005))
        return math.inf, parts, rho

    def basin(self, quantities: dict, least: float) -> float:
        """The largest tube ``rho`` in ``[least, tube]`` (scanned down by 10 %) that maps into
        itself with ``||r||`` inside the enclosure: the states from which the floor is reached
        once the gains have saturated."""
        rho = quantities["tube"]
        self.say(f"scanning the basin (||e|| <= {rho:.3g})")
        while rho > max(least, 1e-6 * quantities["tube"]):
            floor, parts = self.bound.floor_at(self.T, self.d, quantities, rho)
            if floor <= rho and parts.get("r_sup", math.inf) <= quantities["r_max"]:
                return rho
            rho *= 0.9
        return least

    def floor(self) -> tuple[float, dict, dict]:
        """The floor: within the tube ``||e|| <= epsilon`` if there is one, else in wider tubes
        (up to ``10 epsilon``) for the report; ``inf`` beyond."""
        tube = self.epsilon
        if not math.isfinite(self.d):
            quantities = self.floor_of.quantities(tube, 0.0, self.extension)
            return math.inf, {"margin": -math.inf}, quantities
        while True:
            quantities = self.enclose(tube)
            floor, parts, rho = self.least_tube(quantities, self.T)
            if math.isfinite(floor) and parts["r_sup"] <= quantities["r_max"]:
                basin = self.basin(quantities, rho)
                parts.update(tube=rho, r_max=quantities["r_max"], basin_tube=basin)
                return floor, parts, quantities
            if tube >= 10.0 * self.epsilon:
                break
            tube *= 10.0
        quantities = self.enclose(self.epsilon)
        _, parts = self.bound.floor_at(self.T, self.d, quantities)
        parts.update(tube=self.epsilon, r_max=quantities["r_max"])
        return math.inf, parts, quantities

    def max_sample_period(self) -> float:
        """The largest ``T <= 2 T_controller`` with a floor below ``epsilon`` in the tube
        ``||e|| <= epsilon`` (the cells' enclosures hold for every period up to ``2 T``)."""
        quantities = self.enclose(self.epsilon)  # cached from floor()
        self.say("searching the largest sample period")

        def ok(T: float) -> bool:
            floor, parts, _ = self.least_tube(quantities, T)
            return floor <= self.epsilon and parts.get("r_sup", math.inf) <= quantities["r_max"]

        low, high = self.extension * 1e-4, self.extension
        if not ok(low):
            return 0.0
        if ok(high):
            return high
        for _ in range(40):
            middle = math.sqrt(low * high)
            low, high = (middle, high) if ok(middle) else (low, middle)
            if high / low < 1.005:
                break
        return low

    def report(self, floor: float, parts: dict, quantities: dict) -> dict[str, Any]:
        """What dominates the floor, where, and what would certify (``quantities``: the
        enclosures the floor was found with)."""
        floor_of = self.floor_of
        shares = parts.get("shares") or {}
        out: dict[str, Any] = {}
        if "invalid_cell" in parts:
            out["invalid_time"] = floor_of.cell_time(parts["invalid_cell"])[0]
        if shares:
            dominant = max(shares, key=shares.get)
            total = sum(shares.values()) or 1.0
            out["dominant_term"] = dominant
            out["term_shares"] = {k: v / total for k, v in shares.items()}
            cell = parts.get("slow_cell", 0)
            out["worst_time"] = floor_of.cell_time(cell)[0]
            lightest = lightest_joint(floor_of, quantities, cell)
            out["lightest_joint"] = floor_of.robot.joint_names[lightest]
            link = floor_of.dominant_link(
                quantities, parts.get("piece", 0), cell, parts.get("tube", self.epsilon)
            )
            if link is not None:
                out["dominant_link"], out["dominant_link_share"] = link
        if self.controller.adaptive and self.controller.phi_I > 0:
            s_max = (self.controller.phi_max - self.controller.phi_P) / self.controller.phi_I
            #: Before the gains saturate, ||e_k|| >= epsilon for at most s_max / epsilon seconds.
            out["time_above_epsilon_before_saturation"] = s_max / self.epsilon
        return out


def _theorem1_floor(figures: dict, controller: IntervalPassivityController) -> float:
    """Theorem 1: ``||r|| <= sqrt(lambda_max / lambda_min) / kappa_P``, ``||e|| <= ||r|| / Kr``."""
    if not figures["lambda_L"] > 0:
        return math.inf
    ratio = figures["lambda_U"] / figures["lambda_L"]
    return float(math.sqrt(ratio) / controller.kappa_P / np.min(controller.Kr))


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
            + (f" the period to {max_period:.3g} s" if max_period > 0
               else " the period: none up to twice this one is certified"),
        ),
    ]  # fmt: skip
