"""The feedback laws of the interval controller: the robust torque for the gain ``D`` and the
sliding variable ``r``, each with its part of the certificate.

* :class:`ContinuousFeedback`: the paper's ``v = -D r``, i.e. the torque ``D r``, in continuous
  time; certified by Theorems 1-2.
* :class:`HeldFeedback`: the same law sampled at period ``T`` under a zero-order hold
  (``sampled_law="paper"``, the paper's reproduction). Per inertia mode it gives ``r+ = (1 - D T /
  lambda) r``: unstable once ``D T > 2 lambda``, which the growing gain reaches on light plants;
  never certified.
* :class:`ImplicitFeedback` (``sampled_law="implicit"``; not in the paper): the backward-Euler
  discretization, which evaluates the feedback at the predicted next value of ``r`` (Acary &
  Brogliato 2010) with a sound lower bound ``M_L(q)`` of the inertia over the box
  (:class:`~urpc.model.inertia_bounds.InertiaBounds`) as the prediction model::

      u = M0 qdd_a + C0 qd_a + g0 + D (M_L + D T 1)^{-1} M_L r

  one CRBA and one symmetric solve per step. On every plant of the box (``M >= M_L``) the sampled
  loop contracts for every gain, and as ``D -> infinity`` the feedback tends to the dead-beat
  ``M_L r / T``. Adaptation stops once ``phi`` reaches ``phi_max = 20 max_q lambda_max(M_U(q)) /
  T`` (anti-windup: beyond it a larger gain changes the feedback by less than 5 %). The
  discrete-time argument and its ultimate bound are in ``docs/sampled-data.md``
  (:mod:`urpc.control.sampled_search`).

:func:`urpc.control.certificate.certify` asks the controller's law for its part of the argument
(:meth:`FeedbackLaw.argument`) instead of branching on flags.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from ..model.inertia_bounds import InertiaBounds
from ..names import SAMPLED_LAWS
from .argument import Condition, LawArgument

if TYPE_CHECKING:
    from collections.abc import Callable

    from .cells import CellFloor
    from .interval import IntervalPassivityController

#: ``phi_max = PHI_MAX_FACTOR * max_q lambda_max(M_U(q)) / T``: past it, the implicit feedback of
#: every mode is within ``1 / (1 + PHI_MAX_FACTOR)`` of its dead-beat limit, so adaptation stops.
PHI_MAX_FACTOR = 20.0


class FeedbackLaw(ABC):
    """The robust torque [N m] for the gain ``D`` and the sliding variable ``r``; by default the
    paper's ``D r``."""

    #: The law's name in a certificate (``Certificate.law``).
    name: ClassVar[str]
    #: The control period ``T`` [s] the law runs at; ``None``: continuous time.
    sample_period: float | None = None

    def torque(self, q: np.ndarray, gain: float, r: np.ndarray) -> np.ndarray:
        """The feedback torque [N m] at ``q`` for ``D = gain`` [N m s/rad]."""
        return gain * r

    def phi_ceiling(self, phi_P: float, period: float | None = None) -> float:
        """The ceiling ``phi_max`` [N m s/rad] where adaptation stops (none by default)."""
        return math.inf

    @abstractmethod
    def argument(
        self,
        controller: IntervalPassivityController,
        floor_of: CellFloor,
        d: float | None,
        progress: Callable[[str], Any] | None,
        require_efforts: bool = False,
    ) -> LawArgument:
        """The law's part of the certificate of ``controller`` over the cells of ``floor_of``
        with the disturbance bound ``d`` [N m] (``None``: unknown); with ``require_efforts``,
        a law that bounds its commanded torque adds the condition that the bound is within the
        effort limits (and shortens its largest period to one where it is)."""

    def advice(self, controller: IntervalPassivityController, argument: LawArgument) -> str | None:
        """What would certify a configuration that is not certified (none by default)."""
        return None


class ContinuousFeedback(FeedbackLaw):
    """The paper's law in continuous time: certified by Theorem 1's ultimate bound or by
    Theorem 2 (any ``epsilon``)."""

    name = "continuous"

    def argument(self, controller, floor_of, d, progress, require_efforts=False):
        figures = floor_of.inertia_figures(0.0)
        floor, conditions = controller.gain_law.continuous_time_bound(
            figures["lambda_L"], figures["lambda_U"], controller.Kr, controller.epsilon
        )
        known = controller.bound.box.disturbance_bound
        if not controller.gain_law.adaptive:
            # Theorem 1's robust term dominates the mismatch through rho, which includes the
            # box's disturbance bound: a larger disturbance than the law knows voids it.
            within = known is not None and d <= known
            # As many digits as tell the two apart (10.000001 against 10, not "10 > 10").
            digits = next(
                (k for k in (3, 6, 9, 12, 17) if known is None or f"{d:.{k}g}" != f"{known:.{k}g}"),
                17,
            )
            conditions.append(
                Condition(
                    "Theorem 1: the disturbance within the bound the law knows", within, d,
                    math.nan if known is None else known,
                    f"||d|| <= {d:.{digits}g} N m within the box's {known:.{digits}g} N m, which "
                    "rho includes"
                    if within
                    else f"the plant's ||d|| <= {d:.{digits}g} N m exceeds "
                    + ("the box's disturbance bound, none" if known is None
                       else f"the box's disturbance bound {known:.{digits}g} N m")
                    + ", which rho includes: give the box that bound (the law then covers it), "
                    "or use Theorem 2 (disturbance: unknown), whose gains adapt to any bound",
                )
            )  # fmt: skip
            if not within:  # the floor above assumes the disturbance rho covers
                floor = math.inf
        return LawArgument(floor, conditions, figures)


class HeldFeedback(FeedbackLaw):
    """The paper's law under a zero-order hold of period ``T``: never certified. No floor
    follows (a condition that always fails says so), and the gain must stay below the hold's
    stability limit ``2 lambda_L / T`` (it does not under Theorem 2)."""

    name = "paper"

    def __init__(self, sample_period: float):
        self.sample_period = sample_period

    def argument(self, controller, floor_of, d, progress, require_efforts=False):
        T = self.sample_period
        figures = floor_of.inertia_figures(T)
        limit = 2.0 * figures["lambda_L"] / T
        gain = controller.gain_law.settled_phi(controller.phi_max)
        conditions = [
            Condition(
                "paper law: gain below the hold's stability limit 2 lambda_L / T",
                gain < limit, gain, limit,
                "the paper's gain grows without bound under Theorem 2 and diverges once D T > "
                "2 lambda: use the implicit sampled law (sampled_law: implicit)",
            ),
            Condition(
                "paper law: an ultimate bound under the hold", False, math.inf,
                controller.epsilon,
                "no argument bounds the paper's law under a hold, even with constant gains below "
                "the stability limit: use the implicit sampled law (sampled_law: implicit)",
            ),
        ]  # fmt: skip
        return LawArgument(math.inf, conditions, figures)


class ImplicitFeedback(FeedbackLaw):
    """``D (M_L + D T 1)^{-1} M_L r`` with the box's inertia lower bound ``M_L`` (module
    docstring); certified by the sampled-data argument of ``docs/sampled-data.md`` §2."""

    name = "implicit"

    def __init__(self, sample_period: float, inertia_bounds: InertiaBounds):
        self.sample_period = sample_period
        self.inertia_bounds = inertia_bounds
        #: The largest ``D`` [N m s/rad] the feedback uses: the controller sets it to its
        #: ``phi_max`` (:meth:`phi_ceiling`).
        self.gain_cap = math.inf
        lower = inertia_bounds.lower_robot
        self._lower_robot = lower
        self._model, self._data, self._configuration = lower.model, lower.data, lower.configuration
        self._stride = lower.dof + 1

    def torque(self, q, gain, r):
        """``D (M_L + D T 1)^{-1} M_L r = D (r - D T y)`` [N m] with ``(M_L + D T 1) y = r``:
        one CRBA (its upper triangle) and one Cholesky solve (LAPACK ``dposv``, which reads the
        upper triangle only). ``D`` is capped at :attr:`gain_cap`: past the ceiling where the
        adaptation stops more gain buys nothing (every mode is within 5 % of dead-beat), and
        a capped gain is the same at every sample once the gains have saturated, which the
        certificate's argument counts on (docs/sampled-data.md §1)."""
        if gain > self.gain_cap:
            gain = self.gain_cap
        step = gain * self.sample_period
        shifted = pin.crba(self._model, self._data, self._configuration(q))
        shifted.flat[:: self._stride] += step  # the diagonal (half the time of fancy indexing)
        _, y, info = dposv(shifted, r, lower=0)
        if info != 0:  # M_L + D T 1 is not positive definite: M_L is indefinite at q
            return implicit_feedback(positive_part(self._lower_robot.M(q)), gain, step, r)
        return gain * (r - step * y)

    def phi_ceiling(self, phi_P, period=None):
        """``max(phi_P, PHI_MAX_FACTOR * max_q lambda_max(M_U(q)) / T)`` at the law's period, or
        at ``period`` [s] (the certificate's search over periods)."""
        T = self.sample_period if period is None else period
        return max(phi_P, PHI_MAX_FACTOR * self.inertia_bounds.max_upper_eigenvalue / T)

    def argument(self, controller, floor_of, d, progress, require_efforts=False):
        from .certificate_report import effort_condition, torque_figures
        from .sampled_search import SampledSearch

        conditions = []
        if d is None:  # Theorem 2 needs no bound in continuous time; the floor does
            conditions.append(
                Condition(
                    "disturbance bound given", False, math.nan, math.nan,
                    "the sampled-data floor needs ||d||: give the scenario's `disturbance` or "
                    "--disturbance D",
                )
            )  # fmt: skip
            d = math.nan
        search = SampledSearch(floor_of, controller, d, progress)
        floor, parts, quantities = search.floor()
        max_period = search.max_sample_period() if math.isfinite(d) else 0.0
        if math.isfinite(d) and search.failing_cell is None:
            floor, parts, quantities, max_period = search.reconcile(
                floor, parts, quantities, max_period
            )
        if search.failing_cell is not None:  # only the inertia models were enclosed
            figures = {**floor_of.model_figures(controller.epsilon, search.extension), **parts}
        else:
            figures = {**floor_of.figures(quantities), **parts}
        figures.update(search.report(floor, parts, quantities))
        if math.isfinite(floor):
            figures.update(torque_figures(search, controller, d, quantities, parts))
            if require_efforts:
                partitions = [q for q in (search.refined, quantities) if q is not None]
                effort, max_period = effort_condition(
                    search, controller, figures, partitions, max_period
                )
                conditions.append(effort)
        conditions += _sampled_conditions(
            figures, floor, controller.epsilon, max_period, controller.adaptive,
            bool(controller.delay),
        )  # fmt: skip
        return LawArgument(floor, conditions, figures, max_period)

    def advice(self, controller, argument):
        from .certificate_report import advice

        return advice(argument.figures, argument.floor, controller, argument.max_sample_period)


def feedback_law(
    sample_period: float | None, sampled_law: str, inertia_bounds: InertiaBounds | None
) -> FeedbackLaw:
    """The feedback law of the controller's arguments: continuous time without a period, else
    the ``sampled_law`` (``"implicit"``, which needs ``inertia_bounds``, or ``"paper"``).

    Raises:
        ValueError: an unknown ``sampled_law``; the implicit law without inertia bounds.
    """
    if sampled_law not in SAMPLED_LAWS:
        raise ValueError(f"{sampled_law!r} is not a sampled law; valid: {', '.join(SAMPLED_LAWS)}")
    if sample_period is None:
        return ContinuousFeedback()
    if sampled_law == "paper":
        return HeldFeedback(sample_period)
    if inertia_bounds is None:
        raise ValueError("the implicit sampled law needs the box's inertia bounds")
    return ImplicitFeedback(sample_period, inertia_bounds)


def _sampled_conditions(
    figures: dict[str, float],
    floor: float,
    epsilon: float,
    max_period: float,
    adaptive: bool,
    delayed: bool = False,
) -> list[Condition]:
    """The sampled law's conditions; each explanation says what to change when the condition
    fails, and what holds when it holds. With constant gains (Theorem 1, not ``adaptive``) the
    contraction ``a`` grows with ``T phi_P`` as ``b`` grows with ``T``: the fix is the gain."""
    margin = figures["margin"]
    fix_floor = (
        (f"raise epsilon to {floor:.3g} rad or shorten" if math.isfinite(floor)
         else "no epsilon is guaranteed at this period: shorten")
        + (f" the period to {max_period:.3g} s" if max_period > 0
           else " the period: none up to twice this one is certified")
    )  # fmt: skip
    if max_period <= 0 and not adaptive:
        fix_floor = (
            (f"raise epsilon to {floor:.3g} rad or phi_P" if math.isfinite(floor)
             else "no epsilon is guaranteed at this period: raise phi_P")
            + " (the gains are constant: no period up to twice this one is certified)"
        )  # fmt: skip
    # Bounds that fail for the tube's sake (the inertia moves more over ||e|| <= epsilon than
    # they allow) are not the box's fault alone: say so.
    tube = (
        f"the inertia changes more over the tube ||e|| <= {epsilon:g} rad than the bounds "
        "allow: lower epsilon, or narrow the mass/inertia intervals"
        if figures.get("invalid_for_tube")
        else None
    )
    specs = [
        ("inertia lower bound M_L positive definite", figures["lambda_L"] > 0,
         figures["lambda_L"], 0.0,
         tube or "the box allows a joint with no inertia: narrow the mass/inertia intervals",
         "every plant of the box has an inertia of at least lambda_L along every mode"),
        ("relative inertia bound beta > 0", figures["beta"] > 0, figures["beta"], 0.0,
         tube or "the box's inertia bounds are vacuous: narrow the mass/inertia intervals",
         "the law's inertia model is at least beta times every plant's"),
        ("contraction a exceeds the perturbation b (at r = 0)", margin > 0, margin, 0.0,
         "shorten the sample period or lower Kr (b grows with T Kr and T |qd|)" if adaptive
         else CONSTANT_GAIN_FIX,
         f"a period contracts the error by a - b = {margin:.3g} at least, in the plant's metric")
        if not delayed else
        ("delayed loop: the common form's rate plus the period's perturbation below 1",
         margin > 0, margin, 0.0, _delayed_fix(figures),
         f"a period contracts the delayed loop's form by {margin:.3g} at least (its rate "
         f"{figures.get('delay_rate', math.nan):.3g} plus the perturbations of order T Kr)"),
        ("ultimate bound below epsilon", floor <= epsilon, floor, epsilon, fix_floor,
         f"the error ends below the floor {floor:.3g} rad <= epsilon"),
    ]  # fmt: skip
    return [
        Condition(name, holds, value, limit, held if holds else fix)
        for name, holds, value, limit, fix, held in specs
    ]


def _delayed_fix(figures: dict) -> str:
    """What to change when the delayed loop does not contract (docs/sampled-data.md §7)."""
    rate = figures.get("delay_rate")
    if rate is None:
        ranges = figures.get("delay_ranges") or {}
        return (
            "no common quadratic form contracts the delayed loop over this box (A in ["
            f"{ranges.get('a1', math.nan):.3g}, {ranges.get('a2', math.nan):.3g}], M^-1 M0 in "
            f"[{ranges.get('h1', math.nan):.3g}, {ranges.get('h2', math.nan):.3g}]): the "
            "nominal model is too far from some plants of the box; narrow the mass and "
            "inertia intervals, or run without delay"
        )
    return (
        f"the form contracts by {rate:.3g} per period and the perturbations of order T Kr, "
        "T |qd| add the rest: shorten the sample period or lower Kr"
    )


#: What to change when a period does not contract under Theorem 1's constant gains.
CONSTANT_GAIN_FIX = (
    "raise phi_P, or state `disturbance: unknown` for Theorem 2's adaptive gains (the gains "
    "are constant: the contraction a grows with T phi_P as b grows with T, so no period helps)"
)


#: Floor of the eigenvalues of :func:`positive_part`, relative to the largest one.
POSITIVE_FLOOR = 1e-3


def positive_part(inertia: np.ndarray, floor: float = POSITIVE_FLOOR) -> np.ndarray:
    """``inertia`` with its eigenvalues raised to at least ``floor * lambda_max`` [kg m^2].

    A box that is partly no rigid body (wide mass and CoM intervals with narrow inertias) can
    give a lower bound ``M_L`` that is not positive definite at some ``q``. The implicit feedback
    ``D (M_L + D T 1)^{-1} M_L r`` is then singular where ``D T = -lambda`` for a negative
    eigenvalue ``lambda`` and changes sign beyond: the gain the adaptation reaches blows the law
    up. On a mode the predicted inertia ``lambda_0`` only needs ``0 < lambda_0 <= lambda_true``
    for the loop factor ``1 - lambda_0 / lambda_true`` to contract, so a small positive floor in
    the directions where ``M_L`` fails is the cautious choice: the feedback there saturates at
    ``lambda_0 / T`` instead of diverging (the certificate reports such a box as not certified).
    """
    eigenvalues, vectors = np.linalg.eigh(inertia)
    top = float(eigenvalues[-1])
    least = floor * top if top > 0 else floor
    clamped = np.maximum(eigenvalues, least)
    return (vectors * clamped) @ vectors.T


def implicit_feedback(inertia: np.ndarray, gain: float, step: float, r: np.ndarray) -> np.ndarray:
    """``D (M + D T 1)^{-1} M r`` [N m] with ``D = gain`` and ``D T = step``, by a general
    solve (the fallback of the Cholesky path for an ``inertia`` made positive definite)."""
    return gain * np.linalg.solve(inertia + step * np.eye(len(r)), inertia @ r)
