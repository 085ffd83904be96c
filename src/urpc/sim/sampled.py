"""The sampled closed loop: the controller's output held (zero-order hold) over each period with a
disturbance (drawn in a ball, or of constant magnitude against the sliding variable ``r``), the
plant integrated by RK4 over the period.

With an actuation delay of ``d`` samples the torque computed from the sample at ``t_k`` (clipped
to the torque limit, as a robot's safety layer clips it before sending) is held over
``[t_{k+d}, t_{k+d+1})`` instead; over the first ``d`` periods the plant holds a zero torque (no
command has arrived yet, as on :class:`urpc.robot.virtual.VirtualArm` and in the delayed law's
``u_{-1} = 0``). The disturbance ``d_k`` is the plant's own and is not delayed.
"""

from __future__ import annotations

import math
import time
from collections import deque
from typing import Any

import numpy as np

from ..errors import SimulationError
from ..names import DISTURBANCE_MODELS
from .closed_loop import RunSetup, diverged
from .plants import Plant

#: The disturbance models of a sampled run: ``ball`` draws ``d_k`` uniformly in ``||d|| <= D``
#: (seeded); ``against`` holds ``d_k = -D r_k / ||r_k||``, magnitude ``D`` against the sliding
#: variable ``r = (qd_d - qd) + Kr (q_d - q)`` of the sample (``0`` where ``r = 0``); ``worst``
#: holds ``d_k = -D M^-1 r_k / ||M^-1 r_k||`` with the plant's ``M(q_k)``: at its bound, against
#: ``r`` in the ``M^-1`` metric (the direction that grows ``||r||`` fastest, the certificate's
#: worst case); ``lightest`` holds ``d_k = D v_k`` with ``v_k`` the unit eigenvector of the
#: lightest mode of the law's inertia model ``M_L(q_k)`` (the plant's ``M(q_k)`` for a law
#: without one), its sign kept from sample to sample: a constant push at the bound along the
#: mode through which the loop rejects a disturbance worst (its steady state is the leading term
#: of the certificate's disturbance response, ``T D / lambda_min(M_L)``; ``worst`` and
#: ``against`` vanish where ``r = 0``, on a reference the arm follows exactly).
DISTURBANCES = DISTURBANCE_MODELS


def run_sampled(
    setup: RunSetup,
    stepper: Plant,
    disturbance_bound: float,
    seed: int,
    disturbance_model: str = "ball",
    delay: int = 0,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The series (keyword arguments of :class:`~urpc.sim.results.SimulationResult`) and the
    ``info`` of a run sampled at the controller's own period (``controller.sample_period`` [s])
    on ``stepper``, with the disturbance ``disturbance_model`` (one of :data:`DISTURBANCES`) of
    magnitude ``disturbance_bound`` [N m] and an actuation delay of ``delay`` samples (an
    integer >= 0, checked by the caller; module docstring). The ``torque`` series is the
    command at each sample, before the limit and the delay."""
    controller, trajectory = setup.controller, setup.trajectory
    period = controller.sample_period
    q, qd, limit, bar = setup.q0, setup.qd0, setup.limit, setup.bar
    n = stepper.dof
    n_periods = max(1, math.ceil(setup.duration / period - 1e-9))
    samples = n_periods + 1
    against = disturbance_model in ("against", "worst") and disturbance_bound > 0
    worst = disturbance_model == "worst"
    if disturbance_model == "ball":
        disturbance = ball_samples(samples, n, disturbance_bound, np.random.default_rng(seed))
    elif disturbance_model in ("against", "worst"):
        disturbance = np.zeros((samples, n))  # filled sample by sample
        Kr = np.broadcast_to(np.asarray(controller.Kr, dtype=float), (n,))
    elif disturbance_model == "lightest":
        disturbance = np.zeros((samples, n))  # filled sample by sample
        bounds = getattr(controller, "inertia_bounds", None)
        model = setup.plant.M if bounds is None else bounds.lower
        lightest = LightestMode(model, disturbance_bound)
    else:
        raise ValueError(f"unknown disturbance model {disturbance_model!r}; valid: {DISTURBANCES}")
    stepper.reset(q, qd)

    rate = 1.0 / period
    if abs(rate - round(rate)) < 1e-9 * rate:  # k / rate is the exact decimal time: 0.0411 s
        t_series = np.arange(samples) / round(rate)
    else:
        t_series = np.arange(samples) * period
    q_series, qd_series = np.empty((samples, n)), np.empty((samples, n))
    qdes_series, qddes_series = np.empty((samples, n)), np.empty((samples, n))
    torque = np.empty((samples, n))
    names = tuple(controller.diagnostic_units)
    logged = np.full((samples, len(names)), np.nan)
    saturated = np.zeros(samples, dtype=bool)
    step_times = np.empty(samples)
    state = setup.state0
    logged_of, values = None, np.full(len(names), np.nan)
    report_every = max(1, samples // 200)
    bound = setup.max_state**2
    clock = time.perf_counter
    in_flight = deque(np.zeros(n) for _ in range(delay))  # sent, not yet acting: oldest first
    for k in range(samples):
        t = t_series[k]
        reference = trajectory.reference(t)
        tic = clock()
        u = controller.output(t, q, qd, reference, state)
        next_state = controller.advance(t, q, qd, reference, state)
        step_times[k] = clock() - tic
        # Before the torque limit (which would clip an inf to the limit) and at every sample,
        # the last one included: a controller never hands out a non-finite torque silently.
        if not u @ u < math.inf:  # NaN, inf, or so large that its square overflows
            diverged(t, q, qd, "the controller output a non-finite or overflowing torque")
        q_series[k], qd_series[k] = q, qd
        qdes_series[k], qddes_series[k] = reference.q, reference.qd
        torque[k] = u
        if disturbance_model == "lightest":
            disturbance[k] = lightest(q)
        elif against:
            disturbance[k] = against_r(
                reference.q - q, reference.qd - qd, Kr, disturbance_bound,
                setup.plant.M(q) if worst else None,
            )  # fmt: skip
        if names:
            if state is not logged_of:  # advance() returns the same array while nothing changes
                named = controller.diagnostics(state)
                logged_of, values = state, [named.get(name, np.nan) for name in names]
            logged[k] = values
        if k == n_periods:
            break
        if limit is not None:
            clipped = np.clip(u, -limit, limit)
            saturated[k] = np.any(clipped != u)
            u = clipped
        if delay:
            in_flight.append(np.array(u))
            u = in_flight.popleft()
        try:
            q, qd = stepper.step(u + disturbance[k], period)
        except SimulationError:
            diverged(t, q, qd, "the state became non-finite during the following period")
        # One dot product catches runaway (and NaN, should the plant let one through).
        if not q @ q + qd @ qd <= bound:
            diverged(t + period, q, qd, f"non-finite or ||(q, qd)|| above {setup.max_state:g}")
        state = next_state
        if k % report_every == 0:
            bar.update((k + 1) / samples)
    if limit is not None:
        saturated[-1] = np.any(np.abs(torque[-1]) > limit)
    bar.update(1.0)
    series = dict(
        t=t_series,
        q=q_series,
        qd=qd_series,
        q_desired=qdes_series,
        qd_desired=qddes_series,
        torque=torque,
        disturbance=disturbance,
        diagnostics={name: logged[:, i] for i, name in enumerate(names)},
        saturated=saturated,
        step_time_median=float(np.median(step_times)),
    )
    substeps = max(1, math.ceil(period / stepper.max_step - 1e-9))
    info = {
        "plant": stepper.kind,
        "integrator": "rk4",
        "integration_step": period / substeps,
        "substeps": substeps,
        "controller_state_final": np.asarray(state, dtype=float).tolist(),
    }
    if disturbance_model != "ball":
        info["disturbance_model"] = disturbance_model
    return series, info


def against_r(
    e: np.ndarray, ed: np.ndarray, Kr: np.ndarray, magnitude: float, inertia=None
) -> np.ndarray:
    """``-magnitude r / ||r||`` with ``r = ed + Kr e`` [N m]: the constant-magnitude disturbance
    pushing against the sliding variable (zero where ``r = 0``); with the plant's ``inertia``,
    ``-magnitude M^-1 r / ||M^-1 r||`` (against ``r`` in the ``M^-1`` metric)."""
    r = ed + Kr * e
    if inertia is not None:
        r = np.linalg.solve(inertia, r)
    norm = math.sqrt(r @ r)
    if norm == 0.0:
        return np.zeros_like(r)
    return r * (-magnitude / norm)


class LightestMode:
    """``magnitude v(q)`` [N m], ``v`` the unit eigenvector of the least eigenvalue of
    ``inertia(q)``, its sign chosen to keep ``v . v_previous >= 0`` (a push that holds its
    direction as the arm moves; the first points along the positive sum of ``v``'s entries)."""

    def __init__(self, inertia, magnitude: float):
        self.inertia, self.magnitude = inertia, float(magnitude)
        self.previous: np.ndarray | None = None

    def __call__(self, q: np.ndarray) -> np.ndarray:
        v = np.linalg.eigh(self.inertia(q))[1][:, 0]
        reference = self.previous if self.previous is not None else np.ones_like(v)
        if v @ reference < 0:
            v = -v
        self.previous = v
        return self.magnitude * v


def ball_samples(count: int, dimension: int, radius: float, rng: np.random.Generator) -> np.ndarray:
    """``count`` points drawn uniformly in the ball ``||d|| <= radius`` of ``R^dimension``:
    a normalized Gaussian direction times ``radius * U^(1/dimension)``."""
    if radius == 0:
        return np.zeros((count, dimension))
    directions = rng.standard_normal((count, dimension))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = radius * rng.random(count) ** (1.0 / dimension)
    return directions * radii[:, None]
