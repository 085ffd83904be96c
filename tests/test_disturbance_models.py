"""The disturbance models of a sampled run: ``ball`` (the default, drawn in ``||d|| <= D``) and
``against`` (``d_k = -D r_k / ||r_k||``, constant magnitude against the sliding variable).

Reference: the loop written out (``r`` from the recorded samples and the reference, each period
integrated by DOP853 on the textbook RR model of ``conftest.rr_closed_form``), independent of the
simulator's RK4 plant.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import rr_closed_form
from scipy.integrate import solve_ivp

from urpc.control.base import Controller
from urpc.control.synthesis import synthesize
from urpc.errors import InputError
from urpc.sim.sampled import against_r
from urpc.sim.simulation import simulate
from urpc.trajectories import PaperTrajectory

TRUE = dict(m2=10.0, lc2=0.525, I2=20 / 12)


class PDPlusGravity(Controller):
    """``u = Kp e + Kd ed + g_textbook(q)``: no ``Kr``, so the model uses ``Kr = 1``."""

    name = "pd"
    epsilon = 0.05

    def output(self, t, q, qd, reference, state):
        g = rr_closed_form(q, qd, 5.0, 0.5, 5 / 12)[2]
        return 400.0 * (reference.q - q) + 40.0 * (reference.qd - qd) + g


@pytest.fixture(scope="module")
def true_plant(rr, rr_box, rr_true_point):
    return rr_box.plant(rr, rr_true_point)


def _rhs(torque):
    def rhs(t, x):
        q, qd = x[:2], x[2:]
        M, C, g = rr_closed_form(q, qd, **TRUE)
        return np.concatenate((qd, np.linalg.solve(M, torque - C @ qd - g)))

    return rhs


def _sliding(result, Kr):
    """``r_k = (qd_d - qd) + Kr (q_d - q)`` at every sample, from the recorded series."""
    return (result.qd_desired - result.qd) + Kr * (result.q_desired - result.q)


def test_against_pushes_with_magnitude_D_against_r_and_reaches_the_plant(true_plant):
    """Without a ``Kr`` on the controller, ``r = ed + e``; the plant sees ``u_k + d_k``."""
    period, duration, D = 5e-3, 0.3, 7.0
    controller, trajectory = PDPlusGravity(), PaperTrajectory()
    controller.sample_period = period
    result = simulate(
        true_plant,
        controller,
        trajectory,
        duration=duration,
        q0=[0.05, 0.0],
        disturbance_bound=D,
        disturbance="against",
    )
    assert result.info["disturbance_model"] == "against"
    r = _sliding(result, 1.0)
    norms = np.linalg.norm(r, axis=1)
    assert norms.min() > 0
    np.testing.assert_allclose(result.disturbance, -D * r / norms[:, None], rtol=1e-12)
    x = np.array([0.05, 0.0, 0.0, 0.0])
    for k, t in enumerate(result.t):
        np.testing.assert_allclose(result.q[k], x[:2], atol=1e-9)
        np.testing.assert_allclose(result.qd[k], x[2:], atol=1e-8)
        reference = trajectory.reference(t)
        u = controller.output(t, x[:2], x[2:], reference, np.zeros(0))
        r_k = (reference.qd - x[2:]) + (reference.q - x[:2])
        d = -D * r_k / np.linalg.norm(r_k)
        np.testing.assert_allclose(result.disturbance[k], d, rtol=1e-6, atol=1e-9)
        if k == len(result.t) - 1:
            break
        step = solve_ivp(_rhs(u + d), (t, t + period), x, method="DOP853", rtol=1e-12, atol=1e-12)
        x = step.y[:, -1]


def test_against_uses_the_controllers_Kr(rr, rr_box, true_plant):
    """The interval controller's ``Kr`` (30/s at epsilon = 1e-2) defines ``r``: ``d_k . r_k =
    -D ||r_k||`` at every sample, which ``Kr = 1`` would not give."""
    controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3)
    D = 10.0
    result = simulate(
        true_plant,
        controller,
        PaperTrajectory(),
        duration=0.3,
        q0=[0.02, -0.02],
        disturbance_bound=D,
        disturbance="against",
    )
    r = _sliding(result, controller.Kr)
    norms = np.linalg.norm(r, axis=1)
    np.testing.assert_allclose(np.einsum("ki,ki->k", result.disturbance, r), -D * norms, rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(result.disturbance, axis=1), D, rtol=1e-12)
    unit = _sliding(result, 1.0)
    cosine = np.einsum("ki,ki->k", result.disturbance, unit) / (D * np.linalg.norm(unit, axis=1))
    assert cosine.max() > -0.999  # with Kr = 1 the direction would differ somewhere
    assert result.metrics["met"] is not None


def test_against_is_zero_where_r_vanishes():
    """IC1 on the paper's reference: ``r_0 = 0`` exactly, so ``d_0 = 0`` (no direction)."""
    assert not against_r(np.zeros(2), np.zeros(2), np.ones(2), 10.0).any()
    d = against_r(np.array([1.0, 0.0]), np.array([0.0, 3.0]), np.array([4.0, 4.0]), 10.0)
    np.testing.assert_allclose(d, [-8.0, -6.0])


def test_ball_is_the_default_and_unchanged(rr, rr_box, true_plant):
    """``disturbance="ball"`` is the default path, bit for bit, and records nothing new."""
    controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3)
    kwargs = dict(duration=0.1, q0=[0, 0], disturbance_bound=10.0, seed=4)
    default = simulate(true_plant, controller, PaperTrajectory(), **kwargs)
    ball = simulate(true_plant, controller, PaperTrajectory(), disturbance="ball", **kwargs)
    for name in ("q", "qd", "torque", "disturbance"):
        assert np.array_equal(getattr(default, name), getattr(ball, name), equal_nan=True), name
    assert np.array_equal(default.diagnostics["phi"], ball.diagnostics["phi"])
    assert "disturbance_model" not in default.info
    against = simulate(true_plant, controller, PaperTrajectory(), disturbance="against", **kwargs)
    assert not np.array_equal(default.disturbance, against.disturbance)
    # The magnitude is D at every sample but the first (IC1: r_0 = 0).
    norms = np.linalg.norm(against.disturbance, axis=1)
    assert norms[0] == 0 and np.allclose(norms[1:], 10.0)
    assert math.isfinite(against.metrics["final_error"])


def test_unknown_disturbance_model_names_the_field(true_plant):
    with pytest.raises(InputError) as info:
        simulate(
            true_plant,
            PDPlusGravity(),
            PaperTrajectory(),
            duration=1.0,
            disturbance_bound=0.0,
            disturbance="sine",
        )
    assert info.value.field == "disturbance"
    assert "ball" in str(info.value) and "against" in str(info.value)
