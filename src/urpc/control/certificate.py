"""The certificate of a synthesized controller: for which ``epsilon`` and which sample period the
tracking guarantee holds, and which condition fails when it does not.

:func:`certify` asks the controller's two laws for their parts: the gain law
(:mod:`urpc.control.gain_laws`) for the gain conditions of Theorem 1 or 2, the feedback law
(:mod:`urpc.control.feedback`) for the floor, its conditions and figures. Continuous time: Theorem 2
certifies any ``epsilon``, Theorem 1 ``||r|| <= sqrt(lambda_max / lambda_min) / kappa_P``; the
paper's law under a hold is never certified. Under a zero-order hold of period ``T`` with the
implicit law: the discrete-time argument of
``docs/sampled-data.md`` §2, every quantity bounded over cells of time, the tube and the box by
:mod:`urpc.control.cells`. In the metric of the true inertia, with the held loop's equilibrium
``r* = T M_L^-1 w + w / D`` for a frozen mismatch, the response ``r_d`` of the frozen plant to the
disturbance's history, and ``r = r* + r_d + delta``::

    ||delta+||_M <= (1 - a + b) ||delta||_M + f + b (||r*||_M + ||r_d||_M)
    a = beta D T / (D T + beta lambda_U)        contraction of the implicit feedback
    b = T (K (1/2 + nu) + Gamma + Gamma_Delta + Dv / lambda_L) + T mu / 2
                                                 Kr, Coriolis, Coriolis mismatch, damping, metric
    f = T ||M^1/2 dr*/dt|| + T ||M^1/2 dr_d/dt||   motion of r* and r_d within a period
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
from ..trajectories import Trajectory
from ..validation import check_trajectory_dof, checked_count, number_in, positive_number
from ..wording import count
from .argument import Condition
from .base import actuation_delay_of
from .cells import CellFloor
from .certificate_report import EFFORT_CONDITION, effort_limits, reference_torque
from .interval import IntervalPassivityController

#: Version of the argument and of the :class:`Certificate` it returns. Bump it whenever a change
#: of this module, of the laws' parts (:mod:`urpc.control.gain_laws`, :mod:`urpc.control.feedback`,
#: :mod:`urpc.control.argument`), of :mod:`urpc.control.cells`, :mod:`urpc.control.cell_bounds`,
#: :mod:`urpc.control.period_bound`, :mod:`urpc.control.sampled_search` or
#: :mod:`urpc.control.certificate_report` changes a certificate (a bound, a condition, a figure,
#: a default): the certificate cache (:mod:`urpc.control.certificate_cache`) keys every record on
#: it, so that no certificate of an older argument is ever reused. (The key also holds urpc's
#: version and a digest of its source.)
#: 4: cells refined where the floor needs them, Taylor Coriolis forms, zonotopes, the motion of
#: the disturbance's response, the reference within the effort limits.
#: 5: the disturbance's response also bounded by Cauchy-Schwarz (several light modes).
#: 6: the period at which the torque bound is within the efforts (torque_period).
#: 7: Theorem 1 against a disturbance beyond the box's; no largest period when a condition no
#: period changes fails; cells split without a floor while the floor at rho = 0 falls.
#: 8: Theorem 1 under a hold is told to raise phi_P, not to shorten the period.
#: 9: the inertia models' second-order terms (own boxes for the halves of failing cells, the
#: structure of the second derivatives kept); beta at the cell's centre in the advice.
#: 10: the delayed law certified behind its own one-sample delay (docs/sampled-data.md §7).
#: 11: the torque bound's plant torque over the regime's tube, not the enclosures' (and
#: ``require_efforts``).
CERTIFICATE_VERSION = 11
#: The condition on the delay: the law's must be the plant's actuation delay (0, or 1 for the
#: delayed law, whose loop has its own argument).
DELAY_CONDITION = "actuation delay counted by the argument"


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
    actuation_delay: int | None = None,
    require_efforts: bool = False,
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
        actuation_delay: Samples between a state and the period its torque acts over on the
            plant (:func:`urpc.simulate`'s ``actuation_delay``); ``None``: the delay the law
            predicts over (``controller.delay``). The argument covers a torque that acts over
            the period of its own sample: any delay, the law's or the plant's, fails the
            condition "actuation delay counted by the argument" (the floor and the largest
            period are still reported: they are the undelayed loop's).
        require_efforts: Make the commanded torque's bound within the URDF's effort limits a
            condition (for a robot whose drives clip there: a clipped torque voids the
            argument), and shorten ``max_sample_period`` to a period where it holds. By default
            the bound is reported (``torque_bound``, ``torques_within_limits``, the summary's
            note) and the verdict assumes an unclipped torque, as the paper's theorems do.
        progress: Called with one short line as each stage of the sampled-data search starts
            (``"enclosing 236 cells (||e|| <= 0.01, ||r|| <= 0.45)"``), or ``None``.
    """
    if not isinstance(controller, IntervalPassivityController):
        raise InputError(
            "the certificate is that of the interval controller (urpc.synthesize); got "
            f"{type(controller).__name__}",
            field="controller",
        )
    check_trajectory_dof(trajectory, controller.dof, f"the robot {controller.robot.name!r}")
    duration = positive_number("duration", duration, "a finite number > 0 [s]")
    box = controller.bound.box
    if disturbance_bound is not None:
        disturbance_bound = number_in(
            "disturbance_bound", disturbance_bound, "a finite number >= 0 [N m]", lambda x: x >= 0
        )
    d = box.disturbance_bound if disturbance_bound is None else float(disturbance_bound)
    if cells is not None:
        checked_count("cells", cells, 1, ", or None (chosen from the reference's speed)")
    conditions = controller.gain_law.conditions()
    law_delay = int(controller.delay)
    plant_delay = actuation_delay_of(controller, actuation_delay)
    # The argument covers a torque acting over its sample's period (docs/sampled-data.md §2) and
    # the delayed law behind the one-sample delay it predicts over (§7); nothing else.
    delay = 0 if plant_delay == law_delay else max(law_delay, plant_delay)
    if law_delay and not delay:
        conditions.append(
            Condition(
                DELAY_CONDITION, True, float(law_delay), float(law_delay),
                "the one-sample delay the law predicts over is counted (docs/sampled-data.md "
                "§7: a common quadratic form of the delayed loop)",
            )
        )  # fmt: skip
    if delay:
        late = count(delay, "sample")
        if law_delay:
            why = (
                f"this plant applies each torque {count(plant_delay, 'sample')} after its "
                f"sample (actuation_delay) while the law predicts over "
                f"{count(law_delay, 'sample')}: synthesize the law with delay: {plant_delay}"
                if plant_delay <= 1
                else f"this plant applies each torque {late} late (actuation_delay), more "
                "than the one sample the delayed law predicts over"
            )
        else:
            why = (
                f"this plant applies each torque {late} later (actuation_delay), which the "
                "undelayed law does not predict: certify the configuration without delay"
                + (", or synthesize the law with delay: 1" if plant_delay == 1 else "")
            )
        conditions.append(
            Condition(
                DELAY_CONDITION, False, float(plant_delay), float(law_delay),
                "the certificate covers a torque acting over the period of its sample, and "
                f"the delayed law behind the one-sample delay it predicts over; {why}",
            )
        )  # fmt: skip
    floor_of = CellFloor(controller, trajectory, duration, cells=cells)
    try:
        floor_of.trajectory.jerk_bound(np.zeros(1), np.full(1, float(duration)))
    except NotImplementedError as exc:
        raise InputError(str(exc), field="trajectory") from None
    law = controller.feedback
    # Overflow and nan in an enclosure (a tube of 1e300 rad, a vacuous box) come out as inf or nan
    # quantities, which fail their conditions; numpy's warnings about them would only be noise.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        argument = law.argument(controller, floor_of, d, progress, require_efforts)
    reference = reference_torque(controller, trajectory, floor_of.span)
    if reference is not None:
        conditions.append(reference)
    # The gain conditions and the reference's torque do not depend on the period: when one
    # fails, no period is certified (a delay keeps the undelayed loop's figures, above).
    fixed = [c for c in conditions if not c.holds and c.name != DELAY_CONDITION]
    max_period = 0.0 if fixed else argument.max_sample_period
    conditions += argument.conditions
    required = require_efforts and bool(np.any(effort_limits(controller.robot)[1]))
    if required and not any(c.name == EFFORT_CONDITION for c in argument.conditions):
        conditions.append(
            Condition(
                EFFORT_CONDITION, False, math.inf, 1.0,
                "this argument bounds no commanded torque ("
                + ("the continuous-time theorems assume an unclipped torque"
                   if controller.sample_period is None
                   else "no finite floor, so no regime to bound it in")
                + "): the sampled implicit law's certificate bounds it",
            )
        )  # fmt: skip
    floor, figures = argument.floor, argument.figures
    holds = all(c.holds for c in conditions) and floor <= controller.epsilon
    if not holds:
        note = law.advice(controller, argument)
        if fixed:  # no period or epsilon helps: say what does
            note = (
                f"no period or epsilon certifies this configuration: '{fixed[0].name}' fails "
                f"whatever the period ({fixed[0].explanation})"
            )
        effort = next((c for c in argument.conditions if c.name == EFFORT_CONDITION), None)
        others = [c for c in conditions if not c.holds and c.name != EFFORT_CONDITION]
        if effort is not None and not effort.holds and not others and floor <= controller.epsilon:
            note = "to certify within the effort limits: " + figures["effort_fix"]
        if note is not None:
            figures["advice"] = note
        if delay:  # no period or epsilon makes up for a delay the argument does not count
            others = [c for c in conditions if c.name != DELAY_CONDITION]
            undelayed = all(c.holds for c in others) and floor <= controller.epsilon
            fix = (
                f"synthesize the law with delay: {plant_delay}"
                if plant_delay <= 1
                else "the argument covers the delays of 0 and 1 sample the laws predict over"
            )
            figures["advice"] = (
                "no period or epsilon certifies a plant that applies each torque "
                f"{count(plant_delay, 'sample')} after its sample behind a law that predicts "
                f"over {count(law_delay, 'sample')}: {fix}; behind its own delay the law "
                + (
                    "is certified" if undelayed
                    else f"is not certified either ({note})" if note is not None
                    else "is not certified either"
                )
            )  # fmt: skip
    ordered = tuple(sorted(conditions, key=lambda c: c.holds))
    return Certificate(
        bool(holds), controller.epsilon, float(floor), float(max_period),
        controller.sample_period, law.name, ordered, figures,
    )  # fmt: skip
