"""The gain and feedback laws the interval controller composes, against closed forms.

References: the one-joint slider (constant scalar inertia, so the implicit feedback is the scalar
``D m_L / (m_L + D T)``), the eigen-decomposition of ``M_L(q)`` on the RR arm (the implicit law
acts per mode), the textbook RR model (``conftest.rr_closed_form``) at the vertices of Table I for
the inertia figures Theorem 1's continuous-time floor is made of, and the theorems' own gain
conditions at their boundaries.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from conftest import SLIDER, rr_closed_form

import urpc
from urpc.control.certificate import certify
from urpc.control.feedback import ContinuousFeedback, HeldFeedback, ImplicitFeedback
from urpc.control.gain_laws import AdaptiveGains, ConstantGains
from urpc.control.interval import IntervalPassivityController
from urpc.trajectories import PaperTrajectory

GAINS = (1.0, 50.0, 5e3, 1e6, 1e9)  # [N m s/rad]


def test_each_feedback_law_on_one_joint_is_its_closed_form(tmp_path):
    """Continuous and held: ``D r``; implicit: ``D m_L r / (m_L + D T)`` with the cart's sound
    lower mass ``0 < m_L <= 0.8 * 2 kg`` (the box's lightest cart) and ``D`` capped at
    ``phi_max``, never above the dead-beat ``m_L r / T``."""
    (tmp_path / "slider.urdf").write_text(SLIDER)
    robot = urpc.load_robot(tmp_path / "slider.urdf")
    box = urpc.parse_uncertainty({"links": {"cart": {"mass": "20%"}}}, robot)
    T = 1e-3
    laws = {
        law: urpc.synthesize(robot, box, 1e-2, **options)
        for law, options in {
            "continuous": {},
            "paper": dict(sample_period=T, sampled_law="paper"),
            "implicit": dict(sample_period=T),
        }.items()
    }
    assert [type(c.feedback) for c in laws.values()] == [
        ContinuousFeedback,
        HeldFeedback,
        ImplicitFeedback,
    ]
    assert [c.feedback.name for c in laws.values()] == list(laws)
    implicit = laws["implicit"]
    m_L = float(implicit.inertia_bounds.lower(np.zeros(1))[0, 0])
    assert 0 < m_L <= 0.8 * 2.0
    rng = np.random.default_rng(0)
    for gain in GAINS:
        q, r = rng.uniform(-1, 1, 1), rng.normal(size=1)
        for law in ("continuous", "paper"):
            np.testing.assert_array_equal(laws[law].feedback.torque(q, gain, r), gain * r)
        torque = implicit.feedback.torque(q, gain, r)
        D = min(gain, implicit.phi_max)
        # The Cholesky form D (r - D T y) loses the digits of (m_L + D T) / m_L to cancellation.
        rtol = 1e-14 * (1 + D * T / m_L)
        np.testing.assert_allclose(torque, D * m_L * r / (m_L + D * T), rtol=rtol)
        assert abs(torque[0]) <= m_L * abs(r[0]) / T * (1 + 1e-12)
    # Only the implicit law stops the adaptation, at its ceiling.
    assert laws["continuous"].phi_max == laws["paper"].phi_max == math.inf
    assert math.isfinite(implicit.phi_max) and implicit.phi_max > implicit.phi_P


def test_the_implicit_feedback_acts_per_mode_of_the_lower_inertia(rr, rr_box):
    """``K = D (M_L + D T)^-1 M_L`` (column by column, ``D`` capped at ``phi_max``) has the
    eigenvectors of ``M_L(q)`` and the eigenvalues ``D lambda / (lambda + D T)``, never above the
    dead-beat ``lambda / T``."""
    T = 1e-3
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=T)
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, 2)
        eigenvalues, vectors = np.linalg.eigh(controller.inertia_bounds.lower(q))
        assert eigenvalues[0] > 0
        for gain in GAINS:
            K = np.column_stack([controller.feedback.torque(q, gain, e) for e in np.eye(2)])
            D = min(gain, controller.phi_max)
            modes = D * eigenvalues / (eigenvalues + D * T)
            np.testing.assert_allclose(
                vectors.T @ K @ vectors, np.diag(modes), rtol=1e-8, atol=1e-9 * D * T
            )
            assert np.linalg.eigvalsh(K + K.T).max() / 2 <= eigenvalues[-1] / T * (1 + 1e-9)


def test_a_law_outside_the_registry_or_without_its_model_is_refused(rr, rr_box):
    """The constructor maps its flags to one law or refuses: an unknown name once ran the
    paper's law while the certificate argued for the implicit one."""
    bound = urpc.synthesize(rr, rr_box, 1e-2).bound
    gains = dict(kappa_P=2, kappa_I=1, phi_P=1, phi_I=1e6, Kr=np.full(2, 30.0))
    with pytest.raises(ValueError, match="not a sampled law"):
        IntervalPassivityController(
            bound, 1e-2, sample_period=1e-3, sampled_law="explicit", **gains
        )
    with pytest.raises(ValueError, match="inertia bounds"):
        IntervalPassivityController(bound, 1e-2, sample_period=1e-3, **gains)
    held = IntervalPassivityController(
        bound, 1e-2, sample_period=1e-3, sampled_law="paper", **gains
    )
    assert isinstance(held.feedback, HeldFeedback) and held.sample_period == 1e-3


def test_the_gain_laws_are_the_theorems_gains_and_conditions(rr, rr_box):
    """Theorem 2: ``D = (kappa_P + kappa_I s) ||rho|| + phi_P + phi_I s``, ``s`` growing by
    ``T ||e||`` outside the dead zone up to ``s_max``; Theorem 1: constants and no state. The
    conditions at their boundaries: ``kappa_P, phi_P >= 1`` (Theorem 1), ``kappa_I, phi_I > 0``
    strictly (Theorem 2)."""
    adaptive = AdaptiveGains(2.0, 1.0, 3.0, 1e3, epsilon=1e-2, phi_max=4.0)
    assert adaptive.s_max == pytest.approx(1e-3)
    assert adaptive.gain(5.0, np.array([2e-4])) == pytest.approx((2 + 2e-4) * 5 + 3 + 0.2)
    inside, outside = np.array([6e-3, -7.9e-3]), np.array([6e-3, -8.1e-3])
    assert adaptive.advance(inside, np.array([0.0]), 1e-3)[0] == 0.0
    grown = adaptive.advance(outside, np.array([0.0]), 1e-3)[0]
    assert grown == pytest.approx(1e-3 * np.linalg.norm(outside))
    assert adaptive.advance(outside, np.array([9.99e-4]), 1e-3)[0] == adaptive.s_max
    assert adaptive.state_derivative(outside, np.array([adaptive.s_max]))[0] == 0.0
    constant = ConstantGains(2.0, 3.0)
    assert constant.gain(5.0, np.zeros(0)) == 13.0 and constant.n_states == 0
    assert constant.advance(outside, np.zeros(0), 1e-3).shape == (0,)

    def holding(law):
        return [c.holds for c in law.conditions()]

    assert holding(ConstantGains(1.0, 1.0)) == [True, True]
    assert holding(ConstantGains(0.999, 1.0)) == [False, True]
    assert holding(AdaptiveGains(1.0, 1e-12, 1.0, 1e-12, 1e-2, math.inf)) == [True, True]
    assert holding(AdaptiveGains(1.0, 0.0, 1.0, -1.0, 1e-2, math.inf)) == [False, False]
    # The controller picks the law from the bound: Theorem 1 with a known disturbance.
    known = dataclasses.replace(rr_box, disturbance_bound=10.0)
    assert isinstance(urpc.synthesize(rr, known, 1e-2).gain_law, ConstantGains)
    assert isinstance(urpc.synthesize(rr, rr_box, 1e-2).gain_law, AdaptiveGains)


def test_theorem1_continuous_floor_is_made_of_sound_inertia_bounds(rr, rr_box):
    """The continuous law's argument under Theorem 1: ``lambda_L``, ``lambda_U`` bound the
    textbook inertia's eigenvalues at every vertex of Table I along the reference, and the floor
    is ``sqrt(lambda_U / lambda_L) / (kappa_P min Kr)`` of them."""
    known = dataclasses.replace(rr_box, disturbance_bound=10.0)
    controller = urpc.synthesize(rr, known, 1e-2, kappa_P=30.0, Kr=30.0)
    trajectory = PaperTrajectory()
    certificate = certify(controller, trajectory, duration=4.0)
    lam_L, lam_U = certificate.figures["lambda_L"], certificate.figures["lambda_U"]
    for t in np.linspace(0, 4, 81):
        q = trajectory.reference(t).q
        for m2, lc2, I2 in itertools.product((5, 10), (0.5, 0.525), (5 / 12, 20 / 12)):
            eigenvalues = np.linalg.eigvalsh(rr_closed_form(q, q, m2, lc2, I2)[0])
            assert lam_L <= eigenvalues[0] and eigenvalues[1] <= lam_U
    floor = math.sqrt(lam_U / lam_L) / 30.0 / 30.0
    assert certificate.epsilon_floor == pytest.approx(floor, rel=1e-12)
    assert certificate.certified == (floor <= 1e-2)
    assert certificate.law == "continuous"
    assert "Theorem 1 ultimate bound below epsilon" in {c.name for c in certificate.conditions}
