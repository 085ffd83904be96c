"""General arms: the UR5 and Panda scenarios shipped in robots/<robot>/scenarios.

The full 8 s runs take 4-5 s each; the tests run shortened ones. With the paper's law unchanged,
the 1 kHz runs of the Panda and of the UR5's heaviest corner diverge: the sampled loop is unstable
once ``(kappa ||rho|| + phi) T`` exceeds twice the smallest eigenvalue of ``M(q)`` (a wrist mode),
see ``test_the_panda_failure_is_the_zero_order_hold_gain_limit``. The scenarios therefore run the
implicit sampled-data law (the default for sampled scenarios, :mod:`urpc.control.interval`).
"""

from __future__ import annotations

import numpy as np
import pytest

from urpc.errors import SimulationError
from urpc.studies.scenario import build, build_controller, load_scenario, run_scenario

SCENARIOS = ("ur5/sampled", "ur5/heavy_payload", "panda/sampled", "panda/heavy_payload")


@pytest.mark.parametrize("name", SCENARIOS)
def test_scenarios_describe_the_issue_setting(name):
    scenario = load_scenario(name)
    setup = build(scenario)
    assert scenario.sample_period == 1e-3
    assert scenario.epsilon == 1e-2
    assert scenario.disturbance == 2.0
    assert setup.box.disturbance_bound is None  # unknown to the controller: Theorem 2
    assert scenario.controller == "interval" and not any(scenario.options.values())
    payload = setup.box.link_box("payload")
    assert (payload.lower[0], payload.upper[0]) == (0.0, 3.0)  # 0-3 kg at the flange
    if name.startswith("panda"):
        assert setup.robot.dof == 7  # fingers locked
        assert not any("finger" in joint for joint in setup.robot.joint_names)
    else:
        assert setup.robot.dof == 6
    # The generic trajectory stays inside the joint limits.
    t = np.linspace(0.0, scenario.duration, 401)
    q, _, _ = setup.trajectory.evaluate(t)
    lower, upper = setup.robot.position_limits
    assert np.all(q >= lower) and np.all(q <= upper)
    if "heavy" in name:  # the hard corner: 3 kg at the far end of the box
        np.testing.assert_allclose(setup.true_point.links["payload"][:4], [3.0, 0.02, 0.02, 0.1])


def test_ur5_meets_epsilon_with_the_default_settings():
    scenario = load_scenario("ur5/sampled").with_overrides(duration=2.0)
    result = run_scenario(scenario)
    metrics = result.metrics
    assert metrics["met"]
    assert metrics["final_error"] < scenario.epsilon
    assert np.abs(result.disturbance).max() > 0  # the disturbance is there


@pytest.mark.parametrize("name", ["panda/sampled", "ur5/heavy_payload"])
def test_scenarios_meet_epsilon_at_1_khz(name):
    scenario = load_scenario(name).with_overrides(duration=1.0)
    assert run_scenario(scenario).metrics["met"]


def test_with_the_paper_law_the_panda_diverges_at_1_khz():
    paper_law = load_scenario("panda/sampled").with_overrides(
        duration=0.1, controller_options={"interval": {"sampled_law": "paper"}}
    )
    with pytest.raises(SimulationError, match="diverged"):
        run_scenario(paper_law)


def test_the_panda_failure_is_the_zero_order_hold_gain_limit():
    """Under a held torque ``u = -D r``, a mode of inertia ``m`` evolves as
    ``v+ = (1 - D T / m) v``: unstable for ``D T / m > 2``. The interval law's gain on ``r`` is
    ``D = kappa ||rho|| + phi``; on the Panda at rest with the default gains it already exceeds
    ``2 lambda_min(M) / T`` at 1 kHz, and is well below it at 10 kHz, where the run meets epsilon.
    """
    scenario = load_scenario("panda/sampled")
    setup = build(scenario)
    paper_law = scenario.with_overrides(controller_options={"interval": {"sampled_law": "paper"}})
    controller = build_controller(build(paper_law))
    reference = setup.trajectory.reference(0.0)
    state = controller.initial_state()
    controller.output(0.0, setup.q0, setup.qd0, reference, state)
    phi, kappa = controller.gains(state)
    gain = kappa * controller.last_rho_norm + phi  # [N m s/rad]
    smallest_inertia = np.linalg.eigvalsh(setup.plant.M(setup.q0)).min()  # [kg m^2]
    assert gain * 1e-3 / smallest_inertia > 2.0
    assert gain * 1e-4 / smallest_inertia < 1.0
    faster = scenario.with_overrides(sample_period=1e-4, duration=0.3)
    assert run_scenario(faster).metrics["met"]
