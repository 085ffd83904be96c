"""The 3D replay (urpc.sim.replay): what the page holds, the CLI flags, and the page in a browser."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from urpc import load_robot
from urpc.errors import InputError
from urpc.sim.replay import (
    ReplayPart,
    end_effector_frame,
    frame_indices,
    page_commands,
    page_info,
    robot_shapes,
    write_replay,
)
from urpc.sim.results import SimulationResult

#: The only URLs in the page, both inside meshcat's bundle: the XHTML namespace of three.js (a
#: name, never loaded) and the default websocket of ``viewer.connect()``, which the page never calls.
BUNDLED_URLS = {"http://www.w3.org/1999/xhtml", "ws://${location.host}`"}


@pytest.fixture(scope="module")
def rr_run():
    from urpc.studies.scenario import build, build_controller, load_scenario, simulate_setup

    setup = build(load_scenario("rr_planar/s3_ic1").with_overrides(duration=1.0))
    return setup, simulate_setup(setup, build_controller(setup))


@pytest.fixture(scope="module")
def rr_page(rr_run, tmp_path_factory):
    _, result = rr_run
    path = result.replay(tmp_path_factory.mktemp("replay") / "replay.html")
    return path, path.read_text()


def _animations(text: str) -> dict[str, dict]:
    (command,) = [c for c in page_commands(text) if c["type"] == "set_animation"]
    return {entry["path"]: entry["clip"] for entry in command["animations"]}


def _track(clip: dict, name: str) -> tuple[np.ndarray, np.ndarray]:
    (track,) = [t for t in clip["tracks"] if t["name"] == name]
    times = np.array([key["time"] for key in track["keys"]]) / clip["fps"]
    return times, np.array([key["value"] for key in track["keys"]])


def test_end_effector_key_frames_are_forward_kinematics_of_recorded_samples(rr_run, rr_page):
    setup, result = rr_run
    _, text = rr_page
    robot = setup.robot
    clip = _animations(text)["/urpc/part0/end_effector"]
    times, positions = _track(clip, ".position")
    _, quaternions = _track(clip, ".quaternion")
    assert 25 <= len(times) <= 40  # about 30 key frames per simulated second
    model, data = robot.model, robot.model.createData()
    frame = model.getFrameId("tool")
    assert end_effector_frame(model) == frame
    for time, position, quaternion in zip(times, positions, quaternions, strict=True):
        (row,) = np.flatnonzero(np.isclose(result.t, time, rtol=0, atol=1e-12))  # a real sample
        pin.framesForwardKinematics(model, data, robot.configuration(result.q[row]))
        placement = data.oMf[frame]
        np.testing.assert_allclose(position, placement.translation, atol=1e-12)
        expected = pin.Quaternion(placement.rotation).coeffs()  # x, y, z, w (three.js order)
        assert min(np.abs(quaternion - expected).max(), np.abs(quaternion + expected).max()) < 1e-9
    # The joints: the elbow's node carries Pinocchio's oMi of joint 2 at each key frame.
    times, positions = _track(_animations(text)["/urpc/part0/2_joint2"], ".position")
    row = np.flatnonzero(np.isclose(result.t, times[10], rtol=0, atol=1e-12))[0]
    pin.forwardKinematics(model, data, robot.configuration(result.q[row]))
    np.testing.assert_allclose(positions[10], data.oMi[2].translation, atol=1e-12)


def test_desired_path_is_the_reference_end_effector_path(rr_run, rr_page):
    import umsgpack

    setup, result = rr_run
    (line,) = [c for c in page_commands(rr_page[1]) if c.get("path") == "/urpc/part0/desired_path"]
    position = line["object"]["geometries"][0]["data"]["attributes"]["position"]
    array = position["array"]
    raw = array.data if isinstance(array, umsgpack.Ext) else array
    points = np.frombuffer(raw, dtype=np.float32).reshape(-1, 3)
    robot = setup.robot
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.configuration(result.q_desired[-1]))
    tool = data.oMf[robot.model.getFrameId("tool")].translation
    np.testing.assert_allclose(points[-1], tool, atol=1e-6)
    assert len(points) == len(result.t)  # 1001 samples: every one of them


def test_page_loads_nothing_from_the_network(rr_page):
    _, text = rr_page
    assert 'src="http' not in text and "src='http" not in text and 'href="http' not in text
    assert not re.search(r"<(script|link|img|iframe)[^>]*\s(src|href)=", text)
    assert set(re.findall(r"(?:https?|wss?)://[^\s\"'<>)]*", text)) <= BUNDLED_URLS
    boot = text[text.rindex("<script>") :]
    assert "connect(" not in boot and "fetch(" not in boot
    info = page_info(text)
    assert info["duration"] == pytest.approx(1.0) and info["segments"][0]["start"] == 0.0


def test_frame_indices_pick_recorded_samples_and_keep_the_last():
    t = np.arange(0.0, 1.0005, 0.001)
    indices = frame_indices(t, 30.0)
    assert indices[0] == 0 and indices[-1] == len(t) - 1
    assert np.all(np.abs(t[indices[:-1]] - np.arange(len(indices) - 1) / 30.0) <= 0.0005 + 1e-12)


def test_fps_is_lowered_to_keep_at_most_max_frames(rr_run, tmp_path):
    setup, result = rr_run
    page = write_replay(
        tmp_path / "r.html",
        ReplayPart(setup.robot, result.t, result.q, result.q_desired),
        max_frames=10,
    ).read_text()
    times, _ = _track(_animations(page)["/urpc/part0/end_effector"], ".position")
    assert len(times) <= 12 and page_info(page)["fps"] == pytest.approx(10.0)


def test_geometry_skeleton_visuals_and_meshes():
    assert {s.name[:3] for s in robot_shapes(load_robot("rr_planar"))} == {"joi", "rod"}
    ur5 = robot_shapes(load_robot("ur5"))
    assert len(ur5) == 7 and all(s.geometry.mesh_format == "dae" for s in ur5)
    panda = load_robot("panda", ["panda_finger_joint1", "panda_finger_joint2"])
    shapes = robot_shapes(panda)  # fingers' meshes reduced onto joint 7 with the locked joints
    assert len(shapes) == 11 and max(s.joint for s in shapes) == panda.model.njoints - 1


def test_replay_needs_a_robot_and_a_loaded_result_keeps_it(rr_run, tmp_path):
    _, result = rr_run
    result.save(tmp_path / "run", csv=False)
    loaded = SimulationResult.load(tmp_path / "run")
    assert loaded.replay(tmp_path / "run").name == "replay.html"  # a folder gets replay.html
    anonymous = SimulationResult.load(tmp_path / "run")
    anonymous.info.pop("robot")
    with pytest.raises(InputError, match="does not record its robot"):
        anonymous.replay(tmp_path / "x.html")
    with pytest.raises(InputError, match="expected"):
        ReplayPart(load_robot("rr_planar"), result.t, result.q[:, :1], result.q_desired)


def test_cli_simulate_replay(tmp_path, capsys):
    from urpc.__main__ import main

    out = tmp_path / "run"
    argv = ["simulate", "rr_planar/s3_ic1", "--duration", "0.2", "--no-progress"]
    assert main([*argv, "--replay", "--out", str(out)]) == 0
    text = (out / "replay.html").read_text()
    assert "MeshCat" in text and page_info(text)["duration"] == pytest.approx(0.2)
    capsys.readouterr()
    assert main([*argv, "--replay"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("error:") and "--out" in err[-1] and "Traceback" not in "".join(err)


def test_demo_replay_plays_each_configuration_in_turn(tmp_path):
    from urpc.studies.demo import reconfigure_demo

    summary = reconfigure_demo(tmp_path, duration=0.3, repeats=1, replay=True)
    text = (tmp_path / "replay.html").read_text()
    assert summary["replay"] == str(tmp_path / "replay.html")
    info = page_info(text)
    assert [s["label"].split()[0] for s in info["segments"]] == [
        "arm_3dof",
        "arm_4dof",
        "arm_4dof_vacuum",
    ]
    starts = [s["start"] for s in info["segments"]]
    assert starts[0] == 0 and np.all(np.diff(starts) > 0.29)
    clips = _animations(text)
    for k, start in enumerate(starts):
        times, visible = _track(clips[f"/urpc/part{k}"], ".visible")
        shown = [bool(v) for tm, v in zip(times, visible, strict=True) if tm <= start + 1e-9]
        assert shown[-1] is True  # visible from its start
        if k + 1 < len(starts):
            later = [bool(v) for tm, v in zip(times, visible, strict=True) if tm >= starts[k + 1]]
            assert later[0] is False  # hidden once the next one plays
    colors = {
        c["object"]["materials"][0]["color"]
        for c in page_commands(text)
        if c["type"] == "set_object" and "/visual" in c["path"]
    }
    assert len(colors) >= 3  # modules colored by kind


# ----------------------------------------------------------------------------- in a browser
CHROMIUM = next(
    (shutil.which(name) for name in ("chromium", "chromium-browser") if shutil.which(name)), None
)
#: Test-only probe: console.error calls and uncaught errors become recognizable log lines.
_PROBE = (
    "<script>(function () { var error = console.error; console.error = function () {"
    ' error.apply(console, ["URPC-CONSOLE-ERROR"].concat([].slice.call(arguments))); };'
    ' window.addEventListener("error", function (e) {'
    ' console.log("URPC-CONSOLE-ERROR " + e.message); }); })();</script>'
)


def _screenshot(page: Path, png: Path) -> tuple[np.ndarray, list[str]]:
    """Load ``page`` in headless Chromium (WebGL by SwiftShader, no network); return the
    screenshot's pixels and the console lines that report an error."""
    instrumented = page.with_name(f"probe_{page.name}")
    instrumented.write_text(page.read_text().replace("<head>", "<head>\n" + _PROBE, 1))
    done = subprocess.run(
        [
            CHROMIUM,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--use-gl=angle",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--host-resolver-rules=MAP * ~NOTFOUND",  # nothing can come from the network
            "--window-size=800,600",
            "--virtual-time-budget=3000",
            "--enable-logging=stderr",
            "--v=0",
            f"--screenshot={png}",
            instrumented.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    console = [line for line in done.stderr.splitlines() if "CONSOLE" in line]
    errors = [line for line in console if "URPC-CONSOLE-ERROR" in line or "Uncaught" in line]
    from PIL import Image

    assert png.is_file(), done.stderr[-2000:]
    return np.asarray(Image.open(png).convert("RGB"), dtype=int), errors


@pytest.mark.skipif(
    CHROMIUM is None,
    reason="no Chromium to load the replay in (Debian: apt-get install chromium; .ci/run "
    "installs it)",
)
def test_replay_in_a_headless_browser_shows_the_arm(rr_page, tmp_path):
    page, text = rr_page
    pixels, errors = _screenshot(page, tmp_path / "replay.png")
    assert errors == []
    # The same page without the scene's commands: background, grid and panel only.
    start = text.index('<script type="text/plain" id="urpc-commands">')
    end = text.index("</script>", start)
    empty = tmp_path / "empty.html"
    empty.write_text(text[: text.index(">", start) + 1] + "\n" + text[end:])
    background, errors = _screenshot(empty, tmp_path / "empty.png")
    assert errors == []
    assert pixels.std() > 10  # not a blank canvas
    # Where the arm and its path are drawn (left of the panel, below the label), the pictures
    # differ on many pixels.
    changed = np.abs(pixels - background).sum(axis=2)[60:, :540] > 60
    assert changed.mean() > 0.002, changed.mean()  # the 1 s rr_planar run: about 0.006
    # The probe itself works: an uncaught error is reported.
    broken = tmp_path / "broken.html"
    broken.write_text(
        "<html><head></head><body><script>throw new Error('x')</script></body></html>"
    )
    _, errors = _screenshot(broken, tmp_path / "broken.png")
    assert errors
