"""The cell enclosures do not depend on how the cells are batched (the Coriolis forms, computed
chunk by chunk to bound memory, give every cell the enclosure it gets in one batch), and they
hold the Christoffel matrices of Pinocchio's ``M`` at random points of the cells, the tube and the
box."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import urpc
import urpc.control.cell_bounds as cell_bounds
from urpc.control.cells import CellFloor
from urpc.model.inertia_bounds import InertiaBounds
from urpc.trajectories import generic_trajectory


def test_chunked_coriolis_forms_equal_one_batch(monkeypatch):
    robot = urpc.load_robot("ur5")
    box = urpc.load_uncertainty("ur5", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    trajectory = generic_trajectory(box.nominal_robot(robot))

    def pieces(chunk_bytes):
        monkeypatch.setattr(cell_bounds, "CORIOLIS_CHUNK_BYTES", chunk_bytes)
        floor = CellFloor(controller, trajectory, 0.5, cells=16)
        return floor.quantities(1e-2, 0.5, 2e-3)["pieces"]

    whole, chunked = pieces(2**40), pieces(1)  # one batch; one cell per chunk
    for a, b in zip(whole, chunked, strict=True):
        for name in ("coriolis", "metric_rate"):
            np.testing.assert_allclose(b[name], a[name], rtol=1e-12)
            assert np.all(np.isfinite(a[name])) and np.all(a[name] > 0)


# ============================================================================ against Pinocchio
def _christoffel(robot, q, v, h=1e-6):
    """``C(q, v)`` from the Christoffel symbols of Pinocchio's ``M`` (central differences)."""
    n = robot.dof
    dM = np.empty((n, n, n))  # dM[k] = dM/dq_k
    for k in range(n):
        step = np.zeros(n)
        step[k] = h
        dM[k] = (robot.M(q + step) - robot.M(q - step)) / (2 * h)
    # C_ij = sum_k (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) v_k / 2
    return 0.5 * (
        np.einsum("kij,k->ij", dM, v)
        + np.einsum("jik,k->ij", dM, v)
        - np.einsum("ijk,k->ij", dM, v)
    )


def _inside(piece, point) -> bool:
    return all(
        np.all(point.links[b.link] >= b.lower - 1e-12)
        and np.all(point.links[b.link] <= b.upper + 1e-12)
        for b in piece.links
        if b.link in point.links
    )


@pytest.mark.parametrize("arm", ["rr_planar", "ur5"])
def test_the_coriolis_bounds_hold_pinocchio_in_the_lower_metric(arm):
    """Per piece, ``coriolis`` bounds ``||S C(q, qd; pi) S|| + ||S (C(q, qd_a; pi) - C(q, qd_a;
    pi0)) S||`` with ``S = M_L(q)^-1/2`` (the piece's lower bound), at random times, errors,
    plant velocities and plants of the box (vertices and interior points): the plant's Coriolis
    matrix and its mismatch along ``qd_a``, from Pinocchio's ``M`` by its Christoffel symbols. The
    UR5's box has more parameter directions than the triangle inequality is tried for."""
    robot = urpc.load_robot(arm)
    _check_coriolis_bounds(robot, urpc.load_uncertainty(arm, robot))


def _crowded_arm(folder):
    """Two joints; the second body carries three more links on fixed joints (a sensor, a camera,
    a tool), every link with its mass, centre of mass and inertia uncertain: 40 directions in
    that body, which the plant's parameter set replaces by its interval hull."""
    inertial = (
        '<inertial><origin xyz="{c}"/><mass value="{m}"/><inertia ixx="{i}" ixy="0" ixz="0" '
        'iyy="{i}" iyz="0" izz="{i}"/></inertial>'
    )
    parts = ['<robot name="crowded"><link name="base"/>']
    parts.append(
        '<joint name="j0" type="revolute"><parent link="base"/><child link="l0"/>'
        '<axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="50" velocity="2"/></joint>'
        f'<link name="l0">{inertial.format(c="0.2 0 0", m=2.0, i=0.02)}</link>'
        '<joint name="j1" type="revolute"><parent link="l0"/><child link="l1"/>'
        '<origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>'
        '<limit lower="-2" upper="2" effort="50" velocity="2"/></joint>'
        f'<link name="l1">{inertial.format(c="0.15 0 0", m=1.5, i=0.01)}</link>'
    )
    for k, (name, c) in enumerate((("sensor", "0.05 0.02 0"), ("camera", "0 0 0.04"),
                                   ("tool", "0.1 0 -0.03"))):  # fmt: skip
        parts.append(
            f'<joint name="f{k}" type="fixed"><parent link="l1"/><child link="{name}"/>'
            f'<origin xyz="0.3 0 0"/></joint>'
            f'<link name="{name}">{inertial.format(c=c, m=0.4, i=0.002)}</link>'
        )
    parts.append("</robot>")
    path = folder / "crowded.urdf"
    path.write_text("".join(parts))
    robot = urpc.load_robot(path)
    spec = {
        "mass": "10%", "com_x": "+-0.01", "com_y": "+-0.01", "com_z": "+-0.01",
        "ixx": "20%", "iyy": "20%", "izz": "20%",
    }  # fmt: skip
    box = urpc.parse_uncertainty(
        {"links": {name: spec for name in ("l0", "l1", "sensor", "camera", "tool")}}, robot
    )
    return robot, box


def test_the_coriolis_bounds_hold_pinocchio_with_a_body_hull(tmp_path):
    """The same on an arm whose second body merges four uncertain links (the parameter set's
    interval hull of that body, :data:`urpc.control.parameter_sets.HULL_DIRECTIONS`)."""
    from urpc.control.parameter_sets import HULL_DIRECTIONS, plant_parameters

    robot, box = _crowded_arm(tmp_path)
    keys = plant_parameters(box.nominal_robot(robot), box).keys
    assert any(key[0].startswith("body") for key in keys)  # the hull is in use
    assert sum(not key[0].startswith("body") for key in keys) < HULL_DIRECTIONS
    _check_coriolis_bounds(robot, box)


def _check_coriolis_bounds(robot, box):
    T, tube, r_max = 1e-3, 5e-3, 0.2
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=T)
    trajectory = generic_trajectory(box.nominal_robot(robot))
    floor_of = CellFloor(controller, trajectory, 1.0, cells=16)
    rng = np.random.default_rng(3)
    floor_of.refine(rng.choice(16, 6, replace=False))  # halves among whole cells
    quantities = floor_of.quantities(tube, r_max, 2 * T)
    starts, ends = floor_of.spans()
    lowers = [InertiaBounds(robot, piece).lower_robot for piece in floor_of.pieces]
    nominal, Kr = controller.robot, controller.Kr
    checked = 0
    for _ in range(40):
        cell = int(rng.integers(floor_of.cells))
        t = rng.uniform(starts[cell], ends[cell] + 2 * T)
        e = rng.standard_normal(robot.dof)
        e *= tube * rng.uniform(0, 1) ** 0.2 / np.linalg.norm(e)
        r = rng.standard_normal(robot.dof)
        r *= r_max * rng.uniform(0, 1) ** 0.2 / np.linalg.norm(r)
        reference = trajectory.reference(t)
        q, qd_a = reference.q - e, reference.qd + Kr * e
        qd = reference.qd - (r - Kr * e)  # the plant's velocity, ed = r - Kr e
        point = (
            box.vertex(int(rng.integers(2**box.n_uncertain)))
            if rng.uniform() < 0.5
            else box.sample(rng)
        )
        plant = box.plant(point)
        for piece, lower, values in zip(floor_of.pieces, lowers, quantities["pieces"], strict=True):
            if not _inside(piece, point):
                continue
            S = np.linalg.inv(scipy.linalg.sqrtm(lower.M(q)).real)
            plant_part = np.linalg.norm(S @ _christoffel(plant, q, qd) @ S, 2)
            mismatch = _christoffel(plant, q, qd_a) - _christoffel(nominal, q, qd_a)
            value = plant_part + np.linalg.norm(S @ mismatch @ S, 2)
            assert value <= values["coriolis"][cell] * (1 + 1e-6), (
                t,
                value,
                values["coriolis"][cell],
            )
            checked += 1
    assert checked >= 40


@pytest.mark.parametrize("arm", ["ur5", "panda"])
def test_the_inertia_models_hold_pinocchio_over_the_cells_and_the_tube(arm):
    """``(1 - eps) M_c <= M(q) <= (1 + eps) M_c`` for the nominal model and the law's ``M_L`` at
    random times of random cells and errors of the tube (a 2-norm ball, drawn near its sphere),
    and the law's rate slopes bound ``||M_L^-1/2 (dM_L/dq . v) M_L^-1/2||`` (central differences
    of Pinocchio) for random unit directions ``v``: the Taylor form (first derivatives at the
    centre, second derivatives over boxes of cells) against Pinocchio itself. The Panda is where
    the second-order term matters most (its lightest mode is 0.005 kg m^2)."""
    locked = ("panda_finger_joint1", "panda_finger_joint2") if arm == "panda" else ()
    robot = urpc.load_robot(arm, locked_joints=locked)
    box = urpc.load_uncertainty(arm, robot)
    T, tube = 1e-3, 1e-2
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=T)
    trajectory = generic_trajectory(box.nominal_robot(robot))
    floor_of = CellFloor(controller, trajectory, 1.0, cells=20)
    rng = np.random.default_rng(11)
    floor_of.refine(np.arange(20))  # the halves: second derivatives over their first cells
    floor_of.refine(rng.choice(40, 20, replace=False))
    batch = floor_of.partition.batches[-1]  # quarters of first cells
    q = floor_of._states(batch, tube, 0.0, 2 * T)[0].val
    reference_radii = floor_of._states(batch, 0.0, 0.0, 2 * T)[0].val.rad
    models, rates = floor_of._inertia_models(batch, q, reference_radii, tube, 2 * T)
    plants = [
        (controller.robot, models[0], None),
        (controller.inertia_bounds.lower_robot, models[1], rates[1]),
    ]
    h, checked = 1e-6, 0
    for _ in range(60):
        cell = int(rng.integers(len(batch)))
        t = rng.uniform(batch.start[cell], batch.end[cell] + 2 * T)
        e = rng.standard_normal(robot.dof)
        e *= tube * rng.uniform(0, 1) ** 0.1 / np.linalg.norm(e)
        x = trajectory.reference(t).q - e
        for plant, model, slopes in plants:
            P, eps = model.inverse_factor[cell], model.eps[cell]
            if not model.valid[cell]:
                continue  # eps >= 1: a model the certificate does not use
            checked += 1
            lam = np.linalg.eigvalsh(P @ plant.M(x) @ P.T)
            assert lam[0] >= 1 - eps - 1e-9 and lam[-1] <= 1 + eps + 1e-9, (t, lam, eps)
            if slopes is None:
                continue
            v = rng.standard_normal(robot.dof)
            v /= np.linalg.norm(v)
            rate = (plant.M(x + h * v) - plant.M(x - h * v)) / (2 * h)
            S = np.linalg.inv(scipy.linalg.sqrtm(plant.M(x)).real)
            value = np.linalg.norm(S @ rate @ S, 2)
            bound = np.abs(v) @ slopes[cell] / (1 - eps)
            assert value <= bound * (1 + 1e-6), (t, value, bound)
    assert checked >= 60


def test_the_structured_second_order_terms_hold_pinocchio_on_an_8_link_chain(tmp_path):
    """On the 8-link chain of ``urpc bench certificate`` (lightest mode 3e-4 kg m^2 against a
    largest of 2 kg m^2) the inertia model's second-order terms through ``|P|`` entrywise fail
    (``eps`` up to 6.7 in the tube ``0.01``); :func:`structured_terms` keeps the structure of
    the second derivatives' centres. Against Pinocchio at random points of each half cell's
    region (``|dq_k| <= w_k``): the Taylor remainder ``M(q) - M_c - sum_k dq_k D_k`` and the
    change of each ``dM/dq_k`` (central differences) through the centre's ``P = L^-1`` never
    exceed the structured bounds, which lie below the entrywise ones."""
    from urpc.control.cell_inertia import Curvature, structured_terms, taylor_terms
    from urpc.studies.benchmark.certificate_cost import benchmark_arm

    robot, box = benchmark_arm("chain8", tmp_path)
    T, tube = 1e-3, 1e-2
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=T)
    trajectory = generic_trajectory(box.nominal_robot(robot))
    floor_of = CellFloor(controller, trajectory, 1.0, cells=12)
    floor_of.refine(np.arange(12), own_curvatures=True)
    batch = floor_of.partition.batches[-1]  # halves: second derivatives over their own boxes
    q = floor_of._states(batch, tube, 0.0, 2 * T)[0].val
    widths = floor_of._states(batch, 0.0, 0.0, 2 * T)[0].val.rad + tube
    curvatures, group = floor_of._curvatures(batch, q, tube, 2 * T)
    nominal = 0  # the first model: the nominal robot's parameters
    curvature = Curvature(
        curvatures.mid[:, :, :, nominal], curvatures.rad[:, :, :, nominal], group, widths
    )
    n, h = robot.dof, 1e-5
    centers = [robot.M(center) for center in q.mid]
    P = np.stack([np.linalg.inv(np.linalg.cholesky(M)) for M in centers])
    remainder, change = structured_terms(P, curvature)
    entry_remainder, entry_change = taylor_terms(curvatures, group, widths)
    absolute = np.abs(P)
    entrywise = np.array(
        [
            np.linalg.norm(a @ r @ a.T, 2)
            for a, r in zip(absolute, entry_remainder[:, nominal], strict=True)
        ]
    )
    assert np.all(remainder < 0.9 * entrywise), (remainder / entrywise).max()  # 0.29-0.78

    def slopes(x):
        return [(robot.M(x + h * unit) - robot.M(x - h * unit)) / (2 * h) for unit in np.eye(n)]

    rng = np.random.default_rng(5)
    for cell in range(len(batch)):
        center, p = q.mid[cell], P[cell]
        D = slopes(center)
        for _ in range(6):
            dq = widths[cell] * rng.uniform(0, 1, n) ** 0.2 * rng.choice([-1, 1], n)
            assert np.all(np.abs(dq) <= q.rad[cell])  # inside the box of the second derivatives
            Z = (
                robot.M(center + dq)
                - centers[cell]
                - sum(d * Dk for d, Dk in zip(dq, D, strict=True))
            )
            value = np.linalg.norm(p @ Z @ p.T, 2)
            assert value <= remainder[cell] * (1 + 1e-6) + 1e-7, (cell, value, remainder[cell])
            for k, slope in enumerate(slopes(center + dq)):
                value = np.linalg.norm(p @ (slope - D[k]) @ p.T, 2)
                assert value <= change[cell, k] * (1 + 1e-6) + 1e-5, (cell, k, value)
