"""What a certificate tells its user beyond the verdict: the torque the law commands against the
effort limits, and, when a configuration is not certified, what to change (the period, the
epsilon, the term, joint and link that dominate the floor), in text for ``urpc certify`` and in
the certificate's ``figures`` for ``--json``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .argument import Condition
from .cells import CellFloor, plant_torque
from .interval import IntervalPassivityController


def torque_figures(search, controller, d: float, quantities: dict, parts: dict) -> dict:
    """The bound of the commanded torque per joint once in the floor's regime, against the
    URDF's effort limits (a non-positive or infinite limit counts as none). Not a condition of
    ``certified``: a torque the argument cannot keep below the limit is reported, with the
    joint, in ``torque_note`` and the summary, together with the longest period (below this
    one) at which the configuration is certified with every joint's bound within its effort
    (``torque_period`` [s], 0 when none is, :func:`torque_period`). ``search``: the
    :class:`~urpc.control.sampled_search.SampledSearch` that found the floor."""
    T = controller.sample_period
    bound = search.bound.torque_bound(T, d, quantities, parts["tube"], parts["r_sup"])
    effort, limited = effort_limits(controller.robot)
    out: dict[str, Any] = {"torque_bound": bound.tolist(), "torques_within_limits": True}
    if not np.any(limited):
        out["torques_within_limits"] = None
        return out
    worst = most_exceeded(bound, effort, limited)
    if worst is not None:
        joint = controller.robot.joint_names[worst]
        # The plant's own torque along the reference itself (e = 0, over the box) is part of
        # the bound at every period: when it alone exceeds an effort, no period helps.
        plant = np.max(plant_torque(quantities, 0.0), axis=0)
        j = most_exceeded(plant, effort, limited)
        within = 0.0 if j is not None else torque_period(search, quantities, effort, limited)
        if j is not None:
            change = (
                f"no period brings it within: the plant's own torque along the reference, over "
                f"the box, is already {plant[j]:.4g} N m on joint "
                f"'{controller.robot.joint_names[j]}' (effort {effort[j]:.4g} N m; a narrower "
                "box or a gentler reference lowers it)"
            )
        elif within > 0:
            change = f"proven within them at T = {within:.3g} s"
        else:
            change = f"not proven within them down to T = {T * TORQUE_PERIODS[-1]:.3g} s"
        out["torques_within_limits"] = False
        out["torque_period"] = within
        if j is not None:
            out["torque_fix"] = change
        out["torque_note"] = (
            f"torques within the effort limits not proven: joint '{joint}' bound "
            f"{bound[worst]:.4g} N m > effort {effort[worst]:.4g} N m (the argument assumes an "
            f"unclipped torque); {change}"
        )
    return out


#: The condition :func:`effort_condition` adds when ``certify(..., require_efforts=True)``.
EFFORT_CONDITION = "commanded torque within the effort limits"


def effort_condition(
    search, controller, figures: dict, quantity_sets: list, max_period: float
) -> tuple[Condition, float]:
    """The condition that the commanded torque's bound (:func:`torque_figures`, already in
    ``figures``) is within every limited joint's effort at the controller's period, and the
    largest period that is both certified and within the efforts: ``max_period`` itself when
    its bound is, else the longest of ``max_period 0.9^k`` and ``T 0.9^k`` (``k >= 0``, those
    of :func:`torque_period` among them) that is (each judged on its
    own, with any of ``quantity_sets``: the enclosures of the search's partitions, all sound up
    to twice the period), 0 when none is. Robots without effort limits: the condition holds.
    When it fails, ``figures["effort_fix"]`` says what would make it hold."""
    T = controller.sample_period
    effort, limited = effort_limits(controller.robot)
    if not np.any(limited):
        return (
            Condition(
                EFFORT_CONDITION, True, 0.0, 1.0,
                "the robot has no effort limits (none in its URDF): nothing clips the torque",
            ),
            max_period,
        )  # fmt: skip
    bound = np.asarray(figures["torque_bound"], dtype=float)
    ratio = float(np.max(bound[limited] / effort[limited]))
    holds = bool(figures["torques_within_limits"])
    # The periods torque_period tries below T, too: the strict verdict never names a shorter
    # period than the default one's note.
    candidates = sorted(
        {max_period * 0.9**k for k in range(len(TORQUE_PERIODS) + 1)}
        | {T * f for f in (1.0, *TORQUE_PERIODS) if T * f <= max_period},
        reverse=True,
    )
    within = 0.0
    if max_period > 0:
        within = next(
            (
                period for period in candidates
                if any(_within_at(search, q, period, effort, limited) for q in quantity_sets)
            ),
            0.0,
        )  # fmt: skip
    if holds:
        explanation = (
            "the commanded torque's bound in the floor's regime is within every joint's effort "
            f"(at most {ratio:.3g} of it)"
        )
    else:
        joint = controller.robot.joint_names[most_exceeded(bound, effort, limited)]
        fix = (
            f"shorten the period to {within * 1e3:.3g} ms (certified within the efforts there)"
            if within > 0
            else figures.get(
                "torque_fix",
                f"no certified period down to {max_period * TORQUE_PERIODS[-1] * 1e3:.3g} ms "
                "is proven within them (a smaller epsilon or Kr, a narrower box or a gentler "
                "reference lowers the bound)"
                if max_period > 0
                else "no period is certified",
            )
        )
        explanation = (
            f"joint '{joint}' may be commanded {ratio:.3g} times its effort (the bound in the "
            f"floor's regime): a clipped torque voids the argument; {fix}"
        )
        figures["effort_fix"] = fix
    return Condition(EFFORT_CONDITION, holds, ratio, 1.0, explanation), within


def _within_at(search, quantities: dict, period: float, effort, limited) -> bool:
    """Certified at ``period`` on ``quantities`` (floor at most epsilon in a consistent tube)
    with every limited joint's torque bound within its effort."""
    floor, parts, rho = search.least_tube(quantities, period)
    if not (floor <= search.epsilon and parts.get("r_sup", math.inf) <= quantities["r_max"]):
        return False
    bound = search.bound.torque_bound(period, search.d, quantities, rho, parts["r_sup"])
    return bool(np.all(bound[limited] <= effort[limited]))


#: The periods :func:`torque_period` tries, as fractions of the controller's period.
TORQUE_PERIODS = tuple(0.9**k for k in range(1, 23))  # down to 0.098 T


def torque_period(search, quantities: dict, effort: np.ndarray, limited: np.ndarray) -> float:
    """The longest period of :data:`TORQUE_PERIODS` (fractions of the controller's, longest
    first) at which the configuration is certified (floor at most epsilon in a consistent
    tube) with every limited joint's torque bound within its effort [s]; 0 when none is. Each
    period is judged on its own with the enclosures of the floor (they hold up to twice the
    period): sound for the period returned, whether or not the bound falls monotonically."""
    for fraction in TORQUE_PERIODS:
        period = search.T * fraction
        if _within_at(search, quantities, period, effort, limited):
            return float(period)
    return 0.0


def most_exceeded(value: np.ndarray, limit: np.ndarray, limited: np.ndarray) -> int | None:
    """The joint whose ``value`` exceeds its ``limit`` by the largest ratio, among the
    ``limited`` ones, or ``None`` when none exceeds its limit."""
    ratio = np.where(limited, value / np.where(limited, limit, 1.0), 0.0)
    worst = int(np.argmax(ratio))
    return worst if ratio[worst] > 1.0 else None


def effort_limits(robot) -> tuple[np.ndarray, np.ndarray]:
    """The URDF's effort limits [N m or N] and which joints have one (a non-positive or
    infinite limit counts as none)."""
    effort = np.asarray(robot.effort_limit, dtype=float)
    return effort, np.isfinite(effort) & (effort > 0)


#: Times of the reference and plants of the box :func:`reference_torque` tries.
REFERENCE_SAMPLES, REFERENCE_PLANTS = 401, 64


def reference_torque(controller, trajectory, span: float) -> Condition | None:
    """Whether the reference itself can be followed within the URDF's effort limits: the
    torque ``M(q_d) qdd_d + C(q_d, qd_d) qd_d + g(q_d)`` plus the drives' (armature, damping,
    friction) at :data:`REFERENCE_SAMPLES` times of ``[0, span]`` [s] on the nominal plant and
    at most :data:`REFERENCE_PLANTS` vertices of the box (every vertex when there are no more).
    A sampled torque above a joint's effort proves that this plant cannot follow the reference
    (no controller can: the condition fails, naming the joint, the time and the plant); below
    everywhere, the condition holds for the samples tried, which proves nothing more (the
    commanded torque's bound, :func:`torque_figures`, is the upper side). ``None`` without
    effort limits."""
    import pinocchio as pin

    from ..model.joint_dynamics import friction_torque
    from ..model.regressor_balls import parameters_of

    robot, box = controller.robot, controller.bound.box
    effort, limited = effort_limits(robot)
    if not np.any(limited):
        return None
    count = 2**box.n_uncertain
    if count <= REFERENCE_PLANTS:
        vertices = list(range(count))
    else:  # the all-lower and all-upper corners, then distinct seeded ones
        vertices = [0, count - 1]
        for index in box.random_vertices(np.random.default_rng(0)):
            if len(vertices) == REFERENCE_PLANTS:
                break
            if index not in (0, count - 1):
                vertices.append(index)
    plants = [("the nominal plant", box.plant(robot, None))] + [
        (f"vertex {k} of the box", box.plant(robot, box.vertex(k))) for k in vertices
    ]
    times = np.linspace(0.0, span, REFERENCE_SAMPLES)
    q, qd, qdd = (np.atleast_2d(x) for x in trajectory.evaluate(times))
    # The rigid bodies by the regressor (the plants share the kinematics), the drives per plant.
    model, data = robot.model, robot.model.createData()
    Y = np.stack([
        pin.computeJointTorqueRegressor(model, data, robot.configuration(q[k]), qd[k], qdd[k])
        for k in range(len(times))
    ])  # fmt: skip  # (times, n, 10 n)
    worst, where = 0.0, None
    for label, plant in plants:
        joints = plant.model
        tau = Y @ parameters_of(plant) + joints.armature * qdd
        tau = tau + friction_torque(joints.damping, joints.friction, qd)
        ratio = np.where(limited, np.abs(tau) / np.where(limited, effort, 1.0), 0.0)
        k, joint = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        if ratio[k, joint] > worst:
            worst = float(ratio[k, joint])
            where = (int(joint), float(times[k]), label, float(tau[k, joint]))
    holds = worst <= 1.0
    explanation = "the reference needs less than the effort limits on the plants tried"
    if not holds:
        joint, t, label, tau = where
        explanation = (
            f"the reference needs {abs(tau):.4g} N m on joint '{robot.joint_names[joint]}' at "
            f"t = {t:.3g} s ({label}), above its effort limit {effort[joint]:.4g} N m: no "
            "controller follows it there; slow the reference down or narrow the box"
        )
    return Condition("the reference within the effort limits", holds, worst, 1.0, explanation)


#: What each term of the floor is, for the advice.
TERMS = {
    "mismatch": "the model mismatch w over the box (the held loop's quasi-static error)",
    "torque_lag": "the nominal torque's change within a period",
    "disturbance": "the disturbance's response, through the lightest inertia mode",
    "deviation": "the motion of the quasi-static error and the perturbations of the period "
    "(Coriolis, the metric's change, T Kr) acting on it",
}


#: A certified period below this [s] (10 kHz) is of no use on an arm: the advice then says what
#: in the box makes the contraction small.
IMPRACTICAL_PERIOD = 1e-4

#: When ``beta`` at the cell's centre exceeds this many times its bound over the cell and the
#: tube, the advice blames the enclosure, not the box (an 8-link chain: 0.82 against 0.033 at
#: 1 kHz, 0.46 with four times the first cells).
ENCLOSURE_LOSS = 2.0


def advice(
    figures: dict, floor: float, controller: IntervalPassivityController, max_period: float
) -> str:
    """One paragraph: the changes that certify (computed: the period; the epsilon of the floor
    in a wider tube) and what the floor is made of (term, joint, link)."""
    T = controller.sample_period
    changes = []
    if max_period > 0:
        changes.append(f"shorten the period to {max_period * 1e3:.3g} ms (certified there)")
    else:
        changes.append("no period up to 2 T is certified")
    if math.isfinite(floor) and floor > controller.epsilon:
        changes.append(f"raise epsilon to {floor:.3g} rad (the floor at T = {T * 1e3:.3g} ms)")
    text = "to certify: " + ", or ".join(changes)
    term = figures.get("dominant_term")
    if "invalid_cell" in figures:
        start = figures.get("invalid_time", math.nan)
        if figures.get("invalid_for_tube"):
            return (
                text + f"; the inertia bounds fail on the cell that starts at t = {start:.3g} s "
                "for the tube's sake: the inertia changes more over ||e|| <= epsilon alone "
                "than the bounds allow (no narrower cell helps): a smaller epsilon, or "
                "narrower mass and inertia intervals"
            )
        return (
            text + f"; the inertia bounds fail on the cell that starts at t = {start:.3g} s "
            "(M_L not positive definite or beta <= 0 over that cell's box of q and the "
            "parameters): narrow the box's mass and inertia intervals, or use more cells"
        )
    if term is None and not controller.adaptive:
        return text + (
            f"; the gains are constant (Theorem 1: the box states its disturbance bound), so "
            f"the contraction a = {figures.get('contraction', math.nan):.3g} grows with T "
            f"phi_P as the perturbation b grows with T (a - b = "
            f"{figures.get('margin', math.nan):.3g}): no period helps. Raise phi_P "
            f"({_gain_room(controller)}; a approaches beta = "
            f"{figures.get('beta', math.nan):.3g} once T phi_P passes the inertia), or state "
            "`disturbance: unknown` for Theorem 2's adaptive gains"
        )
    if term is None and "delay_ranges" in figures:  # the delayed law (docs/sampled-data.md §7)
        rate = figures.get("delay_rate")
        if rate is None:
            return text + (
                "; no common quadratic form contracts the delayed loop over this box (the "
                "nominal model it predicts with is too far from some of its plants): narrow "
                "the mass and inertia intervals, or run without delay"
            )
        return text + (
            f"; the delayed loop's form contracts by {rate:.3g} per period and the period's "
            f"perturbations (of order T Kr and T |qd|) take the rest (margin "
            f"{figures.get('margin', math.nan):.3g}): a shorter period or a lower Kr helps"
        )
    if term is None:
        margin = figures.get("margin", math.nan)
        text += (
            f"; the period's perturbation b exceeds its contraction a (a - b = {margin:.3g}"
            "): b grows with T Kr and T |qd|, so a shorter period or a lower Kr helps"
        )
        joint = figures.get("lightest_joint")
        if joint is not None and max_period < IMPRACTICAL_PERIOD:
            text += (
                f"; that period is faster than torque interfaces run: the contraction a = "
                f"{figures.get('contraction', math.nan):.3g} is at most beta = "
                f"{figures.get('beta', math.nan):.3g} (the box's inertia lower bound over its "
                f"upper bound along the worst mode) and the lightest mode, joint '{joint}' at "
                f"t = {figures['worst_time']:.3g} s (lambda_L = "
                f"{figures.get('lambda_L', math.nan):.3g}), divides the perturbations: "
            )
            center, cell = figures.get("beta_center", math.nan), figures.get("beta_cell", math.nan)
            if center > ENCLOSURE_LOSS * cell:
                text += (
                    f"at that cell's centre the box gives beta = {center:.3g}, over the cell "
                    f"and the tube {cell:.3g}: the rest is the inertia models' relative radius "
                    "(the cell's width and the tube's, through the lightest mode), not the box; "
                    "more first cells (urpc certify --cells N, urpc.certify(..., cells=N)) or a "
                    "smaller epsilon narrow it. The box's own beta: "
                )
            text += (
                "narrow the mass and inertia intervals of the links that joint moves, or lock it"
            )
        return text
    share = figures["term_shares"][term]
    text += (
        f"; the floor is {share:.0%} '{term}' ({TERMS[term]}), at t = "
        f"{figures['worst_time']:.3g} s, through joint '{figures['lightest_joint']}'"
        " (the lightest mode)"
    )
    link = figures.get("dominant_link")
    if link is not None:
        text += (
            f"; link '{link}' is {figures['dominant_link_share']:.0%} of the mismatch: "
            "narrowing its box lowers the mismatch and deviation terms"
        )
    if term == "disturbance":
        text += "; a smaller disturbance bound or a larger Kr lowers it in proportion"
    if not controller.adaptive and max_period <= 0:
        text += (
            f"; the gains are constant (Theorem 1), so a shorter period shrinks the contraction "
            f"too: raise phi_P ({_gain_room(controller)})"
        )
    return text


def _gain_room(controller: IntervalPassivityController) -> str:
    """Where Theorem 1's constant gain stands against the ceiling Theorem 2's gains stop at."""
    return (
        f"now {controller.phi_P:.3g} N m s/rad; Theorem 2's adaptive gains stop at phi_max = "
        f"{controller.phi_max:.3g} N m s/rad at this period"
    )


def lightest_joint(floor_of: CellFloor, quantities: dict, cell: int) -> int:
    """The joint whose diagonal of ``M_L^-1`` is largest at a cell (the lightest mode's joint)."""
    inverse = quantities["law_inverse_diagonal"][cell]
    return int(np.argmax(inverse))


def dominant_link(floor_of: CellFloor, quantities: dict, piece: int, cell: int, tube: float):
    """The uncertain link with the largest part of ``||M_L^-1 w||`` at a cell of a piece, and
    that part's share, or ``None`` without uncertain links."""
    parts = quantities["pieces"][piece]["R_links"]
    if not len(parts):
        return None
    values = parts[:, 0, cell] + tube * parts[:, 1, cell]
    k = int(np.argmax(values))
    return floor_of.pieces[piece].uncertain_links[k].link, float(values[k] / np.sum(values))
