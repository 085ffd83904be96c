"""The continuous-time closed loop: the plant state and the controller's internal state as one ODE,
integrated by :func:`scipy.integrate.solve_ivp` and recorded on a fixed output grid."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from ..errors import InputError
from ..model.joint_dynamics import friction_torque
from .closed_loop import RunSetup, diverged

#: Default continuous-time integrator and tolerances, chosen by measurement on the paper's
#: scenario 1 (10 s): the interval law (Kr = 95/s, phi up to ~1.5e3) is stiff-ish, and the r-alpha
#: law (a near-discontinuous ``s / (||s|| + eta)``) is very stiff. Radau handles both (~5 s each);
#: RK45/DOP853 take ~4x longer on the interval law, LSODA fails or crawls (minutes) on r-alpha and
#: BDF is erratic on it. Halving both tolerances changes every reported metric by less than 1 %
#: (interval law: < 1e-5 relative; r-alpha: torque_variation 0.9 %, others < 1e-3).
CONTINUOUS_METHOD = "Radau"
CONTINUOUS_RTOL = 1e-8
CONTINUOUS_ATOL = 1e-10


def run_continuous(
    setup: RunSetup, method: str, rtol: float, atol: float, output_rate: float
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The series (keyword arguments of :class:`~urpc.sim.results.SimulationResult`) and the
    ``info`` of a continuous-time run recorded at ``output_rate`` [Hz]."""
    plant, controller, trajectory = setup.plant, setup.controller, setup.trajectory
    duration, limit, max_state, bar = setup.duration, setup.limit, setup.max_state, setup.bar
    n = plant.dof
    model, data = plant.model, plant.model.createData()
    aba = pin.aba
    configuration = (lambda q: q) if model.nq == model.nv else plant.configuration
    friction = plant.has_joint_friction
    damping, coulomb = np.asarray(model.damping), np.asarray(model.friction)
    step_times: list[float] = []
    clock = time.perf_counter
    furthest = [0.0]

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(x)  # implicit methods pass strided Jacobian columns
        q, qd, state = x[:n], x[n : 2 * n], x[2 * n :]
        if not np.isfinite(x).all():
            raise Diverged(t, x, "non-finite state")
        reference = trajectory.reference(t)
        tic = clock()
        u = controller.output(t, q, qd, reference, state)
        state_rate = controller.state_derivative(t, q, qd, reference, state)
        step_times.append(clock() - tic)
        if not np.isfinite(u).all():  # before the limit, which would clip an inf
            raise Diverged(t, x, "the controller output a non-finite torque")
        if limit is not None:
            u = np.clip(u, -limit, limit)
        if t > furthest[0] + 0.005 * duration:
            furthest[0] = t
            bar.update(t / duration)
        if friction:  # the joints' damping and regularized Coulomb friction (stiff: Radau)
            u = u - friction_torque(damping, coulomb, qd)
        return np.concatenate((qd, aba(model, data, configuration(q), qd, u), state_rate))

    def runaway(t: float, x: np.ndarray) -> float:
        return max_state - np.abs(x[: 2 * n]).max()

    runaway.terminal = True
    samples = max(2, int(round(duration * output_rate)) + 1)
    grid = np.linspace(0.0, duration, samples)
    x0 = np.concatenate((setup.q0, setup.qd0, setup.state0))
    try:
        solution = solve_ivp(
            rhs,
            (0.0, duration),
            x0,
            method=method,
            t_eval=grid,
            rtol=rtol,
            atol=atol,
            events=runaway,
        )
    except Diverged as exc:
        diverged(exc.t, exc.x[:n], exc.x[n : 2 * n], exc.reason)
    except ValueError as exc:  # an unknown method or bad tolerances
        raise InputError(str(exc), field="method") from None
    if solution.status == 1:
        x = solution.y_events[0][0]
        diverged(solution.t_events[0][0], x[:n], x[n : 2 * n], f"|q| or |qd| above {max_state:g}")
    if solution.status != 0:
        x = solution.y[:, -1] if solution.y.size else x0
        t = solution.t[-1] if solution.t.size else 0.0
        diverged(t, x[:n], x[n : 2 * n], f"the integrator failed: {solution.message}")
    bar.update(1.0)

    q, qd, states = solution.y[:n].T, solution.y[n : 2 * n].T, solution.y[2 * n :].T
    qdes, qddes = np.empty((samples, n)), np.empty((samples, n))
    torque = np.empty((samples, n))
    names = tuple(controller.diagnostic_units)
    logged = np.full((samples, len(names)), np.nan)
    for k, t in enumerate(solution.t):
        reference = trajectory.reference(t)
        qdes[k], qddes[k] = reference.q, reference.qd
        torque[k] = controller.output(t, q[k], qd[k], reference, states[k])
        if not np.isfinite(torque[k]).all():  # re-evaluated on the output grid: check again
            diverged(t, q[k], qd[k], "the controller output a non-finite torque")
        if names:
            named = controller.diagnostics(states[k])
            logged[k] = [named.get(name, np.nan) for name in names]
    saturated = (
        np.zeros(samples, dtype=bool) if limit is None else np.any(np.abs(torque) > limit, axis=1)
    )
    series = dict(
        t=solution.t,
        q=q,
        qd=qd,
        q_desired=qdes,
        qd_desired=qddes,
        torque=torque,
        disturbance=np.zeros((samples, n)),
        diagnostics={name: logged[:, i] for i, name in enumerate(names)},
        saturated=saturated,
        step_time_median=float(np.median(step_times)),
    )
    info = {
        "plant": "pinocchio",
        "integrator": method,
        "rtol": rtol,
        "atol": atol,
        "output_rate": output_rate,
        "rhs_evaluations": int(solution.nfev),
        "controller_state_final": states[-1].tolist(),
    }
    return series, info


class Diverged(Exception):
    def __init__(self, t: float, x: np.ndarray, reason: str):
        self.t, self.x, self.reason = t, x, reason
