"""The interval passivity controller and its synthesis, against independent references.

References: the textbook RR model (``conftest.rr_closed_form``, no Pinocchio), sampled parameter
points of the Table I box, the closed-loop ``r`` dynamics ``M rdot + C r = v + w`` of the paper's
eq. (5) (with exact parameters ``w = 0``, so ``r = 0`` is invariant and ``e`` decays as
``exp(-Kr t)``), the Lyapunov function ``V = r^T M r / 2`` of Theorem 1, and the paper's
scenarios 1 and 3.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import rr_closed_form

from urpc.bounds import default_method, make_bound
from urpc.control.base import Reference
from urpc.control.synthesis import synthesize
from urpc.errors import InputError
from urpc.sim.options import SolverOptions
from urpc.sim.simulation import simulate

NOMINAL = dict(m2=5.0, lc2=0.5, I2=5 / 12)
TRUE = dict(m2=10.0, lc2=0.525, I2=20 / 12)


class PaperTrajectory:
    """``q_d(t) = (pi/4, -pi/8) sin(pi t/2) sin(pi t)`` with analytic derivatives (local to the
    tests, independent of ``urpc.trajectories``)."""

    amplitude = np.array([np.pi / 4, -np.pi / 8])

    def reference(self, t: float) -> Reference:
        a, b = 0.5 * np.pi * t, np.pi * t
        s = math.sin(a) * math.sin(b)
        sd = 0.5 * np.pi * math.cos(a) * math.sin(b) + np.pi * math.sin(a) * math.cos(b)
        sdd = -1.25 * np.pi**2 * s + np.pi**2 * math.cos(a) * math.cos(b)
        return Reference(self.amplitude * s, self.amplitude * sd, self.amplitude * sdd)


@pytest.fixture(scope="module")
def nominal_plant(rr, rr_box):
    return rr_box.plant(rr)


@pytest.fixture(scope="module")
def true_plant(rr, rr_box, rr_true_point):
    return rr_box.plant(rr, rr_true_point)


def _random_state(rng):
    q, qd = rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3, 3, 2)
    ref = Reference(rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3, 3, 2), rng.uniform(-20, 20, 2))
    return q, qd, ref


def _closed_loop_terms(controller, q, qd, ref):
    Kr = controller.Kr
    e, ed = ref.q - q, ref.qd - qd
    return ref.qd + Kr * e, ref.qdd + Kr * ed, ed + Kr * e


# ----------------------------------------------------------------------------- the law itself
def test_output_is_the_paper_law_on_the_textbook_model(rr, rr_box):
    """u = M0 qdd_a + C0 qd_a + g0 + (kappa ||rho|| + phi) r, with M0, C0, g0 from the textbook
    formulas and rho from the bound's own per-joint enclosure."""
    controller = synthesize(rr, rr_box, 1e-3)
    rng = np.random.default_rng(1)
    for _ in range(20):
        q, qd, ref = _random_state(rng)
        state = np.array([rng.uniform(0, 1e-3)])
        qd_a, qdd_a, r = _closed_loop_terms(controller, q, qd, ref)
        M0, C0, g0 = rr_closed_form(q, qd, **NOMINAL)
        rho = controller.bound.rho(q, qd, qd_a, qdd_a)
        phi = 1.0 + 1e6 * state[0]
        kappa = 2.0 + 1.0 * state[0]
        expected = M0 @ qdd_a + C0 @ qd_a + g0 + (kappa * np.linalg.norm(rho) + phi) * r
        u = controller.output(0.0, q, qd, ref, state)
        np.testing.assert_allclose(u, expected, rtol=1e-9, atol=1e-9)
        assert controller.last_rho_norm == pytest.approx(np.linalg.norm(rho), rel=1e-12)
        assert controller.diagnostics(state) == pytest.approx({"phi": phi, "kappa": kappa})


def test_rho_dominates_the_mismatch_at_sampled_plants(rr, rr_box):
    """Lemma 1: |w_i| <= rho_i for parameter points of the Table I box (vertices and random),
    with w from the textbook model (d = 0, Theorem 2)."""
    controller = synthesize(rr, rr_box, 1e-3)
    rng = np.random.default_rng(2)
    points = [(m, c, i) for m in (5, 10) for c in (0.5, 0.525) for i in (5 / 12, 20 / 12)]
    points += [
        (rng.uniform(5, 10), rng.uniform(0.5, 0.525), rng.uniform(5 / 12, 20 / 12))
        for _ in range(30)
    ]
    for _ in range(20):
        q, qd, ref = _random_state(rng)
        qd_a, qdd_a, _ = _closed_loop_terms(controller, q, qd, ref)
        controller.output(0.0, q, qd, ref, np.zeros(1))
        rho = controller.bound.rho(q, qd, qd_a, qdd_a)
        M0, C0, g0 = rr_closed_form(q, qd, **NOMINAL)
        nominal = M0 @ qdd_a + C0 @ qd_a + g0
        worst = np.zeros(2)
        for m2, lc2, I2 in points:
            M, C, g = rr_closed_form(q, qd, m2, lc2, I2)
            worst = np.maximum(worst, np.abs(M @ qdd_a + C @ qd_a + g - nominal))
        assert np.all(worst <= rho * (1 + 1e-9) + 1e-9)
        assert controller.last_rho_norm >= np.linalg.norm(worst) * (1 - 1e-12)


@pytest.mark.parametrize("method", ["hull", "vertex", "rigorous"])
def test_the_law_step_gives_pinocchios_nominal_torque_and_the_bounds_enclosure(rr, rr_box, method):
    """``torque_and_enclosure`` (the law's one call per step) against independent references: the
    nominal torque is Pinocchio's ``M0 qdd_a + C0 qd_a + g0`` whether the method has a regressor
    or not, and the enclosure is the method's own :meth:`enclose` at the same state."""
    bound = make_bound(method, rr, rr_box)
    nominal_robot = rr_box.nominal_robot(rr)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd = rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)
        qd_a, qdd_a = rng.uniform(-3, 3, 2), rng.uniform(-10, 10, 2)
        tau0, lower, upper = bound.torque_and_enclosure(q, qd, qd_a, qdd_a)
        expected = nominal_robot.M(q) @ qdd_a + nominal_robot.C(q, qd) @ qd_a + nominal_robot.g(q)
        np.testing.assert_allclose(tau0, expected, rtol=1e-10, atol=1e-9)
        own_lower, own_upper = bound.enclose(q, qd, qd_a, qdd_a)
        np.testing.assert_allclose(lower, own_lower, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(upper, own_upper, rtol=1e-12, atol=1e-12)


def test_dead_zone_integral_and_theorem_selection(rr, rr_box):
    adaptive = synthesize(rr, rr_box, 1e-2)
    assert adaptive.adaptive and adaptive.n_states == 1
    q = np.zeros(2)
    ref = Reference(np.array([0.006, -0.008]), np.zeros(2), np.zeros(2))  # ||e|| = 0.01 = epsilon
    inside = Reference(np.array([0.006, -0.0079]), np.zeros(2), np.zeros(2))
    assert adaptive.state_derivative(0, q, q, ref, np.zeros(1))[0] == pytest.approx(0.01)
    assert adaptive.state_derivative(0, q, q, inside, np.zeros(1))[0] == 0.0
    held = synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    advanced = held.advance(0, q, q, ref, np.array([0.5]))  # one period T = 1e-3 s
    assert advanced[0] == pytest.approx(0.5 + 1e-5)
    assert held.advance(0, q, q, inside, np.array([0.5]))[0] == 0.5

    known = synthesize(rr, dataclasses.replace(rr_box, disturbance_bound=10.0), 1e-2)
    assert not known.adaptive and known.n_states == 0
    assert known.diagnostics(known.initial_state()) == {"phi": 1.0, "kappa": 2.0}
    assert known.state_derivative(0, q, q, ref, known.initial_state()).shape == (0,)
    # Theorem 1 includes the known disturbance in the enclosure: rho grows by ~beta_d per joint.
    rng = np.random.default_rng(4)
    q, qd, r = _random_state(rng)
    known.output(0, q, qd, r, np.zeros(0))
    adaptive.output(0, q, qd, r, np.zeros(1))
    assert known.last_rho_norm > adaptive.last_rho_norm


def test_synthesis_defaults_and_validation(rr, rr_box):
    controller = synthesize(rr, rr_box, 1e-3)
    np.testing.assert_allclose(controller.Kr, 3 / math.sqrt(1e-3) * np.ones(2))
    assert (controller.kappa_P, controller.kappa_I, controller.phi_P, controller.phi_I) == (
        2.0,
        1.0,
        1.0,
        1e6,
    )
    assert controller.name == "interval"
    assert controller.method == default_method(rr_box)
    np.testing.assert_allclose(synthesize(rr, rr_box, 1e-3, Kr=[4, 5]).Kr, [4, 5])
    np.testing.assert_allclose(synthesize(rr, rr_box, 1e-3, Kr=np.diag([4, 5])).Kr, [4, 5])
    bad = [
        (dict(epsilon=0.0), "epsilon"),
        (dict(epsilon=float("nan")), "epsilon"),
        (dict(kappa_P=0.5), "kappa_P"),
        (dict(phi_P=0.9), "phi_P"),
        (dict(kappa_I=0.0), "kappa_I"),
        (dict(phi_I=-1.0), "phi_I"),
        (dict(Kr=[1, 2, 3]), "Kr"),
        (dict(Kr=[1, -2]), "Kr"),
        (dict(Kr=[[1, 1], [0, 1]]), "Kr"),
        (dict(method="nonsense"), "method"),
    ]
    for kwargs, field in bad:
        arguments = {"epsilon": 1e-3, **kwargs}
        with pytest.raises(InputError) as info:
            synthesize(rr, rr_box, **arguments)
        assert info.value.field == field, kwargs


# ----------------------------------------------------------------------------- closed loop
def test_exact_model_keeps_r_zero_and_error_decays_exponentially(rr, rr_box, nominal_plant):
    """Exact parameters, no disturbance: w = 0, so r(0) = 0 gives r = 0 for all t and each error
    component follows ed = -Kr e, i.e. e(t) = e(0) exp(-Kr t) (closed form)."""
    controller = synthesize(rr, rr_box, 1e-2, Kr=[4.0, 6.0])
    trajectory = PaperTrajectory()
    e0 = np.array([0.05, -0.03])
    ref0 = trajectory.reference(0.0)
    q0 = ref0.q - e0
    qd0 = ref0.qd + controller.Kr * e0  # ed(0) = -Kr e(0), so r(0) = 0
    result = simulate(nominal_plant, controller, trajectory, duration=1.0, q0=q0, qd0=qd0)
    expected = e0 * np.exp(-np.outer(result.t, controller.Kr))
    np.testing.assert_allclose(result.error, expected, atol=2e-7)


def test_exact_model_lyapunov_decays_at_least_at_rate_phi_P(rr, rr_box, nominal_plant):
    """Exact parameters: Vdot = -(kappa ||rho|| + phi) ||r||^2 <= -2 phi_P / lambda_max(M) V,
    with V = r^T M r / 2 (textbook M)."""
    controller = synthesize(rr, rr_box, 1e-2, Kr=5.0)
    trajectory = PaperTrajectory()
    result = simulate(
        nominal_plant, controller, trajectory, duration=0.5, q0=[0.2, -0.1], qd0=[1.0, 0.5]
    )
    r = (result.qd_desired - result.qd) + controller.Kr * result.error
    V = np.empty(len(result.t))
    lambda_max = 0.0
    for k in range(len(result.t)):
        M = rr_closed_form(result.q[k], result.qd[k], **NOMINAL)[0]
        V[k] = 0.5 * r[k] @ M @ r[k]
        lambda_max = max(lambda_max, np.linalg.eigvalsh(M)[-1])
    assert V[0] > 1.0
    assert np.all(np.diff(V) <= 1e-9 * V[0])
    bound = V[0] * np.exp(-2 * controller.phi_P / lambda_max * result.t)
    assert np.all(V <= bound * (1 + 1e-6) + 1e-12)


def test_theorem1_lyapunov_decreases_outside_the_ball(rr, rr_box, true_plant):
    """Theorem 1 (known bound, constant gains), true plant: V = r^T M r / 2 with the true M
    (textbook) decreases whenever ||r|| >= 1/kappa_P, and ||r|| is ultimately bounded by
    sqrt(lambda_max / lambda_min) / kappa_P."""
    box = dataclasses.replace(rr_box, disturbance_bound=0.0)
    controller = synthesize(rr, box, 1e-2)
    assert not controller.adaptive
    result = simulate(
        true_plant,
        controller,
        PaperTrajectory(),
        duration=2.0,
        q0=[0.3, -0.3],
        qd0=[0.0, 0.0],
        solver=SolverOptions(output_rate=2000.0),
    )
    r = (result.qd_desired - result.qd) + controller.Kr * result.error
    r_norm = np.linalg.norm(r, axis=1)
    V = np.empty(len(result.t))
    eigenvalues = []
    for k in range(len(result.t)):
        M = rr_closed_form(result.q[k], result.qd[k], **TRUE)[0]
        V[k] = 0.5 * r[k] @ M @ r[k]
        eigenvalues.append(np.linalg.eigvalsh(M))
    ball = 1.0 / controller.kappa_P
    outside = (r_norm[:-1] >= ball) & (r_norm[1:] >= ball)
    assert outside.sum() > 10  # the run starts far outside the ball
    assert np.all(np.diff(V)[outside] < 0)
    eigenvalues = np.array(eigenvalues)
    ultimate = math.sqrt(eigenvalues[:, 1].max() / eigenvalues[:, 0].min()) / controller.kappa_P
    first_inside = np.argmax(r_norm < ball)
    assert np.all(r_norm[first_inside:] <= ultimate)


def test_scenario1_ic1_meets_epsilon(rr, rr_box, true_plant):
    """The paper's scenario 1 (continuous, no disturbance, epsilon = 1e-3), IC1, 6 s."""
    controller = synthesize(rr, rr_box, 1e-3)
    result = simulate(
        true_plant, controller, PaperTrajectory(), duration=6.0, q0=[0, 0], qd0=[0, 0]
    )
    metrics = result.metrics
    assert metrics["met"], metrics
    assert metrics["final_error"] < 1e-3
    assert metrics["phi"] > controller.phi_P  # the integral gains had to grow
    assert metrics["kappa"] > controller.kappa_P


@pytest.mark.parametrize("ic", ["IC1", "IC2"])
def test_scenario3_meets_epsilon_with_unknown_disturbance(rr, rr_box, true_plant, ic):
    """The paper's scenario 3: 1 kHz zero-order hold, ||d|| <= 10 N m unknown, epsilon = 1e-2."""
    epsilon = 1e-2
    controller = synthesize(rr, rr_box, epsilon, sample_period=1e-3, sampled_law="paper")
    q0 = [0.0, 0.0] if ic == "IC1" else [2 * epsilon, -2 * epsilon]
    result = simulate(
        true_plant,
        controller,
        PaperTrajectory(),
        duration=6.0,
        q0=q0,
        qd0=[0, 0],
        disturbance_bound=10.0,
        seed=7,
    )
    assert result.metrics["met"], result.metrics
    assert np.linalg.norm(result.disturbance, axis=1).max() > 5.0  # the disturbance was real


# ------------------------------------------------------------------ implicit sampled-data law
def _panda_controller(sample_period, sampled_law="implicit"):
    import urpc

    robot = urpc.load_robot("panda", locked_joints=["panda_finger_joint1", "panda_finger_joint2"])
    box = urpc.load_uncertainty(
        Path(__file__).resolve().parents[1] / "robots" / "panda" / "uncertainty.yaml", robot
    )
    controller = urpc.synthesize(
        robot, box, 1e-2, method="hull", sample_period=sample_period, sampled_law=sampled_law
    )
    return robot, box, controller


def test_implicit_law_contracts_on_every_sampled_plant_for_every_gain():
    """Spectral radius of the held loop ``r+ = (1 - T M^-1 K) r`` on plants drawn from the box
    (vertices and interior points), independent of the law's own derivation: below 1 for gains
    from 1 to 1e9, where the paper's law (K = D 1) is unstable for large gains."""
    T = 1e-3
    robot, box, controller = _panda_controller(T)
    rng = np.random.default_rng(4)
    unstable_paper = 0
    for trial in range(12):
        point = box.vertex(int(rng.integers(2**box.n_uncertain))) if trial % 2 else box.sample(rng)
        plant = box.plant(robot, point)
        q = rng.uniform(-1, 1, 7)
        M = plant.M(q)
        for gain in (1.0, 50.0, 5e3, 1e9):
            K = np.column_stack([controller.feedback.torque(q, gain, e) for e in np.eye(7)])
            loop = np.eye(7) - T * np.linalg.solve(M, K)
            assert np.abs(np.linalg.eigvals(loop)).max() < 1.0
            paper_loop = np.eye(7) - T * gain * np.linalg.inv(M)
            unstable_paper += np.abs(np.linalg.eigvals(paper_loop)).max() > 1.0
    assert unstable_paper > 0  # the test would catch the paper's law


def test_implicit_feedback_is_the_dense_formula_for_every_gain():
    """The step's Cholesky form ``D (r - D T y)`` against ``D (M_L + D T)^-1 M_L r`` written out,
    ``D`` capped at ``phi_max`` (docs/sampled-data.md §1): above it the torque is the cap's, to
    the bit, so that once the gains have saturated the feedback is the same at every sample."""
    T = 1e-3
    _, _, controller = _panda_controller(T)
    cap = controller.phi_max
    assert controller.feedback.gain_cap == cap and 1e3 < cap < 1e6
    rng = np.random.default_rng(6)
    for _ in range(5):
        q, r = rng.uniform(-1, 1, 7), rng.normal(size=7)
        ML = controller.inertia_bounds.lower(q)
        for gain in (1.0, 50.0, 5e3, cap * (1 - 1e-9), 1e6, 1e9):
            D = min(gain, cap)
            dense = D * np.linalg.solve(ML + D * T * np.eye(7), ML @ r)
            np.testing.assert_allclose(
                controller.feedback.torque(q, gain, r), dense, rtol=1e-8, atol=1e-9 * D * T
            )
        above = controller.feedback.torque(q, 1e9, r)
        assert np.array_equal(above, controller.feedback.torque(q, cap, r))
        assert not np.array_equal(above, controller.feedback.torque(q, 0.5 * cap, r))


def test_implicit_law_tends_to_the_paper_law_as_the_period_vanishes():
    _, _, fast = _panda_controller(1e-15)
    _, _, paper = _panda_controller(None)
    rng = np.random.default_rng(5)
    q, qd = rng.uniform(-1, 1, 7), rng.normal(size=7)
    ref = Reference(q + 0.01, qd + 0.1, rng.normal(size=7))
    state = np.array([0.3])
    np.testing.assert_allclose(
        fast.output(0.0, q, qd, ref, state), paper.output(0.0, q, qd, ref, state), rtol=1e-6
    )


def test_adaptation_stops_at_the_gain_ceiling():
    _, _, controller = _panda_controller(1e-3)
    s_max = (controller.phi_max - controller.phi_P) / controller.phi_I
    ref = Reference(np.full(7, 0.5), np.zeros(7), np.zeros(7))
    state = controller.advance(0.0, np.zeros(7), np.zeros(7), ref, np.array([s_max * 0.999]))
    assert state[0] == s_max
    assert controller.gains(state)[0] == pytest.approx(controller.phi_max)
    frozen = controller.state_derivative(0.0, np.zeros(7), np.zeros(7), ref, state)
    assert frozen[0] == 0.0
    _, _, paper = _panda_controller(1e-3, "paper")
    assert paper.phi_max == np.inf
