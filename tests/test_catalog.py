"""Robots and shipped data by name: from any folder, floating-base robots refused."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import urpc
from urpc.errors import InputError
from urpc.model.catalog import example_robot_data_robots, resolve_robot, shipped_data, shipped_file

ROOT = Path(__file__).resolve().parents[1]


def test_shipped_files_by_name_and_paths_unchanged(tmp_path):
    assert shipped_file("rr_planar", "uncertainty.yaml").parts[-2:] == (
        "rr_planar",
        "uncertainty.yaml",
    )
    assert shipped_file("rr_planar", "true_parameters.yaml").name == "true_parameters.yaml"
    assert shipped_file("ur5/heavy_payload", "true_parameters.yaml").parts[-2:] == (
        "ur5",
        "heavy_payload.yaml",
    )
    mine = tmp_path / "rr_planar"  # a file named like a robot wins
    mine.write_text("links: {}\n")
    assert shipped_file(mine, "uncertainty.yaml") == mine
    assert shipped_file("missing.yaml", "uncertainty.yaml") == Path("missing.yaml")


@pytest.mark.parametrize(
    ("source", "default", "message"),
    [
        ("ur10", "uncertainty.yaml", "urpc init ur10 --out box.yaml"),
        ("ur5", "true_parameters.yaml", "it ships: ur5/heavy_payload"),
        ("rr_planr", "uncertainty.yaml", "did you mean 'rr_planar'"),
    ],
)
def test_shipped_file_errors_say_what_exists(source, default, message):
    with pytest.raises(InputError, match=message):
        shipped_file(source, default, "file")


def test_readme_api_example_runs_from_any_folder(tmp_path):
    code = """
import numpy as np
import urpc
from urpc.trajectories import PaperTrajectory

robot = urpc.load_robot("rr_planar")
box = urpc.load_uncertainty("rr_planar", robot)
true = urpc.load_parameter_point("rr_planar", robot, box)
scenario = urpc.load_scenario("rr_planar/s2_ic1")
controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)
result = urpc.simulate(box.plant(robot, true), controller, PaperTrajectory(),
                       duration=0.2, q0=np.zeros(2), disturbance_bound=10.0)
print(true["link2"][0], scenario.name, result.metrics["final_error"] > 0)
"""
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["10.0", "s2_ic1", "True"]


def test_api_by_name_equals_api_by_path(rr):
    by_name = urpc.load_uncertainty("rr_planar", rr)
    by_path = urpc.load_uncertainty(ROOT / "robots" / "rr_planar" / "uncertainty.yaml", rr)
    assert np.array_equal(by_name.links[0].upper, by_path.links[0].upper)
    point = urpc.load_parameter_point("rr_planar", rr, by_name)
    assert point.links["link2"][0] == 10.0


def test_shipped_data_of_the_robots_that_ship_it():
    for name in ("rr_planar", "ur5", "panda"):
        data = shipped_data(name)
        assert data["uncertainty"] and data["scenarios"]
    assert not any(shipped_data("ur10").values())


def test_floating_base_robots_are_marked_and_refused():
    erd = example_robot_data_robots()
    for name in ("anymal", "go1", "talos_full_v2", "solo12", "tiago_pro"):
        assert erd[name].floating_base, name
    for name in ("ur10", "ur5", "panda", "kinova", "z1", "xarm7", "talos_left_arm", "so100"):
        assert not erd[name].floating_base, name
    with pytest.raises(InputError, match="floating-base"):
        resolve_robot("anymal")
    assert resolve_robot(erd["anymal"].urdf).origin == "file"  # a path is still accepted
