"""Non-finite numbers never pass silently: a NaN or inf in a state, a state whose mismatch torque
overflows, a controller torque that is not finite, an expression that overflows."""

from __future__ import annotations

import numpy as np
import pytest

from urpc.bounds import METHODS, make_bound
from urpc.control.base import Controller
from urpc.errors import InputError, SimulationError
from urpc.expressions import ExpressionOverflow, evaluate
from urpc.sim.simulation import simulate
from urpc.trajectories import PaperTrajectory

VECTORS = ("q", "qd", "qd_a", "qdd_a")


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("position", range(4))
def test_enclose_and_rho_name_the_non_finite_vector(rr, rr_box, method, bad, position):
    bound = make_bound(method, rr, rr_box)
    state = [np.zeros(2) for _ in VECTORS]
    state[position] = np.array([0.0, bad])
    name = VECTORS[position]
    for call in (bound.enclose, bound.rho):
        with pytest.raises(InputError, match=rf"^field '{name}': {name} = .* NaN or infinite"):
            call(*state)


@pytest.mark.parametrize("method", ["hull", "vertex"])
def test_a_state_whose_terms_overflow_is_refused(rr, rr_box, method):
    bound = make_bound(method, rr, rr_box)
    huge = np.full(2, 1e308)
    with pytest.raises(InputError, match="overflow"):
        bound.enclose(huge, huge, np.zeros(2), np.zeros(2))


def test_rigorous_refuses_an_overflowing_enclosure(rr, rr_box):
    """Arb computes with huge exponents; the doubles it rounds to would be infinite."""
    bound = make_bound("rigorous", rr, rr_box)
    with pytest.raises(InputError, match="overflows"):
        bound.enclose(np.array([0.3, 0.5]), np.full(2, 1e200), np.full(2, 1e200), np.zeros(2))


def test_wrong_lengths_are_refused_not_broadcast(rr, rr_box):
    """``qd_a`` of length 1 used to broadcast against ``qd`` silently."""
    bound = make_bound("vertex", rr, rr_box)
    with pytest.raises(InputError, match=r"qd_a has shape \(1,\)"):
        bound.rho(np.zeros(2), np.zeros(2), np.zeros(1), np.zeros(2))


class LateInfinity(Controller):
    """A finite torque, then ``inf`` from ``t_bad`` on."""

    name = "late-inf"
    epsilon = 0.01

    def __init__(self, t_bad: float, value: float = np.inf, sample_period: float | None = None):
        self.t_bad, self.value, self.sample_period = t_bad, value, sample_period

    def output(self, t, q, qd, reference, state):
        return np.array([self.value, 0.0]) if t >= self.t_bad else np.zeros(2)


@pytest.mark.parametrize("sample_period", [None, 1e-2])
def test_an_infinite_torque_is_not_clipped_to_the_limit(rr, rr_box, sample_period):
    """With a torque limit, ``clip(inf)`` is the limit: the check comes before it."""
    with pytest.raises(SimulationError, match="non-finite"):
        simulate(
            rr,
            LateInfinity(0.05, sample_period=sample_period),
            PaperTrajectory(),
            duration=0.2,
            q0=[0, 0],
            torque_limit=100.0,
        )


def test_a_non_finite_torque_at_the_last_sample_is_an_error(rr):
    with pytest.raises(SimulationError, match="non-finite"):
        simulate(
            rr,
            LateInfinity(0.2, np.nan, sample_period=1e-2),
            PaperTrajectory(),
            duration=0.2,
            q0=[0, 0],
        )


@pytest.mark.parametrize("text", ["1e309", "-1e309", "10**10**10", "2**1024", "1e200*1e200"])
def test_expression_overflow_is_reported_as_overflow(text):
    with pytest.raises(ExpressionOverflow, match="overflows"):
        evaluate(text)
    with pytest.raises(ValueError, match="beyond the largest double"):  # still a ValueError
        evaluate(text)


def test_ordinary_expressions_still_evaluate():
    assert evaluate("5/12") == pytest.approx(5 / 12)
    assert evaluate("10**-2") == pytest.approx(0.01)
    assert evaluate("1.7e308") == 1.7e308
    with pytest.raises(ValueError, match="not a real number"):
        evaluate("(-8)**(1/3)")
