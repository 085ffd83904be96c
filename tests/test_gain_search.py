"""Certified synthesis of Kr (urpc.control.gain_search): the search keeps the best certificate,
and that certificate is what a fresh synthesis and certification at the chosen gain give."""

from __future__ import annotations

import json
import math

import pytest

import urpc
from urpc.control.certificate import Certificate
from urpc.control.gain_search import best_gain, search_gains
from urpc.trajectories import PaperTrajectory


def _certificate(certified: bool, floor: float, period: float) -> Certificate:
    return Certificate(certified, 1e-2, floor, period, 1e-3, "implicit", ())


def test_the_best_is_certified_with_the_lowest_floor_else_the_longest_period():
    outcomes = {
        10.0: _certificate(False, math.inf, 9e-4),
        20.0: _certificate(True, 7e-3, 1.2e-3),
        30.0: _certificate(True, 6e-3, 1.1e-3),
        45.0: _certificate(False, 2e-2, 1.5e-3),
    }
    seen = []
    search = best_gain(lambda k: (f"controller {k}", outcomes[k]), outcomes, seen.append)
    assert search.best.Kr == 30.0 and search.controller == "controller 30.0"
    assert [t.Kr for t in seen] == list(outcomes) == [t.Kr for t in search.trials]
    uncertified = {k: c for k, c in outcomes.items() if not c.certified}
    assert best_gain(lambda k: (k, uncertified[k]), uncertified).best.Kr == 45.0
    assert json.dumps(search.to_dict())  # JSON-ready, an infinite floor as null
    assert search.to_dict()["trials"][0]["epsilon_floor"] is None


@pytest.mark.parametrize("candidates", [(), (10.0, -1.0), (float("nan"),)])
def test_bad_candidates_are_refused(candidates):
    with pytest.raises(urpc.InputError, match="positive finite"):
        best_gain(lambda k: (None, None), candidates)


def test_the_search_on_the_paper_arm_matches_a_fresh_certificate(rr, rr_box):
    options = dict(duration=4.0, disturbance_bound=10.0)
    search = search_gains(
        rr, rr_box, 1e-2, PaperTrajectory(), candidates=(15.0, 30.0, 60.0),
        sample_period=1e-3, **options,
    )  # fmt: skip
    certified = [t for t in search.trials if t.certificate.certified]
    assert certified and search.best.certificate.certified
    assert search.best.certificate.epsilon_floor == min(
        t.certificate.epsilon_floor for t in certified
    )
    fresh = urpc.certify(
        urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3, Kr=search.best.Kr),
        PaperTrajectory(), **options,
    )  # fmt: skip
    assert fresh.epsilon_floor == search.best.certificate.epsilon_floor
    assert float(search.controller.Kr.min()) == search.best.Kr
    with pytest.raises(urpc.InputError, match="candidates"):
        search_gains(rr, rr_box, 1e-2, PaperTrajectory(), duration=1.0, Kr=30.0)


def test_cli_refuses_the_search_for_the_paper_law(capsys):
    from urpc.cli import main

    code = main(["certify", "rr_planar/s3_ic1", "--search-kr"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: ") and "--sampled-law implicit" in err
    assert len(err.strip().splitlines()) == 1


def test_a_uniform_gain_certifies_no_worse_than_per_joint_gains_of_the_same_minimum(rr, rr_box):
    """Why the search is over uniform gains: the floor divides the bound of ||r|| by min Kr,
    and every enclosure grows with each joint's gain (the state boxes, K_r = max Kr, and its
    factor sqrt(lambda_U / lambda_L) when Kr is not uniform), so raising a joint's gain above
    the minimum can only raise the floor and shorten the largest period."""
    options = dict(duration=4.0, disturbance_bound=10.0)
    uniform = urpc.certify(
        urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3, Kr=30.0), PaperTrajectory(), **options
    )
    assert uniform.certified
    for Kr in ((30.0, 45.0), (45.0, 30.0)):
        mixed = urpc.certify(
            urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3, Kr=Kr), PaperTrajectory(),
            **options,
        )  # fmt: skip
        assert mixed.epsilon_floor >= uniform.epsilon_floor, Kr
        assert mixed.max_sample_period <= uniform.max_sample_period, Kr
