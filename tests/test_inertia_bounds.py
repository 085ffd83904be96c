"""Loewner bounds of the inertia over a box, checked against plants rebuilt by Pinocchio at
sampled points and vertices of the box (an independent reference: the plant's own CRBA)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import rr_closed_form

from urpc.model.inertia_bounds import InertiaBounds, sample_configurations, spatial_bounds
from urpc.model.uncertainty import parse_uncertainty

WRIST = {"mass": "20%", "com_x": "+-0.02", "com_y": "+-0.01", "ixx": "30%", "iyz": "+-0.001"}
BOXES = {
    "ur5_physical": {
        "links": {
            "forearm_link": {"mass": "10%", "com_z": "+-0.02"},
            "wrist_1_link": WRIST,
            "wrist_3_link": {"mass": [0.1, 0.5], "com_z": "+-0.05", "izz": "50%"},
        },
        "payload": {"link": "tool0", "mass": [0, 3], "com_z": [0, 0.1]},
    },
    "ur5_barycentric": {
        "links": {
            "forearm_link": {"barycentric": {"m": "10%", "h_z": "+-0.05", "I_yy": "20%"}},
            "wrist_2_link": {"barycentric": {"m": "10%", "h_x": "+-0.01", "h_y": "+-0.01"}},
            "wrist_3_link": {"barycentric": {"m": "10%", "I_zz": "30%", "h_z": "+-0.002"}},
        }
    },
}


def _physical(inertia) -> bool:
    return np.linalg.eigvalsh(inertia.matrix())[0] >= -1e-12


@pytest.mark.parametrize("name", sorted(BOXES))
def test_bounds_enclose_every_sampled_plant(ur5, name):
    box = parse_uncertainty(BOXES[name], ur5, source=name)
    bounds = InertiaBounds(ur5, box)
    rng = np.random.default_rng(0)
    configurations = sample_configurations(bounds.robot, 25, seed=3)
    checked = 0
    for k in range(200):
        point = box.vertex(int(rng.integers(2**box.n_uncertain))) if k % 2 else box.sample(rng)
        if not all(_physical(b.inertia(point.links[b.link])) for b in box.links):
            continue
        plant = box.plant(ur5, point)
        q = configurations[k % len(configurations)]
        M = plant.M(q)
        scale = np.abs(M).max()
        assert np.linalg.eigvalsh(M - bounds.lower(q))[0] >= -1e-12 * scale
        assert np.linalg.eigvalsh(bounds.upper(q) - M)[0] >= -1e-12 * scale
        checked += 1
    assert checked > 100


def test_rr_bounds_against_the_closed_form_model(rr, rr_box):
    """Table I: the closed-form M at a grid of (m2, lc2, I2) over the box lies between the bounds,
    and the bounds are not vacuous (M_L positive definite, beta well above zero)."""
    bounds = InertiaBounds(rr, rr_box)
    for q2 in np.linspace(-np.pi, np.pi, 9):
        q = np.array([0.3, q2])
        ML, MU = bounds.lower(q), bounds.upper(q)
        for m2 in (5.0, 7.5, 10.0):
            for lc2 in (0.5, 0.5125, 0.525):
                for I2 in (5 / 12, 1.0, 20 / 12):
                    M, _, _ = rr_closed_form(q, np.zeros(2), m2, lc2, I2)
                    assert np.linalg.eigvalsh(M - ML)[0] >= -1e-12
                    assert np.linalg.eigvalsh(MU - M)[0] >= -1e-12
        assert np.linalg.eigvalsh(ML)[0] > 0.3
        assert bounds.beta(q) > 0.25


def test_spatial_bounds_of_one_link_by_dense_sampling(rr, rr_box):
    """The 6x6 bounds of one link against 2000 spatial inertias drawn from its box."""
    box = rr_box.link_box("link2")
    rng = np.random.default_rng(1)
    for scale in (0.5, 5.0, 50.0):
        lower, upper = spatial_bounds(box, scale)
        for _ in range(2000):
            sigma = box.inertia(rng.uniform(box.lower, box.upper)).matrix()
            assert np.linalg.eigvalsh(sigma - lower.matrix())[0] >= -1e-12
            assert np.linalg.eigvalsh(upper.matrix() - sigma)[0] >= -1e-12
