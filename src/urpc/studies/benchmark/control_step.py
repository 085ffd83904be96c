"""The control step: each robot's controller at a fixed state, and where one step's time goes."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from ...control.interval import IntervalPassivityController
from ...errors import InputError
from .robots import BENCHMARK_ROBOTS
from .timing import time_calls

#: The scenario whose controller, box and settings each robot's control step and synthesis use:
#: the robot's 1 kHz scenario (implicit sampled-data law); for the RR arm, scenario 3 (the paper's
#: law unchanged).
CONTROL_SCENARIOS = {
    "rr_planar": "rr_planar/s3_ic1",
    "ur5": "ur5/sampled",
    "panda": "panda/sampled",
    "ur5_drives": "ur5/joint_friction",
    "panda_drives": "panda/joint_friction",
}
#: The same arms with uncertain armature, damping and friction (the joint terms' cost).
DRIVE_ROBOTS = ("ur5_drives", "panda_drives")


def control_setup(robot_name: str):
    """The scenario setup and the synthesized controller of ``robot_name``'s
    :data:`CONTROL_SCENARIOS` entry, and a fixed state ``(t, q, qd, reference, state)`` on its
    trajectory: ``t = 1.3`` s, ``q = q_d + e`` with ``||e|| = 2 epsilon`` (alternating signs),
    ``qd = qd_d``, the gain integral ``s = 0.05`` rad s (Theorem 2).

    Raises:
        InputError: a robot without an entry (the message lists them).
    """
    from ..scenario import build, build_controller, load_scenario

    setup = build(load_scenario(control_scenario(robot_name)))
    controller = build_controller(setup, "interval")
    t = 1.3
    reference = setup.trajectory.reference(t)
    dof = setup.robot.dof
    signs = np.where(np.arange(dof) % 2 == 0, 1.0, -1.0)
    q = reference.q + 2.0 * setup.scenario.epsilon * signs / np.sqrt(dof)
    qd = reference.qd.copy()
    state = controller.initial_state() + 0.05
    return setup, controller, (t, q, qd, reference, state)


def control_scenario(robot_name: str) -> str:
    """The :data:`CONTROL_SCENARIOS` entry of a robot.

    Raises:
        InputError: a robot without an entry (the message lists them).
    """
    if robot_name not in CONTROL_SCENARIOS:
        valid = ", ".join(CONTROL_SCENARIOS)
        raise InputError(
            f"no control scenario for robot '{robot_name}'; valid: {valid}", field="robot"
        )
    return CONTROL_SCENARIOS[robot_name]


def control_step_call(robot_name: str) -> Callable[[], object]:
    _, controller, args = control_setup(robot_name)
    return lambda: controller.output(*args)


def profile_control_step(
    robots: Sequence[str] = BENCHMARK_ROBOTS, repeats: int = 101
) -> dict[str, dict[str, float]]:
    """Where one control step's time goes, per robot [s per call], timed side by side.

    Parts of :meth:`IntervalPassivityController.output` (with the default, regressor-based
    method): ``regressor`` (``Y_SL``, the Pinocchio regressor calls), ``bound`` (the enclosure
    from ``Y_SL``), ``nominal`` (``Y_SL pi0``), ``sampled_law`` (the implicit feedback: ``M_L(q) + D T 1``
    by one CRBA and one Cholesky solve; only with the implicit sampled-data law), of which
    ``inertia`` (``M_L(q) + D T 1`` as the law builds it: the CRBA of the lower-bound model and
    the diagonal shift), ``crba`` (the bare Pinocchio call) and ``solve`` (LAPACK ``dposv``)
    alone; ``arithmetic`` (a replica of the array arithmetic of ``output`` around those calls:
    ``e``, ``qd_a``, ``qdd_a``, ``r``, ``rho``, its norm, the gain, the sum); ``other`` =
    ``joint_terms`` (the drives' nominal torque and enclosure, for the ``*_drives`` entries of
    :data:`DRIVE_ROBOTS`); ``output`` minus the parts (call overhead, and what the parts lose when they run together
    rather than alone); ``output_paper_law`` (the same step with the paper's law, so that the
    difference is the sampled law's cost inside the step); and ``rnea`` for scale.
    """
    return {robot_name: _profile_robot(robot_name, repeats) for robot_name in robots}


def _profile_robot(robot_name: str, repeats: int) -> dict[str, float]:
    _, controller, args = control_setup(robot_name)
    t, q, qd, reference, state = args
    bound, robot = controller.bound, controller.robot
    if not bound.uses_regressor:
        raise InputError(
            f"the {bound.name} method has no regressor path to profile", field="method"
        )
    e, ed = reference.q - q, reference.qd - qd
    qd_a, qdd_a = reference.qd + controller.Kr * e, reference.qdd + controller.Kr * ed
    r = ed + controller.Kr * e
    Y = bound.regressor(q, qd, qd_a, qdd_a)
    pi0 = np.asarray(robot.nominal_parameters, dtype=float)
    lower, upper = bound.enclose_regressor(Y)
    nominal = Y @ pi0
    Kr = controller.Kr
    kappa_P, kappa_I, phi_P, phi_I = (
        controller.kappa_P,
        controller.kappa_I,
        controller.phi_P,
        controller.phi_I,
    )

    def arithmetic():
        # A replica of output()'s own array arithmetic around the calls timed separately.
        e = reference.q - q
        ed = reference.qd - qd
        Kr_e = Kr * e
        _ = reference.qd + Kr_e, reference.qdd + Kr * ed
        r = ed + Kr_e
        rho = np.maximum(-lower, upper)
        rho_norm = math.sqrt(rho @ rho)
        s = state[0]
        gain = (kappa_P + kappa_I * s) * rho_norm + phi_P + phi_I * s
        return nominal + gain * r

    data = robot.model.createData()
    config = robot.configuration(q)
    functions: dict[str, Callable[[], object]] = {
        "output": lambda: controller.output(*args),
        "regressor": lambda: bound.regressor(q, qd, qd_a, qdd_a),
        "bound": lambda: bound.enclose_regressor(Y),
        "nominal": lambda: Y @ pi0,
        "arithmetic": arithmetic,
        "rnea": lambda: pin.rnea(robot.model, data, config, qd, qdd_a),
    }
    if controller.implicit:
        # The feedback law's torque is exactly what output() adds for the implicit law.
        # Not ``lower``: that name is the enclosure the arithmetic replica reads.
        lower_robot = controller.inertia_bounds.lower_robot
        lower_data = lower_robot.model.createData()
        functions["sampled_law"] = lambda: controller.feedback.torque(q, 1e3, r)
        paper = IntervalPassivityController(  # the same bound method and gains; the paper's law
            bound,
            controller.epsilon,
            kappa_P=kappa_P,
            kappa_I=kappa_I,
            phi_P=phi_P,
            phi_I=phi_I,
            Kr=Kr,
            sample_period=controller.sample_period,
            sampled_law="paper",
        )
        functions["output_paper_law"] = lambda: paper.output(*args)
        step, stride = 1e3 * controller.sample_period, len(q) + 1

        def inertia():
            # M_L(q) + D T 1 as the law builds it: the raw CRBA (upper triangle), then the shift.
            shifted = pin.crba(lower_robot.model, lower_data, lower_robot.configuration(q))
            shifted.flat[::stride] += step
            return shifted

        functions["inertia"] = inertia
        functions["crba"] = lambda: pin.crba(lower_robot.model, lower_data, config)
        shifted = inertia().copy()
        functions["solve"] = lambda: dposv(shifted, r, lower=0)
    joints = bound.joints
    if joints is not None:
        scratch_lower, scratch_upper, torque = lower.copy(), upper.copy(), np.zeros(len(q))

        def joint_terms():
            # What output() adds for the drives: their nominal torque and their enclosure.
            bound.add_joint_terms(scratch_lower, scratch_upper, qd, qd_a, qdd_a, torque=torque)

        functions["joint_terms"] = joint_terms
    times = time_calls(functions, repeats)
    parts = ("regressor", "bound", "nominal", "joint_terms", "arithmetic", "sampled_law")
    times["other"] = times["output"] - sum(times.get(name, 0.0) for name in parts)
    return times


#: Columns of :func:`format_profile`: key, heading.
PROFILE_COLUMNS = (
    ("output", "control step"),
    ("output_paper_law", "step with the paper's law"),
    ("regressor", "regressor Y_SL"),
    ("bound", "bound from Y_SL"),
    ("nominal", "nominal Y_SL pi0"),
    ("joint_terms", "joint terms"),
    ("arithmetic", "array arithmetic"),
    ("sampled_law", "implicit law"),
    ("inertia", "of which M_L(q) + D T 1"),
    ("crba", "of which bare crba"),
    ("solve", "of which solve (dposv)"),
    ("other", "other"),
    ("rnea", "RNEA"),
)


def format_profile(profile: dict[str, dict[str, float]]) -> str:
    """A Markdown table of :func:`profile_control_step`: microseconds and share of the step."""
    lines = [
        "| robot | " + " | ".join(f"{heading} [us]" for _, heading in PROFILE_COLUMNS) + " |",
        "|---" * (1 + len(PROFILE_COLUMNS)) + "|",
    ]
    for robot, times in profile.items():
        cells = []
        for key, _ in PROFILE_COLUMNS:
            if key not in times:
                cells.append("-")
            elif key in ("output", "output_paper_law", "rnea"):
                cells.append(f"{1e6 * times[key]:.1f}")
            else:
                cells.append(f"{1e6 * times[key]:.1f} ({100 * times[key] / times['output']:.0f} %)")
        lines.append(f"| {robot} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
