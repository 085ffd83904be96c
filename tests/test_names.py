"""The valid names, written once in urpc.names: every one of them builds what it names, and the
module is light enough for the command line to read at parse time."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from urpc import names
from urpc.bounds import make_bound
from urpc.control.synthesis import synthesize
from urpc.errors import InputError
from urpc.sim.plants import make_plant
from urpc.studies.scenario import build, build_controller, load_scenario, parse_scenario


def test_every_bound_method_name_encloses_the_nominal_torque(rr, rr_box):
    state = (np.array([0.1, 0.2]), np.ones(2), np.ones(2), np.zeros(2))
    for name in names.BOUND_METHODS:
        lower, upper = make_bound(name, rr, rr_box).enclose(*state)
        assert np.all(lower <= 0) and np.all(upper >= 0), name  # w = 0 at the nominal point
    with pytest.raises(InputError, match="hull, vertex, rigorous"):
        make_bound("exact", rr, rr_box)


def test_every_plant_name_steps_the_robot(rr):
    for name in names.PLANT_BACKENDS:
        if name == "mujoco":
            pytest.importorskip("mujoco")
        plant = make_plant(name, rr)
        plant.reset(np.zeros(2), np.zeros(2))
        q, _ = plant.step(np.zeros(2), 1e-3)
        assert q.shape == (2,) and plant.kind == name


def test_every_controller_and_sampled_law_name_builds_its_law(rr, rr_box):
    setup = build(load_scenario("rr_planar/s3_ic1").with_overrides(duration=0.01))
    assert [build_controller(setup, name).name for name in names.CONTROLLERS] == list(
        names.CONTROLLERS
    )
    for law in names.SAMPLED_LAWS:
        controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law=law)
        assert controller.sampled_law == law and controller.implicit == (law == "implicit")


def test_every_trajectory_kind_builds_a_reference_in_a_scenario(tmp_path):
    from conftest import RR_DIR

    samples = tmp_path / "traj.csv"
    t = [0.1 * k for k in range(11)]
    samples.write_text("t,q1,q2\n" + "".join(f"{x},{0.1 * x},{-0.05 * x}\n" for x in t))
    options = {
        "file": {"kind": "file", "path": str(samples)},
        "waypoints": {"kind": "waypoints", "points": [[0, 0], [0.2, -0.1], [0, 0]]},
    }
    for kind in names.TRAJECTORY_KINDS:
        document = {"robot": "rr_planar", "uncertainty": str(RR_DIR / "uncertainty.yaml")}
        trajectory = options.get(kind, kind)
        setup = build(parse_scenario({**document, "trajectory": trajectory}))
        assert setup.trajectory.reference(0.5).q.shape == (2,), kind


def test_the_names_module_imports_nothing():
    """urpc.names adds no module of its own beyond the package (import urpc is light)."""
    code = (
        "import sys, urpc; before = set(sys.modules); import urpc.names; "
        "print(sorted(set(sys.modules) - before))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "['urpc.names']"
