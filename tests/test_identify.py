"""urpc identify: soundness (coverage over random plants and noise), tightness against brute
force, the payload mode on the UR5, estimated derivatives, drives, and the file written."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import urpc
from urpc.identify import DerivativeBounds, FourierTrajectory, Samples, identify, record
from urpc.identify.data import load_samples, write_csv
from urpc.model.inertia import inertia_problem
from urpc.model.parameter_box import JOINTS, inertia_from_physical
from urpc.model.uncertainty import parse_uncertainty


@pytest.fixture(scope="module")
def rr():
    return urpc.load_robot("rr_planar")


@pytest.fixture(scope="module")
def ur5():
    return urpc.load_robot("ur5")


def rr_trajectory():
    a = np.array([[0.6, 0.2, 0.1], [-0.5, 0.3, 0.15]])
    b = np.array([[0.1, -0.3, 0.05], [0.4, 0.1, -0.1]])
    return FourierTrajectory(np.zeros(2), a, b, 0.25)


def ur5_trajectory():
    rng = np.random.default_rng(7)
    a, b = rng.normal(0, 0.25, (6, 3)), rng.normal(0, 0.25, (6, 3))
    return FourierTrajectory(np.array([0.0, -1.2, 1.0, -1.0, 0.5, 0.0]), a, b, 0.1)


def physical_point(box, rng):
    """A rigid body drawn uniformly from a link box (rejection of non-physical draws)."""
    for _ in range(1000):
        values = rng.uniform(box.lower, box.upper)
        if not inertia_problem(np.asarray(inertia_from_physical(values).inertia)):
            return values
    raise AssertionError("no rigid body drawn")


# ============================================================================ brute force
def test_lp_bounds_match_brute_force_on_two_unknowns(rr):
    """Mass and CoM of the RR arm's link 2 unknown: the identified box contains every grid point
    consistent with the data (soundness), and is no wider than the consistent grid points' range
    plus one grid step (tightness; the feasible set is the exact LP polytope here up to the
    McCormick envelope, which the second round tightens)."""
    prior = parse_uncertainty(
        {"links": {"link2": {"mass": [5, 10], "com_x": [0.5, 0.525]}}}, rr, "<prior>"
    )
    true = {"link2": prior.link_box("link2").nominal.copy()}
    true["link2"][0], true["link2"][1] = 7.3, 0.512
    plant = prior.plant(rr, true)
    times = np.linspace(0, 4, 60)
    noise = 1.0
    samples = record(plant, rr_trajectory(), times, noise, np.random.default_rng(3))
    result = identify(rr, prior, samples, noise, rounds=3)
    # Brute force: every (m, c_x) on a dense grid, checked against every sample and joint.
    base = prior.link_box("link2").nominal
    masses = np.linspace(5, 10, 801)
    coms = np.linspace(0.5, 0.525, 801)
    feasible_m, feasible_c = [], []
    q, qd, qdd = samples.q, samples.qd, samples.qdd
    for c in coms:
        # tau is affine in m for a fixed CoM: tau(m) = tau(0) + m (tau(1) - tau(0)).
        at = {}
        for m in (0.0, 1.0):
            values = base.copy()
            values[0], values[1] = max(m, 1e-300), c
            robot = prior.plant(rr, {"link2": values})
            at[m] = np.array([robot.inverse_dynamics(*s) for s in zip(q, qd, qdd, strict=True)])
        slope = at[1.0] - at[0.0]
        residual = samples.tau[None] - at[0.0][None] - masses[:, None, None] * slope[None]
        ok = np.all(np.abs(residual) <= noise, axis=(1, 2))
        feasible_m += list(masses[ok])
        feasible_c += [c] * int(ok.sum())
    assert feasible_m, "the true point must be on the feasible side of the grid"
    mass = result.field_bound("link2", "mass").identified
    com = result.field_bound("link2", "com_x").identified
    assert mass[0] <= min(feasible_m) and max(feasible_m) <= mass[1]
    assert com[0] <= min(feasible_c) and max(feasible_c) <= com[1]
    step_m, step_c = masses[1] - masses[0], coms[1] - coms[0]
    assert mass[0] >= min(feasible_m) - step_m - 1e-6 and mass[1] <= max(feasible_m) + step_m + 1e-6
    assert com[1] - com[0] <= (max(feasible_c) - min(feasible_c) + 2 * step_c) * 1.5


def test_standard_parameters_against_brute_force_one_unknown(rr):
    """Only link 2's mass unknown: the consistent masses form an interval computable in closed
    form (tau affine in m); the LP reproduces it within its stated margin."""
    prior = parse_uncertainty({"links": {"link2": {"mass": [5, 10]}}}, rr, "<prior>")
    true = {"link2": prior.link_box("link2").nominal.copy()}
    true["link2"][0] = 8.1
    samples = record(prior.plant(rr, true), rr_trajectory(), np.linspace(0, 4, 80), 0.5,
                     np.random.default_rng(5))  # fmt: skip
    result = identify(rr, prior, samples, 0.5)
    zero, one = ({"link2": np.r_[m, prior.link_box("link2").nominal[1:]]} for m in (1e-300, 1.0))
    states = list(zip(samples.q, samples.qd, samples.qdd, strict=True))
    t0 = np.array([prior.plant(rr, zero).inverse_dynamics(*s) for s in states]).ravel()
    t1 = np.array([prior.plant(rr, one).inverse_dynamics(*s) for s in states]).ravel()
    slope, tau = t1 - t0, samples.tau.ravel()
    # |tau0 + m slope - tau| <= 0.5 for every row: an intersection of intervals in m.
    lo = np.where(slope > 0, (tau - 0.5 - t0) / slope, (tau + 0.5 - t0) / slope)
    hi = np.where(slope > 0, (tau + 0.5 - t0) / slope, (tau - 0.5 - t0) / slope)
    exact = (max(5.0, lo[np.abs(slope) > 1e-12].max()), min(10.0, hi[np.abs(slope) > 1e-12].min()))
    found = result.field_bound("link2", "mass").identified
    assert found[0] <= exact[0] and exact[1] <= found[1]
    assert found[0] >= exact[0] - 1e-4 and found[1] <= exact[1] + 1e-4


# ============================================================================ coverage
@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(seed=st.integers(0, 2**31 - 1), noise=st.floats(0.05, 2.0))
def test_coverage_over_random_plants_and_noise(rr, seed, noise):
    """The RR arm's shipped box (Table I): random rigid plants of the box, random noise within the
    bound: the true parameters lie in the identified box, which is narrower than the prior."""
    prior = urpc.load_uncertainty("rr_planar", rr)
    rng = np.random.default_rng(seed)
    true = {"link2": physical_point(prior.link_box("link2"), rng)}
    samples = record(prior.plant(rr, true), rr_trajectory(), np.linspace(0, 4, 100), noise, rng)
    result = identify(rr, prior, samples, noise)
    assert result.contains(true), result.misses(true)
    assert result.width_ratios()["mass"] < 0.5


@settings(
    max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(seed=st.integers(0, 2**31 - 1))
def test_coverage_with_drives(rr, seed):
    """Armature, viscous and Coulomb friction unknown with the link: truth inside, each drive
    parameter narrowed."""
    document = {
        "links": {"link2": {"mass": [5, 10], "com_x": [0.5, 0.525]}},
        "joints": {
            "joint1": {"armature": [0, 0.5], "damping": [0, 3], "friction": [0, 2]},
            "joint2": {"damping": [0, 3], "friction": [0, 2]},
        },
    }
    prior = parse_uncertainty(document, rr, "<prior>")
    rng = np.random.default_rng(seed)
    point = {"link2": physical_point(prior.link_box("link2"), rng)}
    point[JOINTS] = rng.uniform(prior.joints.lower, prior.joints.upper)
    samples = record(prior.plant(rr, point), rr_trajectory(), np.linspace(0, 4, 120), 0.5, rng)
    result = identify(rr, prior, samples, 0.5)
    assert result.contains(point), result.misses(point)
    for field in result.fields:
        if field.joint:
            assert field.width_ratio < 0.5, field


def test_estimated_derivatives_stay_sound(rr):
    """A record of q and tau only: qd, qdd from central differences with the trajectory's exact
    jerk and snap bounds; the truth stays inside, and the box is wider than with exact
    derivatives (the estimation error is paid for)."""
    prior = urpc.load_uncertainty("rr_planar", rr)
    rng = np.random.default_rng(11)
    true = {"link2": physical_point(prior.link_box("link2"), rng)}
    trajectory = rr_trajectory()
    times = np.arange(0, 4, 0.01)
    exact = record(prior.plant(rr, true), trajectory, times, 0.2, rng)
    bounds = DerivativeBounds(
        float(trajectory.derivative_bound(3).max()), float(trajectory.derivative_bound(4).max())
    )
    columns = {"t": exact.t, "q1": exact.q[:, 0], "q2": exact.q[:, 1],
               "tau1": exact.tau[:, 0], "tau2": exact.tau[:, 1]}  # fmt: skip
    path = __import__("pathlib").Path(__import__("tempfile").mkdtemp()) / "record.csv"
    path.write_text(write_csv(path, columns))
    estimated = load_samples([path], 2, bounds)
    assert estimated.count == exact.count - 2 and estimated.estimated
    assert np.all(np.abs(estimated.qdd - exact.qdd[1:-1]) <= estimated.acceleration_error)
    assert np.all(np.abs(estimated.qd - exact.qd[1:-1]) <= estimated.velocity_error)
    result = identify(rr, prior, estimated, 0.2)
    reference = identify(rr, prior, exact, 0.2)
    assert result.contains(true), result.misses(true)
    width = result.field_bound("link2", "mass").width_ratio
    assert reference.field_bound("link2", "mass").width_ratio <= width < 0.5


# ============================================================================ payload, UR5
def test_payload_mode_on_the_ur5_with_2_kg(ur5, tmp_path):
    prior = urpc.load_uncertainty("ur5", ur5)
    true = {"payload": np.array([2.0, 0.012, -0.008, 0.06, 0.003, 0.0, 0.004, 0.0, 0.0, 0.0035])}
    samples = record(prior.plant(ur5, true), ur5_trajectory(), np.linspace(0, 10, 400), 0.5,
                     np.random.default_rng(2))  # fmt: skip
    result = identify(ur5, prior, samples, 0.5, payload="tool0")
    assert result.contains(true), result.misses(true)
    assert result.rank == 10 and result.unknowns == 10
    mass = result.field_bound("payload", "mass")
    assert mass.identified[1] - mass.identified[0] < 0.01 * 3.0
    for axis in "xyz":
        assert result.field_bound("payload", f"com_{axis}").width_ratio < 0.1
    assert set(result.nominal_assumed) == {f"wrist_{i}_link.mass" for i in (1, 2, 3)}
    # The written file loads as urpc check reads it, and holds the truth.
    box = parse_uncertainty(yaml.safe_load(result.box_text("ur5")), ur5, "<written>")
    payload = box.link_box("payload")
    assert np.all(payload.lower <= true["payload"]) and np.all(true["payload"] <= payload.upper)
    assert box.link_box("wrist_1_link").upper[0] == prior.link_box("wrist_1_link").upper[0]


def test_payload_mode_with_mujoco_inverse_dynamics(ur5):
    """Torques from MuJoCo's inverse dynamics of the same URDF (an independent plant)."""
    mujoco = pytest.importorskip("mujoco")
    from urpc.sim.plants.mujoco_model import build_mujoco_model

    prior = urpc.load_uncertainty("ur5", ur5)
    true = {"payload": np.array([2.0, -0.01, 0.015, 0.04, 0.004, 0.0, 0.003, 0.0, 0.0, 0.0045])}
    plant = prior.plant(ur5, true)
    model = build_mujoco_model(plant)
    data = mujoco.MjData(model)
    times = np.linspace(0, 10, 300)
    q, qd, qdd = ur5_trajectory().evaluate(times)
    tau = np.empty_like(q)
    for k in range(times.size):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(model, data)
        tau[k] = data.qfrc_inverse
    rng = np.random.default_rng(4)
    tau += rng.uniform(-0.5, 0.5, tau.shape)
    samples = Samples.from_arrays(times, q, qd, qdd, tau, source="<mujoco>")
    result = identify(ur5, prior, samples, 0.5 + 1e-6, payload="tool0")
    assert result.contains(true), result.misses(true)
    assert result.width_ratios()["mass"] < 0.01


def test_infeasible_data_are_refused(rr):
    prior = urpc.load_uncertainty("rr_planar", rr)
    rng = np.random.default_rng(0)
    samples = record(prior.plant(rr, None), rr_trajectory(), np.linspace(0, 4, 50), 1.0, rng)
    wrong = Samples.from_arrays(samples.t, samples.q, samples.qd, samples.qdd, -samples.tau)
    with pytest.raises(urpc.InputError, match="no parameter vector"):
        identify(rr, prior, wrong, 1.0)


def test_urpc_identify_is_callable_both_ways(rr):
    import urpc.identify as subpackage

    prior = urpc.load_uncertainty("rr_planar", rr)
    samples = record(prior.plant(rr, None), rr_trajectory(), np.linspace(0, 4, 40), 1.0,
                     np.random.default_rng(1))  # fmt: skip
    assert urpc.identify(rr, prior, samples, 1.0).samples == 40
    assert subpackage(rr, prior, samples, 1.0).samples == 40


def test_a_fourier_excitation_has_a_sound_jerk_bound_and_can_be_certified(rr):
    """The jerk bound holds central differences of qdd at random times; with it the
    certificate covers an excitation run (it refused the class before)."""
    rng = np.random.default_rng(4)
    trajectory = FourierTrajectory(np.array([0.3, -0.2]), rng.normal(0, 0.1, (2, 3)),
                                   rng.normal(0, 0.1, (2, 3)), 0.4)  # fmt: skip
    bound = trajectory.jerk_bound(np.zeros(1), np.ones(1))[0]
    h = 1e-4
    for t in rng.uniform(0, 10, 200):
        jerk = (trajectory.evaluate(t + h)[2] - trajectory.evaluate(t - h)[2]) / (2 * h)
        assert np.all(np.abs(jerk) <= bound * (1 + 1e-6))
    box = urpc.load_uncertainty("rr_planar", rr)
    controller = urpc.synthesize(rr, box, 1e-2, sample_period=5e-4)
    certificate = urpc.certify(controller, trajectory, duration=2.0, disturbance_bound=1.0)
    assert certificate.max_sample_period > 0, certificate.summary()
