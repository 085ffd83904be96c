"""The baselines: r-alpha (bounds, design conditions, law) and computed torque.

Independent references: the textbook RR model written out in ``conftest.rr_closed_form``, the
Lyapunov inequality of the r-alpha design, and the analytic solution of the PD error dynamics.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import rr_closed_form
from scipy.integrate import solve_ivp

from urpc.control.base import Reference
from urpc.control.computed_torque import ComputedTorqueController, synthesize_computed_torque
from urpc.control.r_alpha import (
    PAPER_BETAS,
    Betas,
    RAlphaController,
    estimate_betas,
    gain_matrix,
    sample_dynamics,
    synthesize_r_alpha,
)
from urpc.errors import InputError
from urpc.trajectories import PaperTrajectory

GOLDEN = (1 + np.sqrt(5)) / 2


def closed_form_quantities(q, m2, lc2, I2, d):
    """lambda_min(M), lambda_max(M), sqrt(sum ||L_i||^2), ||g - d|| from the textbook model."""
    n = len(q)
    out = np.empty((n, 4))
    for s in range(n):
        M, _, g = rr_closed_form(q[s], np.zeros(2), m2[s], lc2[s], I2[s])
        # L_i[k, j] = C(q, e_k)[i, j]: (C(q, qd) v)_i = qd^T L_i v
        Ck = [rr_closed_form(q[s], e, m2[s], lc2[s], I2[s])[1] for e in np.eye(2)]
        L = [np.array([[Ck[k][i, j] for j in range(2)] for k in range(2)]) for i in range(2)]
        eig = np.linalg.eigvalsh(M)
        gain = np.sqrt(sum(np.linalg.norm(Li, 2) ** 2 for Li in L))
        out[s] = eig[0], eig[-1], gain, np.linalg.norm(g - d[s])
    return out


def test_sampled_quantities_match_the_textbook_model(rr, rr_box):
    samples = sample_dynamics(rr, rr_box, n_samples=3000, seed=5)
    point = samples.points["link2"]
    m2, lc2, I2 = point[:, 0], point[:, 1], point[:, 6]  # mass, com_x, iyy
    assert np.all((m2 >= 5) & (m2 <= 10) & (lc2 >= 0.5) & (lc2 <= 0.525))
    assert np.all((I2 >= 5 / 12) & (I2 <= 20 / 12))
    assert np.all((samples.q >= 0) & (samples.q <= 2 * np.pi))
    assert np.all(np.abs(samples.disturbance) <= 10)
    reference = closed_form_quantities(samples.q, m2, lc2, I2, samples.disturbance)
    computed = np.column_stack(
        [
            samples.lambda_min,
            samples.lambda_max,
            samples.coriolis_gain,
            samples.gravity_disturbance,
        ]
    )
    np.testing.assert_allclose(computed, reference, rtol=1e-10, atol=1e-10)


def test_sampled_quantities_match_pinocchio_plants(rr, rr_box):
    """The batched regressor evaluation agrees with crba / computeCoriolisMatrix / gravity of a
    plant rebuilt at each sampled point."""
    samples = sample_dynamics(rr, rr_box, n_samples=30, seed=11, disturbance_bound=0.0)
    for s in range(30):
        plant = rr_box.plant(rr, {"link2": samples.points["link2"][s]})
        q = samples.q[s]
        eig = np.linalg.eigvalsh(plant.M(q))
        C = [plant.C(q, e) for e in np.eye(2)]
        L = [np.array([[C[k][i, j] for j in range(2)] for k in range(2)]) for i in range(2)]
        gain = np.sqrt(sum(np.linalg.norm(Li, 2) ** 2 for Li in L))
        assert samples.lambda_min[s] == pytest.approx(eig[0], rel=1e-10)
        assert samples.lambda_max[s] == pytest.approx(eig[-1], rel=1e-10)
        assert samples.coriolis_gain[s] == pytest.approx(gain, rel=1e-10, abs=1e-12)
        assert samples.gravity_disturbance[s] == pytest.approx(
            np.linalg.norm(plant.g(q)), rel=1e-10
        )


def test_estimated_betas_match_the_textbook_extremes(rr, rr_box):
    """1e5 samples (the paper's procedure) land just inside the exact extremes of the textbook
    model over the Table I box, and near design.md's sampled values."""
    betas = estimate_betas(rr, rr_box)  # defaults: 1e5 samples, seed 0, d in [-10, 10]^2
    assert betas.n_samples == 100_000 and betas.seed == 0
    # Exact extremes by a dense grid (M depends on q2 only; m2, lc2, I2 at the box vertices).
    q2 = np.linspace(0, 2 * np.pi, 2001)
    lam_min, lam_max = np.inf, 0.0
    for m2 in (5, 10):
        for lc2 in (0.5, 0.525):
            for I2 in (5 / 12, 20 / 12):
                for angle in q2:
                    M = rr_closed_form([0.0, angle], np.zeros(2), m2, lc2, I2)[0]
                    eig = np.linalg.eigvalsh(M)
                    lam_min, lam_max = min(lam_min, eig[0]), max(lam_max, eig[-1])
    coriolis_sup = 10 * 1.0 * 0.525 * np.sqrt(GOLDEN**2 + 1)  # |h| max times ||[[0,1],[1,1]]||, 1
    g_sup = np.hypot((10 * 0.5 + 10 * 1.0) * 9.81 + 10 * 0.525 * 9.81 + 10, 10 * 0.525 * 9.81 + 10)
    assert lam_min <= betas.beta0 <= 1.03 * lam_min
    assert 0.98 * lam_max <= betas.beta1 <= lam_max
    assert 0.99 * coriolis_sup <= betas.beta2 <= coriolis_sup
    assert 0.96 * g_sup <= betas.beta3 <= g_sup
    # design.md: "sampling with the textbook model gives about 0.48, 31.1, 9.90, 212.5"
    assert betas.beta0 == pytest.approx(0.48, abs=0.01)
    assert betas.beta1 == pytest.approx(31.1, rel=0.015)
    assert betas.beta2 == pytest.approx(9.90, rel=0.01)
    assert betas.beta3 == pytest.approx(212.5, rel=0.015)


def test_estimated_betas_bound_fresh_samples(rr, rr_box):
    betas = estimate_betas(rr, rr_box)
    fresh = sample_dynamics(rr, rr_box, n_samples=20_000, seed=2024)
    checks = [
        (betas.beta0 - fresh.lambda_min, betas.beta0),
        (fresh.lambda_max - betas.beta1, betas.beta1),
        (fresh.coriolis_gain - betas.beta2, betas.beta2),
        (fresh.gravity_disturbance - betas.beta3, betas.beta3),
    ]
    for excess, scale in checks:
        assert np.mean(excess > 0) <= 0.01
        assert excess.max() <= 0.01 * scale


def test_estimate_is_seeded_and_cached(rr, rr_box):
    a = estimate_betas(rr, rr_box, n_samples=2000, seed=3)
    b = estimate_betas(rr, rr_box, n_samples=2000, seed=3)
    c = estimate_betas(rr, rr_box, n_samples=2000, seed=4)
    assert a == b and a != c
    again = sample_dynamics(rr, rr_box, n_samples=2000, seed=3).betas(seed=3)
    assert again == a


def test_design_conditions_with_the_papers_numbers():
    controller = RAlphaController(PAPER_BETAS, 2, r=1e-2, alpha=1.0, Lambda=1.0, Q=35.0, eta=7e-5)
    conditions = controller.design_conditions()
    assert conditions.rate_Lambda and conditions.rate_Q and conditions.tolerance and conditions.hold
    assert conditions.required_Q == pytest.approx(34.27)
    assert conditions.eta_max == pytest.approx(1e-4 * 35 * 0.86 / 34.27, rel=1e-12)  # 8.78e-5
    # too small Q violates the rate condition, and (through lambda_min(Q)) the tolerance one
    weak = RAlphaController(PAPER_BETAS, 2, Q=30.0, eta=7e-5).design_conditions()
    assert not weak.rate_Q and weak.eta_max == pytest.approx(1e-4 * 30 * 0.86 / 34.27)
    assert "VIOLATED" in str(weak)
    # lambda_min of a full matrix is used
    full = RAlphaController(PAPER_BETAS, 2, Q=[[40.0, 10.0], [10.0, 40.0]]).design_conditions()
    assert full.lambda_min_Q == pytest.approx(30.0)


def test_synthesis_picks_the_least_conservative_gains_that_meet_the_conditions(rr, rr_box):
    controller = synthesize_r_alpha(rr, rr_box, betas=PAPER_BETAS, r=0.02, alpha=2.0)
    conditions = controller.design_conditions()
    assert conditions.hold
    assert conditions.lambda_min_Q == pytest.approx(2.0 * 34.27)
    assert conditions.eta == pytest.approx(conditions.eta_max)
    assert controller.name == "r-alpha" and controller.n_states == 0
    given = synthesize_r_alpha(rr, rr_box, betas=PAPER_BETAS, Q=35, eta=7e-5, Lambda=[1, 2])
    np.testing.assert_allclose(given.Lambda, np.diag([1.0, 2.0]))


def test_control_law_formula():
    betas = Betas(0.5, 30.0, 10.0, 200.0)
    controller = RAlphaController(betas, 2, Lambda=[1.0, 2.0], Q=35.0, eta=1e-3)
    rng = np.random.default_rng(0)
    for _ in range(20):
        q, qd, qr, qdr, qddr = rng.normal(size=(5, 2))
        reference = Reference(qr, qdr, qddr)
        Lam = np.diag([1.0, 2.0])
        e, ed = q - qr, qd - qdr
        s = ed + Lam @ e
        rho = (
            30 * np.linalg.norm(qddr - Lam @ ed)
            + 10 * np.linalg.norm(qd) * np.linalg.norm(qdr - Lam @ e)
            + 200
        )
        expected = -35 * s - rho**2 / (rho * np.linalg.norm(s) + 1e-3) * s
        np.testing.assert_allclose(controller.output(0.0, q, qd, reference, np.zeros(0)), expected)
        assert controller.rho(q, qd, reference) == pytest.approx(rho)


def test_lyapunov_inequality_on_plants_of_the_box(rr, rr_box):
    """Vdot = s^T (u - M qdd_r - C qd_r - g + d) <= -s^T Q s + eta whenever the betas bound the
    plant: checked at random states on random plants of the box (textbook model)."""
    betas = estimate_betas(rr, rr_box)
    # inflate slightly so that the betas are true bounds (sampled maxima can be exceeded)
    safe = Betas(betas.beta0, 1.02 * betas.beta1, 1.02 * betas.beta2, 1.02 * betas.beta3)
    controller = RAlphaController(safe, 2)
    rng = np.random.default_rng(1)
    Q, eta, Lam = controller.Q, controller.eta, controller.Lambda
    for _ in range(300):
        m2, lc2, I2 = rng.uniform([5, 0.5, 5 / 12], [10, 0.525, 20 / 12])
        q = rng.uniform(0, 2 * np.pi, 2)
        qdr, qddr = rng.normal(scale=[1, 3], size=(2, 2)).T
        scale = 10 ** rng.uniform(-6, 0)  # down to the boundary layer, where eta matters
        q_ref = q - scale * rng.normal(size=2)
        qd = qdr + scale * rng.normal(size=2)
        d = rng.uniform(-10, 10, 2)
        reference = Reference(q_ref, qdr, qddr)
        e, ed = q - q_ref, qd - qdr
        s = ed + Lam @ e
        qd_r, qdd_r = qdr - Lam @ e, qddr - Lam @ ed
        M, C, g = rr_closed_form(q, qd, m2, lc2, I2)
        needed = M @ qdd_r + C @ qd_r + g - d
        assert np.linalg.norm(needed) <= controller.rho(q, qd, reference)
        u = controller.output(0.0, q, qd, reference, np.zeros(0))
        V_dot = s @ (u - needed)
        assert V_dot <= -s @ Q @ s + eta + 1e-12 * (1 + abs(s @ Q @ s))


def test_closed_loop_reaches_the_r_ball(rr, rr_box, rr_true_point):
    """Continuous time, true plant of the paper: ||s|| obeys the r-alpha bound
    ||s||^2 <= (lmax/lmin) ||s0||^2 exp(-c t) + 2 eta/(c lmin), c = 2 lambda_min(Q)/lmax,
    with lmin, lmax the true plant's inertia extremes, and ends inside the ball r."""
    plant = rr_box.plant(rr, rr_true_point)
    controller = RAlphaController(PAPER_BETAS, 2)
    trajectory = PaperTrajectory()

    def rhs(t, x):
        q, qd = x[:2], x[2:]
        u = controller.output(t, q, qd, trajectory.reference(t), np.zeros(0))
        return np.concatenate([qd, plant.forward_dynamics(q, qd, u)])

    x0 = np.array([0.02, -0.02, 0.0, 0.0])
    times = np.linspace(0, 1.5, 301)
    solution = solve_ivp(rhs, (0, 1.5), x0, method="LSODA", t_eval=times, rtol=1e-9, atol=1e-11)
    assert solution.success
    s = np.empty(len(times))
    for k, t in enumerate(times):
        reference = trajectory.reference(t)
        e = solution.y[:2, k] - reference.q
        s[k] = np.linalg.norm(solution.y[2:, k] - reference.qd + e)
    angles = np.linspace(0, 2 * np.pi, 721)
    eigs = np.array(
        [
            np.linalg.eigvalsh(rr_closed_form([0, a], np.zeros(2), 10, 0.525, 20 / 12)[0])
            for a in angles
        ]
    )
    lmin, lmax = eigs[:, 0].min(), eigs[:, 1].max()
    c = 2 * 35 / lmax
    bound = np.sqrt(lmax / lmin * s[0] ** 2 * np.exp(-c * times) + 2 * 7e-5 / (c * lmin))
    assert np.all(s <= bound * (1 + 1e-6) + 1e-9)
    assert s[-1] <= 1e-2


def test_bad_gains_raise_input_errors():
    with pytest.raises(InputError, match="positive definite"):
        gain_matrix([1.0, -1.0], 2, "Q")
    with pytest.raises(InputError, match="does not fit 2 joints"):
        gain_matrix([1.0, 2.0, 3.0], 2, "Lambda")
    with pytest.raises(InputError, match="symmetric"):
        gain_matrix([[1.0, 2.0], [0.0, 1.0]], 2, "Q")
    with pytest.raises(InputError, match="eta"):
        RAlphaController(PAPER_BETAS, 2, eta=0.0)


# ============================================================================ computed torque
@pytest.mark.parametrize("damping", [1.0, 0.4])
def test_computed_torque_gives_the_linear_error_dynamics(rr, damping):
    """Exact model, no disturbance: e = q_d - q follows e'' + Kd e' + Kp e = 0 per joint."""
    omega = 6.0
    controller = ComputedTorqueController(rr, natural_frequency=omega, damping=damping)
    assert controller.Kp == pytest.approx(36.0) and controller.Kd == pytest.approx(12 * damping)
    trajectory = PaperTrajectory()

    def plant(t, x):
        q, qd = x[:2], x[2:]
        u = controller.output(t, q, qd, trajectory.reference(t), np.zeros(0))
        return np.concatenate([qd, rr.forward_dynamics(q, qd, u)])

    def error_dynamics(t, z):
        e, ed = z[:2], z[2:]
        return np.concatenate([ed, -controller.Kd * ed - controller.Kp * e])

    x0 = np.array([0.1, -0.05, 0.3, 0.2])
    times = np.linspace(0, 2, 201)
    closed = solve_ivp(plant, (0, 2), x0, t_eval=times, rtol=1e-10, atol=1e-12, method="DOP853")
    reference0 = trajectory.reference(0.0)
    z0 = np.concatenate([reference0.q - x0[:2], reference0.qd - x0[2:]])
    linear = solve_ivp(error_dynamics, (0, 2), z0, t_eval=times, rtol=1e-11, atol=1e-13)
    q_desired = trajectory.evaluate(times)[0]
    error = q_desired - closed.y[:2].T
    np.testing.assert_allclose(error, linear.y[:2].T, atol=1e-7)
    if damping == 1.0:  # closed form of the critically damped case
        e0, ed0 = z0[:2], z0[2:]
        analytic = (e0 + (ed0 + omega * e0) * times[:, None]) * np.exp(-omega * times[:, None])
        np.testing.assert_allclose(error, analytic, atol=1e-7)


def test_computed_torque_uses_the_nominal_model(rr, rr_box, rr_true_point):
    controller = synthesize_computed_torque(rr, rr_box, natural_frequency=3.0)
    reference = Reference(np.zeros(2), np.zeros(2), np.zeros(2))
    # at rest on the reference it outputs the nominal gravity torque, not the true one
    u = controller.output(0.0, np.zeros(2), np.zeros(2), reference, np.zeros(0))
    np.testing.assert_allclose(u, rr_closed_form(np.zeros(2), np.zeros(2), 5, 0.5, 5 / 12)[2])
    plant = rr_box.plant(rr, rr_true_point)
    assert not np.allclose(u, plant.g(np.zeros(2)))
    with pytest.raises(InputError, match="damping"):
        ComputedTorqueController(rr, damping=-1.0)
