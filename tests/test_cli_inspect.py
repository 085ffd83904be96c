"""``urpc robots`` and ``urpc check`` (text output; the JSON is tested in test_cli.py)."""

from __future__ import annotations

import json

from urpc.cli import main


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_robots_shows_shipped_data_and_marks_floating_base(capsys):
    code, out, _ = _run(capsys, "robots")
    assert code == 0
    shipped, fixed, floating = out.split("\n\n")
    for name in ("rr_planar", "ur5", "panda"):
        assert f"\n  {name} " in shipped
    assert "rr_planar/s2_ic1" in shipped and "ur5/heavy_payload" in shipped
    assert "urpc init" in fixed and "ur10" in fixed.split() and "kinova" in fixed.split()
    assert "Not supported" in floating
    for name in ("anymal", "go1", "talos_full_v2"):
        assert name in floating.split() and name not in fixed.split()


def test_robots_json_lists_shipped_and_not_supported(capsys):
    code, out, _ = _run(capsys, "robots", "--json")
    listing = json.loads(out)
    assert code == 0 and set(listing["shipped"]) == {"rr_planar", "ur5", "panda"}
    assert listing["shipped"]["ur5"]["scenarios"] == [
        "ur5/heavy_payload",
        "ur5/joint_friction",
        "ur5/sampled",
    ]
    assert listing["shipped"]["rr_planar"]["parameter_points"] == ["rr_planar/true_parameters"]
    assert {"anymal", "go1", "talos_full_v2"} <= set(listing["not_supported"])
    assert not set(listing["not_supported"]) & set(listing["example_robot_data"])


def test_robots_gives_the_lock_list_that_loads_each_robot_with_mimic_joints(capsys):
    """Every suggested --lock list loads the robot (and the robot is refused without it)."""
    import pytest

    import urpc
    from urpc.errors import InputError

    code, out, _ = _run(capsys, "robots", "--json")
    needs_lock = json.loads(out)["needs_lock"]
    assert {"panda", "baxter"} <= set(needs_lock)
    for name in ("panda", "baxter"):
        with pytest.raises(InputError, match="mimics joint"):
            urpc.load_robot(name)
        assert urpc.load_robot(name, locked_joints=needs_lock[name]).dof > 0
    code, text, _ = _run(capsys, "robots")
    assert f"--lock {','.join(needs_lock['baxter'])}" in text


def test_check_lists_the_moving_links(capsys):
    code, out, _ = _run(capsys, "check", "rr_planar")
    assert code == 0 and "moving links link1, link2, tool" in out
    assert "3 parameters in 1 link\n" in out


def test_check_without_a_shipped_box_points_to_init(capsys):
    code, out, _ = _run(capsys, "check", "ur10")
    assert code == 0 and "every parameter exact" not in out
    assert "no shipped box for ur10" in out and "urpc init ur10 --out box.yaml" in out
    assert "shoulder_link, upper_arm_link, forearm_link" in out
