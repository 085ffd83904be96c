"""Random true plants are rigid bodies, and a box whose inertia lower bound is not positive
definite does not blow the sampled law up (issue 21.8)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import urpc
from urpc.cli import main
from urpc.control.feedback import implicit_feedback, positive_part

#: The RR arm's link 2 (I_C = diag(5/3, 5/12, 5/3) kg m^2) with independent inertia intervals
#: that break the triangle inequality izz <= ixx + iyy in part of the box: partly no rigid body.
PARTLY_PHYSICAL = (
    "links:\n  link2: {mass: [5, 10], ixx: [1.5, 1.8], iyy: [0.05, 0.5], izz: [1.5, 1.8]}\n"
)


def test_the_sampler_draws_only_rigid_bodies_and_counts_the_rejections(rr, tmp_path):
    path = tmp_path / "box.yaml"
    path.write_text(PARTLY_PHYSICAL)
    box = urpc.load_uncertainty(path, rr)
    plain = [
        urpc.physically_consistent(box, box.sample(np.random.default_rng(s))) for s in range(200)
    ]
    assert not all(plain) and any(plain)  # the box is partly non-physical
    rejected = 0
    for seed in range(20):
        point, count = urpc.sample_rigid_point(box, seed)
        assert urpc.physically_consistent(box, point)
        rejected += count
    assert rejected > 0
    again, count = urpc.sample_rigid_point(box, np.random.default_rng(3))
    np.testing.assert_array_equal(
        again.links["link2"], urpc.sample_rigid_point(box, 3)[0].links["link2"]
    )


def test_simulate_says_how_many_draws_were_rejected(tmp_path, capsys):
    path = tmp_path / "box.yaml"
    path.write_text(PARTLY_PHYSICAL)
    argv = ["simulate", "--robot", "rr_planar", "-u", str(path), "--true-params", "sample"]
    for seed in range(6):
        assert main([*argv, "--seed", str(seed), "--duration", "0.02", "--json"]) == 0
        description = json.loads(capsys.readouterr().out)["true_parameters"]["description"]
        assert "rigid bodies of the box" in description
        if "rejected" in description:
            return
    pytest.fail("no seed of 0..5 needed a rejection (the box is mostly non-physical)")


def test_an_indefinite_inertia_bound_gives_a_bounded_contracting_feedback():
    indefinite = np.diag([1.0, -0.5])  # M_L not positive definite at this q
    r = np.array([0.3, 1.0])
    made = positive_part(indefinite)
    assert np.all(np.linalg.eigvalsh(made) > 0)
    np.testing.assert_allclose(made[0, 0], 1.0)  # the positive mode is kept
    gain = 1e4
    for step in np.linspace(0.05, 5.0, 100).tolist() + [0.5]:  # D T = 0.5 = -lambda: singular
        feedback = implicit_feedback(made, gain, step, r)
        assert np.all(np.isfinite(feedback))
        assert feedback @ r > 0  # still opposes r: the loop contracts
        assert np.linalg.norm(feedback) <= gain * np.linalg.norm(r)
        # What the law computed before: singular at D T = 0.5, pushing along r beyond.
        try:
            raw = gain * np.linalg.solve(indefinite + step * np.eye(2), indefinite @ r)
        except np.linalg.LinAlgError:
            assert step == pytest.approx(0.5)
            continue
        if step > 0.5 + 1e-9:
            assert raw[1] * r[1] < 0
