"""The simulator, against independent integrations of the textbook RR model.

References: ``conftest.rr_closed_form`` (no Pinocchio) integrated by scipy's DOP853 at tight
tolerances, period by period for zero-order-hold runs; the continuous run for sampled runs with a
tiny period; the run itself with halved tolerances or finer steps for convergence.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import rr_closed_form
from scipy.integrate import solve_ivp

from urpc.control.base import Controller, Reference
from urpc.control.synthesis import synthesize
from urpc.errors import InputError, SimulationError
from urpc.sim.metrics import METRIC_NAMES
from urpc.sim.options import SolverOptions
from urpc.sim.sampled import ball_samples
from urpc.sim.simulation import CONTINUOUS_METHOD, simulate

TRUE = dict(m2=10.0, lc2=0.525, I2=20 / 12)


class PaperTrajectory:
    """The paper's test trajectory (local to the tests)."""

    amplitude = np.array([np.pi / 4, -np.pi / 8])

    def reference(self, t: float) -> Reference:
        a, b = 0.5 * np.pi * t, np.pi * t
        s = math.sin(a) * math.sin(b)
        sd = 0.5 * np.pi * math.cos(a) * math.sin(b) + np.pi * math.sin(a) * math.cos(b)
        sdd = -1.25 * np.pi**2 * s + np.pi**2 * math.cos(a) * math.cos(b)
        return Reference(self.amplitude * s, self.amplitude * sd, self.amplitude * sdd)


def at(period, controller):
    """``controller`` set to run at ``period`` [s] (``None``: continuous time): a test law owns
    its period as a synthesized one does."""
    controller.sample_period = period
    return controller


class ConstantTorque(Controller):
    name = "constant"

    def __init__(self, torque):
        self.torque = np.asarray(torque, dtype=float)

    def output(self, t, q, qd, reference, state):
        return self.torque.copy()


class PDPlusGravity(Controller):
    """``u = Kp e + Kd ed + g_textbook(q)`` (nominal gravity), a simple state feedback."""

    name = "pd"
    epsilon = 0.05

    def output(self, t, q, qd, reference, state):
        g = rr_closed_form(q, qd, 5.0, 0.5, 5 / 12)[2]
        return 400.0 * (reference.q - q) + 40.0 * (reference.qd - qd) + g


class Unstable(Controller):
    """Positive position feedback: drives the arm away exponentially."""

    name = "unstable"
    epsilon = 0.01

    def output(self, t, q, qd, reference, state):
        return 1e5 * (q - reference.q) + 1e3 * qd


class NotANumber(Controller):
    name = "nan"
    epsilon = 0.01

    def output(self, t, q, qd, reference, state):
        return np.full(2, np.nan) if t > 0.05 else np.zeros(2)


def textbook_rhs(torque):
    def rhs(t, x):
        q, qd = x[:2], x[2:]
        M, C, g = rr_closed_form(q, qd, **TRUE)
        return np.concatenate((qd, np.linalg.solve(M, torque - C @ qd - g)))

    return rhs


@pytest.fixture(scope="module")
def true_plant(rr, rr_box, rr_true_point):
    return rr_box.plant(rr, rr_true_point)


# ----------------------------------------------------------------------------- plant dynamics
@pytest.mark.parametrize("sample_period", [None, 1e-2])
def test_open_loop_plant_follows_the_textbook_true_dynamics(true_plant, sample_period):
    """A constant torque: the simulated plant is the true RR arm (textbook formulas)."""
    torque = np.array([120.0, 30.0])
    x0 = np.array([0.1, -0.2, 0.0, 0.5])
    result = simulate(
        true_plant,
        at(sample_period, ConstantTorque(torque)),
        PaperTrajectory(),
        duration=1.0,
        q0=x0[:2],
        qd0=x0[2:],
        epsilon=1.0,
    )
    reference = solve_ivp(
        textbook_rhs(torque),
        (0, 1.0),
        x0,
        method="DOP853",
        t_eval=result.t,
        rtol=1e-12,
        atol=1e-12,
    )
    tolerance = 1e-6 if sample_period is None else 1e-9
    np.testing.assert_allclose(result.q, reference.y[:2].T, atol=tolerance)
    np.testing.assert_allclose(result.qd, reference.y[2:].T, atol=10 * tolerance)


@pytest.mark.parametrize(("delay", "limit"), [(0, None), (1, [150.0, 60.0]), (3, [150.0, 60.0])])
def test_zero_order_hold_feedback_and_disturbance_reach_the_plant(true_plant, delay, limit):
    """Sampled run: u is computed from the sampled state, clipped to the torque limit, held
    (``delay`` periods later, zero before: the actuation delay), and the plant sees it plus
    d_k (not delayed). Reference: the same loop written out, each period integrated by DOP853 on
    the textbook model."""
    period, duration = 5e-3, 0.3
    controller, trajectory = at(period, PDPlusGravity()), PaperTrajectory()
    result = simulate(
        true_plant,
        controller,
        trajectory,
        duration=duration,
        q0=[0.05, 0.0],
        qd0=[0.0, 0.0],
        disturbance_bound=10.0,
        seed=11,
        torque_limit=limit,
        actuation_delay=delay,
    )
    assert np.all(np.linalg.norm(result.disturbance, axis=1) <= 10.0)
    assert result.info["actuation_delay"] == delay
    if limit is not None:  # the limit acts, so the order clip-then-delay matters
        assert result.saturated_samples > 0
    bound = np.inf if limit is None else np.array(limit)
    x = np.array([0.05, 0.0, 0.0, 0.0])
    in_flight = [np.zeros(2)] * delay
    for k, t in enumerate(result.t):
        np.testing.assert_allclose(result.q[k], x[:2], atol=1e-9)
        np.testing.assert_allclose(result.qd[k], x[2:], atol=1e-8)
        u = controller.output(t, x[:2], x[2:], trajectory.reference(t), np.zeros(0))
        np.testing.assert_allclose(result.torque[k], u, rtol=1e-7, atol=1e-6)
        if k == len(result.t) - 1:
            break
        in_flight.append(np.clip(u, -bound, bound))
        step = solve_ivp(
            textbook_rhs(in_flight.pop(0) + result.disturbance[k]),
            (t, t + period),
            x,
            method="DOP853",
            rtol=1e-12,
            atol=1e-12,
        )
        x = step.y[:, -1]


def test_rk4_step_is_converged_at_the_default(rr, rr_box, true_plant):
    """Scenario 3 (1 kHz, disturbance): RK4 at 1e-4 s vs 1e-5 s steps agree to rounding."""
    controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    runs = [
        simulate(
            true_plant,
            controller,
            PaperTrajectory(),
            duration=0.3,
            q0=[0, 0],
            qd0=[0, 0],
            disturbance_bound=10.0,
            solver=SolverOptions(integration_step=step),
        )
        for step in (1e-4, 1e-5)
    ]
    assert runs[0].info["substeps"] == 10 and runs[1].info["substeps"] == 100
    np.testing.assert_allclose(runs[0].q, runs[1].q, atol=1e-12)
    np.testing.assert_allclose(runs[0].torque, runs[1].torque, rtol=1e-8, atol=1e-8)


def test_sampled_with_a_tiny_period_agrees_with_continuous(rr, rr_box, true_plant):
    controller = synthesize(rr, rr_box, 1e-2)
    held = synthesize(rr, rr_box, 1e-2, sample_period=1e-4, sampled_law="paper")
    trajectory = PaperTrajectory()
    continuous = simulate(true_plant, controller, trajectory, duration=1.0, q0=[0, 0], qd0=[0, 0])
    sampled = simulate(true_plant, held, trajectory, duration=1.0, q0=[0, 0], qd0=[0, 0])
    assert len(sampled.t) == 10001 and len(continuous.t) == 1001
    every = sampled.t[::10]
    np.testing.assert_allclose(every, continuous.t, atol=1e-12)
    # Errors are ~1e-2 rad; the zero-order hold at 10 kHz shifts them by ~1e-5 rad.
    np.testing.assert_allclose(sampled.q[::10], continuous.q, atol=2e-5)
    np.testing.assert_allclose(sampled.torque[::10], continuous.torque, atol=1.0)
    assert sampled.metrics["phi"] == pytest.approx(continuous.metrics["phi"], rel=0.01)


def test_continuous_tolerances_are_converged(rr, rr_box, true_plant):
    """Halving rtol and atol changes no reported metric of scenario 1 by 1 % or more."""
    controller = synthesize(rr, rr_box, 1e-3)
    runs = [
        simulate(
            true_plant,
            controller,
            PaperTrajectory(),
            duration=4.0,
            q0=[0, 0],
            qd0=[0, 0],
            solver=SolverOptions(rtol=rtol, atol=atol),
        )
        for rtol, atol in ((1e-8, 1e-10), (5e-9, 5e-11))
    ]
    assert runs[0].info["rtol"] == 1e-8 and runs[0].info["integrator"] == CONTINUOUS_METHOD
    assert runs[0].metrics["met"]  # entry_time and the after-entry error are compared too
    for name in METRIC_NAMES:
        if name in ("step_time_median", "wall_time"):
            continue
        default, halved = runs[0].metrics[name], runs[1].metrics[name]
        if isinstance(default, float):
            assert halved == pytest.approx(default, rel=0.01), name
        else:
            assert halved == default, name


# ----------------------------------------------------------------------------- features
def test_torque_limit_clips_the_command_and_counts_saturation(true_plant):
    kwargs = dict(duration=0.2, q0=[0, 0], qd0=[0, 0], epsilon=1.0)
    limited = simulate(
        true_plant,
        at(1e-3, ConstantTorque([300.0, -5.0])),
        PaperTrajectory(),
        torque_limit=[150.0, 50],
        **kwargs,
    )
    clipped = simulate(
        true_plant, at(1e-3, ConstantTorque([150.0, -5.0])), PaperTrajectory(), **kwargs
    )
    np.testing.assert_allclose(limited.q, clipped.q, atol=1e-14)
    assert limited.saturated_samples == len(limited.t)
    assert clipped.saturated_samples == 0
    assert limited.torque[0, 0] == 300.0  # the recorded torque is the command
    assert limited.torque_limit == (150.0, 50.0)


def test_disturbance_is_uniform_in_the_ball_and_seeded():
    rng = np.random.default_rng(0)
    for dimension in (2, 3):
        points = ball_samples(40000, dimension, 10.0, rng)
        norms = np.linalg.norm(points, axis=1)
        assert norms.max() <= 10.0
        # Uniform in the ball: P(||d|| <= R/2) = 2^-n; the mean is the origin.
        assert np.mean(norms <= 5.0) == pytest.approx(0.5**dimension, abs=0.01)
        assert np.all(np.abs(points.mean(axis=0)) < 0.1)
    same = [ball_samples(5, 2, 1.0, np.random.default_rng(3)) for _ in range(2)]
    np.testing.assert_array_equal(same[0], same[1])
    assert not np.array_equal(same[0], ball_samples(5, 2, 1.0, np.random.default_rng(4)))
    assert not ball_samples(4, 2, 0.0, rng).any()


def test_runs_are_reproducible_and_the_controller_reusable(rr, rr_box, true_plant):
    controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    kwargs = dict(duration=0.2, q0=[0, 0], qd0=[0, 0], disturbance_bound=10.0)
    first = simulate(true_plant, controller, PaperTrajectory(), seed=5, **kwargs)
    again = simulate(true_plant, controller, PaperTrajectory(), seed=5, **kwargs)
    other = simulate(true_plant, controller, PaperTrajectory(), seed=6, **kwargs)
    for name in ("q", "qd", "torque", "disturbance"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
    for name in ("phi", "kappa"):
        np.testing.assert_array_equal(first.diagnostics[name], again.diagnostics[name])
    assert not np.array_equal(first.disturbance, other.disturbance)
    assert first.seed == 5 and first.controller == "interval" and first.epsilon == 1e-2
    assert first.step_time_median > 0 and first.wall_time > first.step_time_median
    assert "link2: m = 10 kg" in first.plant


@pytest.mark.parametrize("sample_period", [None, 1e-3])
def test_divergence_raises_naming_time_and_state(true_plant, sample_period):
    with pytest.raises(SimulationError, match=r"diverged at t = .* s .*q = .* rad, qd = "):
        simulate(
            true_plant,
            at(sample_period, Unstable()),
            PaperTrajectory(),
            duration=5.0,
            q0=[0.01, 0],
            qd0=[0, 0],
        )
    with pytest.raises(SimulationError, match="non-finite"):
        simulate(
            true_plant,
            at(sample_period, NotANumber()),
            PaperTrajectory(),
            duration=0.2,
            q0=[0, 0],
            qd0=[0, 0],
        )


def test_progress_reporting(true_plant, capsys):
    fractions = []
    simulate(
        true_plant,
        at(1e-3, ConstantTorque([0, 0])),
        PaperTrajectory(),
        duration=0.1,
        epsilon=1.0,
        progress=fractions.append,
    )
    assert fractions[-1] == 1.0 and np.all(np.diff(fractions) > 0)

    class Bar:
        total, n = None, 0.0

        def update(self, amount):
            self.n += amount

    bar = Bar()
    simulate(
        true_plant,
        ConstantTorque([0, 0]),
        PaperTrajectory(),
        duration=0.1,
        epsilon=1.0,
        progress=bar,
    )
    assert bar.total == 100 and bar.n == pytest.approx(100)

    simulate(
        true_plant,
        at(1e-3, ConstantTorque([0, 0])),
        PaperTrajectory(),
        duration=0.01,
        epsilon=1.0,
        progress=True,
    )
    assert "simulate" in capsys.readouterr().err  # a tqdm bar on stderr


def test_invalid_arguments_name_the_field(true_plant):
    controller, trajectory = ConstantTorque([0, 0]), PaperTrajectory()
    cases = [
        (None, dict(duration=1.0, disturbance_bound=10.0), "disturbance_bound"),
        (2.0, dict(duration=1.0), "sample_period"),  # the controller's period is too long
        (None, dict(duration=0.0), "duration"),
        (None, dict(duration=1.0, q0=[0, 0, 0]), "q0"),
        (None, dict(duration=1.0, torque_limit=0.0), "torque_limit"),
        (1e-3, dict(duration=1.0, plant_backend="bullet"), "plant"),
        (None, dict(duration=1.0, plant_backend="mujoco"), "plant"),  # continuous time
        (None, dict(duration=1.0, controller_state0=[1.0]), "controller_state0"),  # static law
    ]
    for period, kwargs, field in cases:
        with pytest.raises(InputError) as info:
            simulate(true_plant, at(period, controller), trajectory, epsilon=1.0, **kwargs)
        assert info.value.field == field, kwargs
    with pytest.raises(InputError) as info:  # an unknown solver, refused where it is made
        SolverOptions(method="Euler")
    assert info.value.field == "method" and "valid: RK45" in str(info.value)
    with pytest.raises(TypeError, match="sample_period"):  # the period is the controller's alone
        simulate(true_plant, at(None, controller), trajectory, epsilon=1.0, duration=1.0,
                 sample_period=1e-3)  # fmt: skip
    controller.sample_period = None
    with pytest.raises(InputError) as info:  # no epsilon to judge the run against
        simulate(true_plant, controller, trajectory, duration=1.0)
    assert info.value.field == "epsilon"


# ----------------------------------------------------------------------------- backends, state
def test_mujoco_backend_runs_the_same_sampled_loop(true_plant):
    """The independent MuJoCo plant under the same zero-order-hold loop (PD plus gravity, 5 ms,
    disturbance) follows the Pinocchio plant to rounding; both follow the textbook model."""
    pytest.importorskip("mujoco")
    kwargs = dict(
        duration=0.3,
        q0=[0.05, 0.0],
        qd0=[0.0, 0.0],
        disturbance_bound=10.0,
        seed=2,
    )
    runs = {
        backend: simulate(
            true_plant,
            at(5e-3, PDPlusGravity()),
            PaperTrajectory(),
            plant_backend=backend,
            **kwargs,
        )
        for backend in ("pinocchio", "mujoco")
    }
    assert (
        runs["mujoco"].info["plant"] == "mujoco" and runs["pinocchio"].info["plant"] == "pinocchio"
    )
    np.testing.assert_allclose(runs["mujoco"].q, runs["pinocchio"].q, atol=1e-10)
    np.testing.assert_allclose(runs["mujoco"].torque, runs["pinocchio"].torque, atol=1e-6)
    # and the textbook model, one period integrated by DOP853 under the recorded torque
    k, t = 10, runs["mujoco"].t[10]
    x = np.concatenate((runs["mujoco"].q[k], runs["mujoco"].qd[k]))
    u = runs["mujoco"].torque[k] + runs["mujoco"].disturbance[k]
    step = solve_ivp(textbook_rhs(u), (t, t + 5e-3), x, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(runs["mujoco"].q[k + 1], step.y[:2, -1], atol=1e-9)


class Shifted:
    """A trajectory delayed by ``offset`` [s]: ``reference(t) = trajectory.reference(t + offset)``."""

    def __init__(self, trajectory, offset: float):
        self.trajectory, self.offset = trajectory, offset

    def reference(self, t: float) -> Reference:
        return self.trajectory.reference(t + self.offset)


def test_controller_state0_continues_a_run(rr, rr_box, true_plant):
    """A 0.4 s run equals a 0.2 s run continued from its final plant and controller state."""
    controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    trajectory = PaperTrajectory()
    kwargs = {}
    whole = simulate(
        true_plant, controller, trajectory, duration=0.4, q0=[0.02, -0.02], qd0=[0, 0], **kwargs
    )
    first = simulate(
        true_plant, controller, trajectory, duration=0.2, q0=[0.02, -0.02], qd0=[0, 0], **kwargs
    )
    state = first.info["controller_state_final"]
    assert state[0] > 0  # the dead-zone integral has grown: ||e|| = 0.028 > epsilon at first
    continued = simulate(
        true_plant,
        controller,
        Shifted(trajectory, 0.2),
        duration=0.2,
        q0=first.q[-1],
        qd0=first.qd[-1],
        controller_state0=state,
        **kwargs,
    )
    np.testing.assert_allclose(continued.q, whole.q[200:], atol=1e-9)
    np.testing.assert_allclose(continued.torque, whole.torque[200:], rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(
        continued.diagnostics["phi"], whole.diagnostics["phi"][200:], rtol=1e-12
    )
    restarted = simulate(
        true_plant,
        controller,
        Shifted(trajectory, 0.2),
        duration=0.2,
        q0=first.q[-1],
        qd0=first.qd[-1],
        **kwargs,
    )
    assert restarted.diagnostics["phi"][0] == controller.phi_P < continued.diagnostics["phi"][0]


def test_the_lightest_disturbance_pushes_at_its_bound_along_the_laws_lightest_mode():
    """``disturbance="lightest"``: at every sample ``d_k`` has the norm of the bound and is an
    eigenvector of the law's ``M_L(q_k)`` for its least eigenvalue (``M_L d = lambda_min d``),
    and it keeps its direction from sample to sample (``d_k . d_(k-1) > 0``)."""
    import urpc

    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    result = simulate(
        box.plant(), controller, PaperTrajectory(), duration=0.5, disturbance_bound=3.0,
        disturbance="lightest",
    )  # fmt: skip
    pushes = result.disturbance[:-1]
    assert np.allclose(np.linalg.norm(pushes, axis=1), 3.0, rtol=1e-12)
    for q, push in zip(result.q[:-1], pushes, strict=True):
        lower = controller.inertia_bounds.lower(q)
        least = np.linalg.eigvalsh(lower)[0]
        assert np.allclose(lower @ push, least * push, atol=1e-9 * np.abs(lower).max() * 3.0)
    assert np.all(np.sum(pushes[1:] * pushes[:-1], axis=1) > 0)
