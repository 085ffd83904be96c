"""The certificate against simulations it must not contradict, and its reports.

The floor is a claim about every plant of the box: a simulation of any plant (vertices included)
under the certified law must end below ``max(epsilon, epsilon_floor)``. Runs where the gains
saturate (epsilon far below the floor) test the floor itself.
"""

from __future__ import annotations

import numpy as np
import pytest

import urpc
from urpc.control.certificate import certify
from urpc.sim.trajectories import PaperTrajectory

DURATION = 3.0


def _final_error(result, window: float = 1.0) -> float:
    keep = result.t >= result.t[-1] - window
    return float(result.error_norm[keep].max())


@pytest.mark.parametrize(
    ("epsilon", "period"),
    [(1e-2, 2e-4), (1e-4, 1e-4)],  # certified; and far below the floor (saturated gains)
)
def test_no_simulated_plant_beats_the_floor(rr, rr_box, epsilon, period):
    # Kr fixed at the paper's value for epsilon = 1e-2, so that epsilon = 1e-4 saturates the gains.
    controller = urpc.synthesize(rr, rr_box, epsilon, sample_period=period, Kr=30.0)
    certificate = certify(controller, PaperTrajectory(), duration=DURATION, disturbance_bound=10.0)
    assert np.isfinite(certificate.epsilon_floor)
    assert certificate.certified == (certificate.epsilon_floor <= epsilon)
    claim = max(epsilon, certificate.epsilon_floor)
    for vertex in (0, 7):  # the light and the heavy corner of Table I
        plant = rr_box.plant(rr, rr_box.vertex(vertex))
        result = urpc.simulate(
            plant, controller, PaperTrajectory(), duration=DURATION, q0=np.zeros(2),
            sample_period=period, disturbance_bound=10.0, seed=vertex,
        )  # fmt: skip
        assert _final_error(result) <= claim, (vertex, certificate.summary())


def test_the_paper_law_under_a_hold_is_not_certified(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    certificate = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert not certificate.certified
    assert certificate.failed[0].name.startswith("paper law")
    assert "implicit" in certificate.failed[0].explanation


def test_an_uncertified_period_names_the_failed_condition_and_the_period_that_works(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3)
    certificate = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert not certificate.certified
    assert 0 < certificate.max_sample_period < 1e-3
    faster = urpc.synthesize(rr, rr_box, 1e-2, sample_period=certificate.max_sample_period * 0.99)
    again = certify(faster, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert again.certified, again.summary()


def test_continuous_time_theorem_2_is_certified_for_any_epsilon(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-3)
    certificate = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert certificate.certified and certificate.epsilon_floor == 0.0
    names = {c.name for c in certificate.conditions}
    assert {"Theorem 2: kappa_I > 0", "Theorem 2: phi_I > 0"} <= names


def test_a_sampled_certificate_needs_the_disturbance_bound(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-4)
    certificate = certify(controller, PaperTrajectory(), duration=4.0)
    assert not certificate.certified
    assert certificate.failed[0].name == "disturbance bound given"


def test_certificate_json_has_the_documented_fields(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-4)
    data = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0).to_dict()
    assert {"certified", "epsilon_floor", "max_sample_period", "conditions"} <= set(data)
    assert all({"name", "holds", "value", "limit"} <= set(c) for c in data["conditions"])
