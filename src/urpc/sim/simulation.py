"""Closed-loop simulation of a true plant under a controller, continuous or sampled.

The plant is a :class:`~urpc.model.robot.Robot` carrying the *true* parameters; its accelerations come
from Pinocchio's articulated-body algorithm. The plant sees ``sat(u) + d``: the controller's torque
``u``, clipped to the optional per-joint ``torque_limit``, plus an input disturbance ``d``.

The controller owns its period: a controller synthesized with ``sample_period=T``
(``controller.sample_period``) runs sampled at ``T``, one without (``None``) in continuous time;
the period is never given a second time here.

* **Continuous time** (``sample_period=None``, the paper's scenario 1): the plant state and the
  controller's internal state form one ODE, integrated by :func:`scipy.integrate.solve_ivp` with
  tight tolerances; series are recorded on a fixed output grid (``solver.output_rate``, 1 kHz)
  from the solver's dense output, the torque being re-evaluated at each grid point.
* **Sampled** (scenarios 2, 3): at each sample ``t_k = k T`` the controller reads ``(q, qd)``,
  its output is held (zero-order hold) over ``[t_k, t_k + T)`` together with a disturbance ``d_k``
  drawn uniformly in the ball ``||d|| <= disturbance_bound`` (seeded), and a stepper
  (:class:`~urpc.sim.plants.Plant`) of the chosen backend (``plant_backend``: ``pinocchio``, the
  reference, or the independent ``mujoco`` one) integrates the period by classical Runge-Kutta 4
  with steps of at most ``solver.integration_step``. Under a held torque the plant alone is not
  stiff, so RK4 with ``1e-4`` s steps is accurate to far below the tracking tolerances
  (``tests/test_simulation.py`` compares it with ten times finer steps). The controller's state
  advances once per sample (:meth:`Controller.advance`).
* **Actuation delay** (``actuation_delay``, sampled runs): a whole number ``d`` of samples
  between a state and the period its torque acts over, as on a real torque interface (most apply
  the torque answering ``t_k`` at ``t_{k+1}``: ``d = 1``). The command computed at ``t_k`` acts
  over ``[t_{k+d}, t_{k+d+1})``; before the first command arrives (the first ``d`` periods) the
  plant holds a zero torque. Counted in samples, like the delayed law
  (:mod:`urpc.control.delay`) and the virtual robot: a delay that is not a multiple of the period
  would switch the torque inside a period, which a zero-order hold does not model. The default is
  the delay the law predicts over (``controller.delay``: 0, or 1 for the delayed law).
  ``urpc.certify``'s argument covers no delay (docs/sampled-data.md §3).

The integrator's settings are one :class:`~urpc.sim.options.SolverOptions` (``solver=``); the
report's labels are set on the result (:meth:`SimulationResult.labelled`).

A run that diverges (a non-finite value, ``|q|`` or ``|qd|`` above ``max_state``, a solver failure)
raises :class:`~urpc.errors.SimulationError` naming the time and the state.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..control.base import Controller, actuation_delay_of
from ..errors import InputError
from ..model.robot import Robot
from ..trajectories import Trajectory
from ..validation import (
    check_run_length,
    check_trajectory_dof,
    check_type,
    finite_vector,
    positive_number,
)
from .closed_loop import RunSetup
from .continuous import (  # noqa: F401 (the defaults, read here by older code)
    CONTINUOUS_ATOL,
    CONTINUOUS_METHOD,
    CONTINUOUS_RTOL,
    run_continuous,
)
from .options import SolverOptions, legacy_arguments
from .plants import PLANTS, make_plant
from .progress import SimulationProgress
from .results import SimulationResult
from .sampled import DISTURBANCES, run_sampled


def simulate(
    plant: Robot,
    controller: Controller,
    trajectory: Trajectory,
    *,
    duration: float,
    q0: np.ndarray | None = None,
    qd0: np.ndarray | None = None,
    disturbance_bound: float = 0.0,
    disturbance: str = "ball",
    seed: int = 0,
    torque_limit: float | np.ndarray | None = None,
    epsilon: float | None = None,
    plant_backend: str = "pinocchio",
    controller_state0: np.ndarray | None = None,
    actuation_delay: int | None = None,
    solver: SolverOptions | None = None,
    progress: bool | Callable[[float], Any] | Any | None = None,
    **deprecated: Any,
) -> SimulationResult:
    """Simulate ``plant`` under ``controller`` tracking ``trajectory``.

    Args:
        plant: The true plant (a robot with the true parameters).
        controller: The control law (built once, reusable: its state is explicit). It runs at
            its own period ``controller.sample_period`` [s] (zero-order hold), or in continuous
            time when that is ``None``.
        trajectory: Object with ``reference(t) -> Reference``.
        duration: Simulated time [s] (a sampled run is rounded up to whole periods).
        q0, qd0: Initial joint positions [rad] and velocities [rad/s]; ``None`` starts on the
            reference at ``t = 0``.
        disturbance_bound: Radius [N m] of the ball the input disturbance is drawn from, once per
            sample (sampled runs only).
        disturbance: ``"ball"`` (``d_k`` drawn uniformly in that ball), ``"against"``
            (``d_k = -disturbance_bound r_k / ||r_k||``, constant magnitude against the sliding
            variable ``r = (qd_d - qd) + Kr (q_d - q)``, ``Kr`` the controller's), ``"worst"``
            (against ``r`` in the plant's ``M^-1`` metric) or ``"lightest"`` (at its bound along
            the lightest mode of the law's inertia model ``M_L(q_k)``, sign held);
            :data:`urpc.sim.sampled.DISTURBANCES`.
        seed: Seed of the disturbance generator (``numpy.random.default_rng``).
        torque_limit: Per-joint bound [N m] (scalar or ``dof`` values) the command is clipped to;
            ``None`` for no limit.
        epsilon: Required precision [rad] for the metrics; defaults to ``controller.epsilon``.
        plant_backend: The backend that steps ``plant`` in a sampled run, a key of
            :data:`urpc.sim.plants.PLANTS` (``pinocchio`` or ``mujoco``); continuous time needs
            ``pinocchio``.
        controller_state0: The controller's internal state at ``t = 0`` (length
            ``controller.n_states``), e.g. to continue a run after a tool change; ``None`` uses
            ``controller.initial_state()``.
        actuation_delay: Samples between a state and the period its torque acts over (an
            integer >= 0; module docstring): the command of the sample at ``t_k`` is held over
            ``[t_{k+d}, t_{k+d+1})``, a zero torque over the first ``d`` periods. ``None``: the
            delay the law predicts over (``controller.delay``, 0 for an undelayed law). Recorded
            as ``info["actuation_delay"]``; a delay > 0 needs a sampled controller.
        solver: The integrator's settings (:class:`~urpc.sim.options.SolverOptions`: method,
            tolerances, output rate, RK4 step, divergence bound); ``None``: the defaults.
        progress: ``None``; ``True`` for a tqdm bar on stderr; a callable receiving the fraction
            done in ``[0, 1]``; or a tqdm-like object (``update``, ``total``), advanced by
            ``total`` times the fraction done (``total`` is set to 100 when it is ``None``).
        **deprecated: The older keywords, for one release (a ``DeprecationWarning`` each):
            ``method``, ``rtol``, ``atol``, ``output_rate``, ``integration_step`` and
            ``max_state`` (now ``solver=SolverOptions(...)``), ``scenario`` and
            ``plant_description`` (now ``simulate(...).labelled(scenario=..., plant=...)``).

    The result's ``scenario`` is empty and its ``plant`` describes the plant's link masses and
    centers of mass; :meth:`SimulationResult.labelled` sets others.

    Raises:
        InputError: an argument out of range (the message names it).
        SimulationError: the run diverged or the integrator failed (names the time and state).
    """
    start = time.perf_counter()
    _check_parts(plant, controller, trajectory)
    solver, labels = legacy_arguments(solver, deprecated)
    delay = actuation_delay_of(controller, actuation_delay)
    n = plant.dof
    reference0 = trajectory.reference(0.0)
    q0 = finite_vector("q0", reference0.q if q0 is None else q0, n)
    qd0 = finite_vector("qd0", reference0.qd if qd0 is None else qd0, n)
    duration = positive_number("duration", duration, "a finite number > 0 [s]")
    sample_period = controller.sample_period
    if delay and delay * sample_period > duration:
        samples = math.floor(duration / sample_period)
        raise InputError(
            f"a delay of {delay} samples ({delay * sample_period:.3g} s) is longer than the run "
            f"({duration:g} s, {samples} samples): no torque would act; give at most {samples}",
            field="actuation_delay",
        )
    if epsilon is None:
        epsilon = controller.epsilon
        if epsilon is None:
            raise InputError(
                f"controller '{controller.name}' has no epsilon; pass the required precision",
                field="epsilon",
            )
    epsilon = positive_number("epsilon", epsilon, "a finite number > 0 [rad]")
    disturbance_bound = float(disturbance_bound)
    if not (math.isfinite(disturbance_bound) and disturbance_bound >= 0):
        raise InputError(
            f"{disturbance_bound!r} is out of range; expected a finite number >= 0 [N m]",
            field="disturbance_bound",
        )
    if disturbance not in DISTURBANCES:
        raise InputError(
            f"unknown disturbance {disturbance!r}; valid: {', '.join(DISTURBANCES)}",
            field="disturbance",
        )
    try:
        valid_seed = int(seed) == seed and int(seed) >= 0
    except (TypeError, ValueError):
        valid_seed = False
    if not valid_seed:
        raise InputError(f"{seed!r} is not an integer >= 0", field="seed")
    if sample_period is None:
        check_run_length(duration, None, solver.output_rate)
    else:
        check_run_length(duration, sample_period)
    limit = None
    if torque_limit is not None:
        try:
            limit = np.asarray(torque_limit, dtype=float)
        except (TypeError, ValueError):
            raise InputError(
                f"{torque_limit!r} is not a number; expected numbers > 0 [N m], one or {n}",
                field="torque_limit",
            ) from None
        if limit.ndim > 1 or limit.size not in (1, n):
            raise InputError(
                f"{torque_limit!r} has {limit.size} entries; the plant '{plant.name}' has {n} "
                f"joints: give one number or {n}",
                field="torque_limit",
            )
        limit = np.broadcast_to(limit.reshape(-1)[0] if limit.size == 1 else limit, (n,)).copy()
        if not np.all(limit > 0):
            raise InputError(
                f"{torque_limit!r} is out of range; expected numbers > 0 [N m]",
                field="torque_limit",
            )
    if plant_backend not in PLANTS:
        raise InputError(
            f"unknown plant {plant_backend!r}; valid: {', '.join(PLANTS)}", field="plant"
        )
    if sample_period is None and plant_backend != "pinocchio":
        raise InputError(
            f"the {plant_backend} plant steps under a held torque: synthesize the controller "
            "with a sample_period, or use the pinocchio plant for continuous time",
            field="plant",
        )
    state0 = controller.initial_state()
    if controller_state0 is not None:
        state0 = controller.check_state(controller_state0, "controller_state0")
    common = dict(
        controller=controller.name,
        epsilon=epsilon,
        seed=int(seed),
        scenario=labels.get("scenario", ""),
        plant=describe_plant(plant) if labels.get("plant") is None else labels["plant"],
        disturbance_bound=disturbance_bound,
        torque_limit=None if limit is None else tuple(float(x) for x in limit),
    )
    bar = SimulationProgress(progress)
    setup = RunSetup(
        plant, controller, trajectory, duration, q0, qd0, state0, limit, solver.max_state, bar
    )
    try:
        if sample_period is None:
            if disturbance_bound > 0:
                raise InputError(
                    "an input disturbance is drawn once per control sample; synthesize the "
                    "controller with a sample_period or set disturbance_bound to 0 for "
                    "continuous time",
                    field="disturbance_bound",
                )
            series, info = run_continuous(
                setup, solver.method, solver.rtol, solver.atol, solver.output_rate
            )
        else:
            if sample_period > duration:
                raise InputError(
                    f"the controller's period {sample_period!r} s is longer than the duration "
                    f"{duration!r} s",
                    field="sample_period",
                )
            stepper = make_plant(plant_backend, plant, max_step=solver.integration_step)
            series, info = run_sampled(
                setup, stepper, disturbance_bound, int(seed), disturbance, delay
            )
            duration = float(series["t"][-1])
    finally:
        bar.close()
    info["actuation_delay"] = delay
    if sample_period is not None and disturbance != "ball":  # the default records nothing new
        info["disturbance_model"] = disturbance
    # The robot, so that the result can be replayed later (SimulationResult.replay).
    info["robot"] = {
        "name": plant.name,
        "urdf": str(plant.urdf_path),
        "locked_joints": dict(plant.locked_joints),
    }
    info["joint_kinds"] = list(plant.joint_kinds)  # units: rad, N m or m, N per joint
    if controller.diagnostic_units:
        info["diagnostic_units"] = dict(controller.diagnostic_units)
    return SimulationResult(
        **series,
        **common,
        duration=duration,
        sample_period=None if sample_period is None else float(sample_period),
        wall_time=time.perf_counter() - start,
        info=info,
    )


def _check_parts(plant: Any, controller: Any, trajectory: Any) -> None:
    """Typed errors naming the argument when a plant, controller or trajectory is of the wrong
    type or size (a box given as the controller, a 2-joint trajectory for a 6-joint arm)."""
    check_type("plant", plant, Robot, "a Robot (urpc.load_robot(...) or box.plant(robot, point))")
    check_type(
        "controller",
        controller,
        Controller,
        "a controller (urpc.synthesize(robot, box, epsilon=...) or another urpc.control.Controller)",
    )
    check_trajectory_dof(trajectory, plant.dof, f"the plant {plant.name!r}")
    if controller.dof is not None and controller.dof != plant.dof:
        raise InputError(
            f"controller {controller.name!r} was built for {controller.dof} joints, the plant "
            f"{plant.name!r} has {plant.dof}",
            field="controller",
        )


def describe_plant(plant: Robot) -> str:
    """``link: m = .. kg, com = (..) m, I_C diag = (..) kg m^2`` for each moving link."""
    parts = []
    for link in plant.links:
        if link.joint_index == 0:
            continue
        inertia = link.inertia
        com = ", ".join(f"{c:.6g}" for c in np.asarray(inertia.lever))
        diag = ", ".join(f"{c:.6g}" for c in np.diag(np.asarray(inertia.inertia)))
        parts.append(
            f"{link.name}: m = {inertia.mass:.6g} kg, com = ({com}) m, I_C diag = ({diag})"
        )
    return f"{plant.name}; " + "; ".join(parts)
