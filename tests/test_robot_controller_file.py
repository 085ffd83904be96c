"""Save and load a controller: a plain versioned JSON file, bit-identical torque, refusals."""

import json
import shutil

import numpy as np
import pytest

import urpc
from urpc.studies.scenario import build, build_controller, load_scenario


@pytest.mark.parametrize("name", ["rr_planar/s3_ic1", "ur5/sampled"])
def test_loaded_controller_gives_bit_identical_torque(name, tmp_path):
    setup = build(load_scenario(name))
    controller = build_controller(setup, "interval")
    path = controller.save(tmp_path / "controller.json")
    document = json.loads(path.read_text())
    assert document["format"] == "urpc-controller" and document["version"] == 1
    loaded = urpc.load_controller(path)
    rng = np.random.default_rng(3)
    state = controller.initial_state()
    for k in range(20):
        t = 0.37 * k
        reference = setup.trajectory.reference(t)
        q = reference.q + 0.02 * rng.standard_normal(setup.robot.dof)
        qd = reference.qd + 0.1 * rng.standard_normal(setup.robot.dof)
        assert np.array_equal(
            controller.output(t, q, qd, reference, state), loaded.output(t, q, qd, reference, state)
        )
        state = controller.advance(t, q, qd, reference, state + 0.01)


def test_a_changed_urdf_or_version_is_refused(tmp_path):
    robot = urpc.load_robot("rr_planar")
    urdf = tmp_path / "rr.urdf"
    shutil.copy(robot.urdf_path, urdf)
    box_file = tmp_path / "box.yaml"
    shutil.copy(urpc.load_uncertainty("rr_planar", robot).source, box_file)
    mine = urpc.load_robot(urdf)
    controller = urpc.synthesize(
        mine, urpc.load_uncertainty(box_file, mine), 1e-2, sample_period=1e-3
    )
    path = controller.save(tmp_path / "c.json")
    urpc.load_controller(path)  # fine as saved
    urdf.write_text(urdf.read_text().replace('effort="1000"', 'effort="999"', 1))
    with pytest.raises(urpc.InputError, match="changed since the controller was saved"):
        urpc.load_controller(path)
    document = json.loads(path.read_text())
    document["version"] = 99
    path.write_text(json.dumps(document))
    with pytest.raises(urpc.InputError, match="version 99"):
        urpc.load_controller(path)


def test_a_loaded_controller_saves_again_from_its_embedded_box(tmp_path):
    """Saved, loaded, the box file deleted, saved again: the second file embeds the same box
    (not the file, which is gone) and its controller gives the first's torque bit for bit; a box
    parsed from a document in code saves too."""
    robot = urpc.load_robot("rr_planar")
    shutil.copy(urpc.load_uncertainty("rr_planar", robot).source, tmp_path / "box.yaml")
    box = urpc.load_uncertainty(tmp_path / "box.yaml", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    first = urpc.load_controller(controller.save(tmp_path / "first.json"))
    (tmp_path / "box.yaml").unlink()
    second = urpc.load_controller(first.save(tmp_path / "second.json"))
    documents = [
        json.loads((tmp_path / f"{n}.json").read_text())["box"] for n in ("first", "second")
    ]
    assert documents[0] == documents[1]
    reference = urpc.PaperTrajectory().reference(0.5)
    q, qd = reference.q + 0.01, reference.qd - 0.1
    state = controller.initial_state()
    assert np.array_equal(
        controller.output(0.5, q, qd, reference, state), second.output(0.5, q, qd, reference, state)
    )
    parsed = urpc.parse_uncertainty({"links": {"link2": {"mass": "10%"}}}, robot)
    in_code = urpc.synthesize(robot, parsed, 1e-2, sample_period=1e-3)
    loaded = urpc.load_controller(in_code.save(tmp_path / "in_code.json"))
    assert loaded.bound.box.source is None
