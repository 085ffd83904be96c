"""The control loop in lock step with the virtual arm (no wall clock): it tracks like the
simulator, its log saves like simulate's, a NaN state stops it, and the delayed law meets epsilon
on vertex plants of the box with a one-sample delay."""

import numpy as np
import pytest

import urpc
from urpc.robot.loop import ControlLoop
from urpc.robot.runner import run
from urpc.robot.safety import SafetyLayer
from urpc.robot.virtual import ArmOptions, FakeClock, LockstepRobot, VirtualArm
from urpc.robot.watchdog import Watchdog
from urpc.sim.results import SimulationResult


@pytest.fixture(scope="module")
def rr():
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    return robot, box


def lockstep(plant, controller, robot, duration, options=None, **safety):
    clock = FakeClock()
    arm = VirtualArm(plant, 1e-3, options or ArmOptions())
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    layer = SafetyLayer.for_robot(robot, 1e-3, **safety)
    report = run(
        LockstepRobot(arm, clock, 1e-4), loop, layer, Watchdog(1e-3), duration, clock=clock
    )
    return report, loop, layer


def test_loop_matches_the_sampled_simulator(rr):
    robot, box = rr
    plant = box.plant(robot, urpc.load_parameter_point("rr_planar", robot, box))
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    report, loop, _ = lockstep(plant, controller, robot, 0.5)
    assert report.ok and report.cycles == 501
    simulated = urpc.simulate(
        plant, controller, urpc.PaperTrajectory(), duration=0.5, q0=np.zeros(2)
    )
    logged = loop.series()
    # Same law, same plant; the arm integrates with 2 RK4 steps per period, the simulator 10.
    assert np.max(np.abs(logged["q"] - simulated.q)) < 1e-6
    assert np.max(np.abs(logged["torque"] - simulated.torque)) < 1e-2 * np.max(
        np.abs(simulated.torque)
    )


def test_log_saves_like_simulate(rr, tmp_path):
    robot, box = rr
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    report, loop, layer = lockstep(box.plant(robot, {}), controller, robot, 0.2)
    result = loop.result(scenario="lockstep", torque_limit=layer.torque_limit)
    result.save(tmp_path)
    back = SimulationResult.load(tmp_path)
    assert np.array_equal(back.q, loop.series()["q"]) and back.sample_period == 1e-3
    assert {"p50", "p99", "p99_9", "max"} <= set(result.info["step_time"])
    assert loop.last["rho_norm"] > 0 and np.isfinite(loop.last["phi"])
    loop.reset()
    assert loop.samples == 0 and np.array_equal(loop.state, controller.initial_state())


def test_torque_above_the_limit_is_clipped_before_the_arm(rr):
    robot, box = rr
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    report, loop, layer = lockstep(
        box.plant(robot, {}), controller, robot, 0.3, torque_limit=[60.0, 20.0]
    )
    series = loop.series()
    assert layer.counts["torque_limit"] > 0
    assert np.all(np.abs(series["torque_sent"]) <= [60.0, 20.0])
    assert np.any(np.abs(series["torque"]) > [60.0, 20.0])
    assert int(series["clipped"].sum()) == layer.counts["torque_limit"]


def test_nan_state_stops_the_loop_with_one_message(rr):
    robot, box = rr
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)

    class Broken(LockstepRobot):
        def read_state(self, timeout):
            state = super().read_state(timeout)
            if state.seq == 30:
                state.q[1] = np.nan
            return state

    clock = FakeClock()
    arm = VirtualArm(box.plant(robot, {}), 1e-3)
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    layer = SafetyLayer.for_robot(robot, 1e-3)
    report = run(Broken(arm, clock, 1e-4), loop, layer, Watchdog(1e-3), 1.0, clock=clock)
    assert report.ending == "fault" and report.cycles == 30
    assert report.message.startswith("non-finite state at t = 0.0300 s")
    assert layer.counts["non_finite_state"] == 1 and arm.braked


@pytest.mark.parametrize("controller_period", [1e-4, 2e-3])
def test_a_controller_for_another_period_than_the_robots_is_stopped(rr, controller_period):
    """A 10 kHz (or 500 Hz) law on a 1 kHz arm: after 50 samples the robot's period, from its
    states' times, is compared with the law's; the run stops with the safe command and says
    both periods."""
    robot, box = rr
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=controller_period)
    clock = FakeClock()
    arm = VirtualArm(box.plant(robot, box.vertex(0)), 1e-3, ArmOptions())
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    layer = SafetyLayer.for_robot(robot, controller_period)
    watchdog = Watchdog(controller_period, late_budget=10**6, deadline=1.0)
    report = run(LockstepRobot(arm, clock), loop, layer, watchdog, 1.0, clock=clock)
    assert report.ending == "fault" and report.cycles == 50, report
    assert "the robot's period is 1 ms" in report.message
    assert f"the controller's {controller_period * 1e3:g} ms" in report.message


def test_a_controller_for_the_robots_period_is_not_stopped_by_the_period_check(rr):
    report, _, _ = lockstep(*_vertex_plant_controller(rr), rr[0], 0.2)
    assert report.ending == "completed", report


def _vertex_plant_controller(rr):
    robot, box = rr
    return box.plant(robot, box.vertex(0)), urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)


def test_delayed_law_state_and_save(rr, tmp_path):
    robot, box = rr
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3, delay=1)
    assert controller.delay == 1 and controller.n_states == 3
    with pytest.raises(urpc.InputError, match="valid: 0, 1"):
        urpc.synthesize(robot, box, 1e-2, sample_period=1e-3, delay=2)
    controller.save(tmp_path / "c.json")
    loaded = urpc.load_controller(tmp_path / "c.json")
    reference = urpc.PaperTrajectory().reference(0.7)
    state = np.array([0.01, 3.0, -4.0])
    q = reference.q + 0.004
    assert np.array_equal(
        controller.output(0.7, q, reference.qd, reference, state),
        loaded.output(0.7, q, reference.qd, reference, state),
    )
    advanced = controller.advance(0.7, q, reference.qd, reference, state)
    assert np.array_equal(advanced[1:], controller.output(0.7, q, reference.qd, reference, state))


@pytest.mark.parametrize("side", ["lower", "upper"])
def test_delayed_law_meets_epsilon_on_vertex_plants_with_a_one_sample_delay(rr, side):
    """Vertex plants of Table I (the lightest and the heaviest link 2) behind a one-sample delay,
    with a 10 N m disturbance: the delayed law meets epsilon = 1e-2 by the last quarter."""
    robot, box = rr
    link = box.uncertain_links[0]
    point = {link.link: np.array(getattr(link, side), dtype=float)}
    plant = box.plant(robot, point)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3, delay=1)
    report, loop, _ = lockstep(plant, controller, robot, 2.0, ArmOptions(delay=1, disturbance=10.0))
    assert report.ok
    metrics = loop.result().metrics
    assert metrics["met"], metrics["final_error"]


# ---------------------------------------------------------------- the controller's own diagnostics
def _drive(loop, steps=40):
    """``steps`` loop steps 3 mrad off the paper's trajectory (no plant: the log is the point)."""
    trajectory = urpc.PaperTrajectory()
    for k in range(steps):
        reference = trajectory.reference(k * 1e-3)
        loop.step(k * 1e-3, reference.q + 3e-3, reference.qd)
    return loop


def _loop_and_simulation(controller, steps=40):
    loop = _drive(ControlLoop(controller, urpc.PaperTrajectory(), period=1e-3, epsilon=1e-2), steps)
    robot = urpc.load_robot("rr_planar")
    simulated = urpc.simulate(
        robot, controller, urpc.PaperTrajectory(), duration=(steps - 1) * 1e-3,
        q0=urpc.PaperTrajectory().reference(0.0).q + 3e-3, epsilon=1e-2,
    )  # fmt: skip
    return loop, simulated


def _r_alpha():
    from urpc.control.r_alpha import PAPER_BETAS, synthesize_r_alpha

    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    return synthesize_r_alpha(robot, box, betas=PAPER_BETAS, sample_period=1e-3)


def _interval(delay=0):
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    return urpc.synthesize(robot, box, 1e-2, sample_period=1e-3, delay=delay)


@pytest.mark.parametrize("kind", ["interval", "delayed", "loaded", "r-alpha"])
def test_loop_logs_exactly_the_controllers_declared_diagnostics(kind, tmp_path):
    """Whatever the law, the loop's log, ``last`` and saved result carry exactly the names of the
    controller's ``diagnostic_units`` (with those units, as ``urpc simulate`` writes them); a law
    that declares none gets no diagnostic columns at all, not empty or NaN ones."""
    if kind == "r-alpha":
        controller = _r_alpha()
    elif kind == "loaded":
        _interval().save(tmp_path / "c.json")
        controller = urpc.load_controller(tmp_path / "c.json")
    else:
        controller = _interval(delay=1 if kind == "delayed" else 0)
    declared = dict(type(controller).diagnostic_units)
    assert declared == ({} if kind == "r-alpha" else {"phi": "N m s/rad", "kappa": "s/rad"})
    loop, simulated = _loop_and_simulation(controller)
    result = loop.result()
    assert set(result.diagnostics) == set(declared) == set(simulated.diagnostics)
    assert result.info.get("diagnostic_units") == simulated.info.get("diagnostic_units")
    assert result.info.get("diagnostic_units", {}) == declared
    series = loop.series()
    for name in declared:
        assert np.all(np.isfinite(series[name])) and np.isfinite(loop.last[name])
    rho = kind != "r-alpha"  # the interval law reports ||rho|| (last_rho_norm); r-alpha does not
    assert ("rho_norm" in series) is rho and ("rho_norm" in loop.last) is rho
    assert set(loop.last) == {"e", *declared, *(("rho_norm",) if rho else ()), "step_time"}
    assert not {"phi", "kappa"} & (set(series) - set(declared))
    result.save(tmp_path / "run")
    header = (tmp_path / "run" / "result.csv").read_text().splitlines()[0].split(",")
    assert [c for c in header if c in ("phi", "kappa")] == list(declared)
    back = SimulationResult.load(tmp_path / "run")
    assert set(back.diagnostics) == set(declared)
    assert back.info.get("diagnostic_units", {}) == declared


def test_loop_logs_a_controllers_own_diagnostic_names_sample_by_sample():
    """A law with diagnostics of its own names: the loop logs them, evaluated at each sample's
    state as the simulator does (here the state counts the samples), and nothing else."""
    from urpc.control.base import Controller

    class Counting(Controller):
        name = "counting"
        diagnostic_units = {"samples_seen": "1", "half": "s"}
        n_states = 1
        sample_period = 1e-3

        def output(self, t, q, qd, reference, state):
            return np.zeros(len(q))

        def advance(self, t, q, qd, reference, state):
            return state + 1.0

        def diagnostics(self, state):
            return {"samples_seen": float(state[0]), "half": 0.5 * float(state[0])}

    loop = _drive(ControlLoop(Counting(), urpc.PaperTrajectory(), epsilon=1e-2), 25)
    series = loop.series()
    assert np.array_equal(series["samples_seen"], np.arange(25.0))
    assert np.array_equal(series["half"], 0.5 * np.arange(25.0))
    assert set(loop.last) == {"e", "samples_seen", "half", "step_time"}
    result = loop.result()
    assert set(result.diagnostics) == {"samples_seen", "half"}
    assert result.info["diagnostic_units"] == {"samples_seen": "1", "half": "s"}
    assert "phi" not in series and "rho_norm" not in series

    class Clashing(Counting):
        diagnostic_units = {"q": "rad"}

    with pytest.raises(urpc.InputError, match="field 'diagnostic_units'.*'q'"):
        ControlLoop(Clashing(), urpc.PaperTrajectory())

    class Continuous(Counting):
        sample_period = None

    with pytest.raises(ValueError, match="the loop needs a period"):
        ControlLoop(Continuous(), urpc.PaperTrajectory())
    assert ControlLoop(Continuous(), urpc.PaperTrajectory(), period=1e-3).period == 1e-3


# ---------------------------------------------------------------- the velocity filter
def _echo_loop(**options):
    """A loop whose controller commands the velocity it is given: its torque is what the
    controller saw."""
    from urpc.control.base import Controller

    class Echo(Controller):
        name = "echo"
        sample_period = 1e-3

        def output(self, t, q, qd, reference, state):
            return np.array(qd, dtype=float)

    return ControlLoop(Echo(), urpc.PaperTrajectory(), epsilon=1e-2, **options)


def _feed(loop, velocities, times=None):
    times = np.arange(len(velocities)) * loop.period if times is None else times
    q = np.zeros(loop.dof)
    return np.array([loop.step(t, q, qd) for t, qd in zip(times, velocities, strict=True)])


def test_velocity_filter_step_response_is_the_first_order_closed_form():
    """A velocity step (0 -> (1, -2) at t = 0 after one sample at rest) through the 50 Hz filter:
    the controller sees (1 - exp(-2 pi 50 t)) (1, -2) at every sample, the continuous first-order
    filter's response; the log keeps the measured step as qd."""
    f_c, T = 50.0, 1e-3
    loop = _echo_loop(velocity_filter_hz=f_c)
    steps = 200
    velocities = np.vstack([np.zeros((1, 2)), np.tile([1.0, -2.0], (steps, 1))])
    seen = _feed(loop, velocities)
    t = np.arange(steps + 1) * T
    expected = (1.0 - np.exp(-2 * np.pi * f_c * t))[:, None] * np.array([1.0, -2.0])
    assert np.max(np.abs(seen - expected)) < 1e-12
    series = loop.series()
    assert np.array_equal(series["qd"], velocities) and np.array_equal(series["qd_filtered"], seen)
    assert loop.result().info["velocity_filter_hz"] == f_c


def test_velocity_filter_lags_a_ramp_by_its_time_constant():
    """A velocity ramp (constant acceleration c) lags behind by the closed form of the discrete
    first-order filter, e_k = e (1 - (1 - a)^k) with e = c T (1 - a) / a, a = 1 - exp(-2 pi f_c T):
    c (1 / (2 pi f_c) - T / 2), the continuous filter's lag less half a sample: the velocity
    error the filter adds."""
    f_c, T, c = 20.0, 1e-3, 3.0
    loop = _echo_loop(velocity_filter_hz=f_c)
    k = np.arange(400)
    ramp = c * k * T
    seen = _feed(loop, np.column_stack([ramp, -ramp]))[:, 0]
    a = 1.0 - np.exp(-2 * np.pi * f_c * T)
    lag = c * T * (1 - a) / a
    assert np.max(np.abs((ramp - seen) - lag * (1 - (1 - a) ** k))) < 1e-12
    assert lag == pytest.approx(c * (1 / (2 * np.pi * f_c) - T / 2), rel=2e-3)


def test_velocity_filter_uses_the_time_between_samples_and_resets():
    """A lost sample is a step of two periods (a = 1 - exp(-2 pi f_c 2T)); reset() forgets the
    filter's state; without a filter the controller sees the measured qd itself."""
    f_c = 30.0
    loop = _echo_loop(velocity_filter_hz=f_c)
    seen = _feed(loop, [np.zeros(2), np.ones(2), np.ones(2)], times=[0.0, 2e-3, 3e-3])
    y1 = 1 - np.exp(-2 * np.pi * f_c * 2e-3)
    assert seen[1] == pytest.approx([y1, y1], abs=1e-15)
    assert seen[2] == pytest.approx(1 - (1 - y1) * np.exp(-2 * np.pi * f_c * 1e-3), abs=1e-15)
    loop.reset()
    assert np.array_equal(_feed(loop, [np.full(2, 5.0)]), [[5.0, 5.0]])  # y_0 = qd_0 again
    plain = _echo_loop()
    velocities = np.random.default_rng(0).standard_normal((20, 2))
    assert np.array_equal(_feed(plain, velocities), velocities)
    assert "qd_filtered" not in plain.series()
    assert "velocity_filter_hz" not in plain.result().info


@pytest.mark.parametrize("bad", [0.0, -5.0, float("nan"), float("inf"), "fast"])
def test_velocity_filter_refuses_a_bad_cutoff_naming_the_field(bad):
    with pytest.raises(urpc.InputError, match="field 'velocity_filter_hz'") as info:
        _echo_loop(velocity_filter_hz=bad)
    assert "\n" not in str(info.value)


def test_velocity_filter_white_noise_variance_is_the_closed_form():
    """White noise of unit variance leaves the filter with variance a / (2 - a) (the sum of the
    squared impulse response a (1 - a)^k), here at 100 Hz and 1 kHz: 0.304. 4000 independent
    channels through filter_velocity, past the transient."""
    f_c, T = 100.0, 1e-3
    loop = _echo_loop(velocity_filter_hz=f_c)
    noise = np.random.default_rng(1).standard_normal((600, 4000))
    out = np.array([loop.filter_velocity(k * T, x) for k, x in enumerate(noise)])[100:]
    a = 1.0 - np.exp(-2 * np.pi * f_c * T)
    assert np.var(out) == pytest.approx(a / (2 - a), rel=0.02)


def test_run_refuses_a_bad_velocity_filter_in_one_line(capsys):
    from urpc.__main__ import main

    argv = ["run", "rr_planar/s3_ic1", "--robot-address", "udp://127.0.0.1:9"]
    assert main([*argv, "--velocity-filter", "0"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "--velocity-filter" in err


@pytest.mark.parametrize("asked", ["flag", "scenario"])
def test_run_refuses_a_saved_controller_whose_delay_is_not_the_one_asked_for(
    asked, tmp_path, capsys
):
    """A saved law's delay cannot change: ``--delay 1`` (or a scenario whose interval options say
    ``delay: 1``) with a saved undelayed controller is one error naming the field, before any
    robot is contacted (port 9 has none), instead of running the undelayed law silently."""
    import yaml
    from conftest import RR_DIR

    from urpc.__main__ import main

    saved = _interval(delay=0).save(tmp_path / "controller.json")
    scenario, extra = "rr_planar/s3_ic1", ["--delay", "1"]
    if asked == "scenario":
        shipped = RR_DIR / "scenarios" / "s3_ic1.yaml"
        data = yaml.safe_load(shipped.read_text())
        for key in ("uncertainty", "true_parameters"):
            data[key] = str((shipped.parent / data[key]).resolve())
        data["controller_options"] = {"interval": {"delay": 1}}
        scenario, extra = str(tmp_path / "delayed.yaml"), []
        (tmp_path / "delayed.yaml").write_text(yaml.safe_dump(data))
    argv = ["run", scenario, "--robot-address", "udp://127.0.0.1:9", "--controller", str(saved)]
    assert main([*argv, *extra]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert "predicts over 0 sample(s)" in err and "not the 1 asked for" in err and "delay" in err


def test_run_refuses_a_saved_controller_whose_law_is_not_the_one_asked_for(tmp_path, capsys):
    """``--sampled-law paper`` with a saved implicit-law controller: one error naming the field,
    before any robot is contacted, instead of running the saved law silently."""
    from urpc.__main__ import main

    saved = _interval(delay=0).save(tmp_path / "controller.json")
    argv = ["run", "rr_planar/s3_ic1", "--robot-address", "udp://127.0.0.1:9"]
    assert main([*argv, "--controller", str(saved), "--sampled-law", "paper"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert "runs the implicit law, not the paper one" in err and "sampled_law" in err
