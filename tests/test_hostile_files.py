"""Hostile files (issue 21.3, 21.5): an alias bomb, a 50 MB YAML, deep nesting and a 50 MB URDF are
each refused with one ``error:`` line within a second; the C++ URDF parser's own lines never reach
stderr (urpc quotes it in its one line)."""

from __future__ import annotations

import os
import time

import pytest
from conftest import RR_DIR

from urpc.cli import main
from urpc.formats.base import MAX_YAML_NODES
from urpc.native import captured_stderr

RR_URDF = (RR_DIR / "rr_planar.urdf").read_text()


def _alias_bomb() -> str:
    """Nine levels of nine aliases inside an accepted value (the interval of a CoM coordinate):
    9**9 (387 million) strings once expanded, 500 bytes on disk."""
    levels = ["&l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for level in range(1, 10):
        levels.append(f"&l{level} [" + ", ".join([f"*l{level - 1}"] * 9) + "]")
    return "links:\n  link2:\n    com_x: [" + ", ".join(levels) + "]\n"


def _big_yaml(path) -> None:
    with path.open("w") as stream:
        stream.write("links:\n  link2:\n    mass: [5, 10]\nnotes:\n")
        line = "  - " + "x" * 40 + "\n"
        stream.write(line * (50 * 2**20 // len(line)))


def _big_urdf(path) -> None:
    head, tail = RR_URDF.rsplit("</robot>", 1)
    with path.open("w") as stream:
        stream.write(head)
        comment = "<!-- " + "x" * 1000 + " -->\n"
        stream.write(comment * (50 * 2**20 // len(comment)))
        stream.write("</robot>" + tail)


CASES = {
    "alias_bomb": ("box.yaml", lambda p: p.write_text(_alias_bomb()), "aliases", False),
    "yaml_50_MB": ("box.yaml", _big_yaml, "too large", False),
    "yaml_deep": ("box.yaml", lambda p: p.write_text("links: " + "[" * 200 + "]" * 200), "nested", False),
    "yaml_many_values": ("box.yaml", lambda p: p.write_text("notes: [" + "1, " * (MAX_YAML_NODES + 10) + "1]\n"), f"more than {MAX_YAML_NODES}", False),
    "urdf_50_MB": ("arm.urdf", _big_urdf, "too large for a URDF", True),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_hostile_file_is_one_error_line_within_a_second(name, tmp_path, capsys):
    filename, make, words, is_urdf = CASES[name]
    path = tmp_path / filename
    make(path)
    argv = ["check", str(path)] if is_urdf else ["check", "rr_planar", "-u", str(path)]
    main(["check", "rr_planar"])  # the robot loaded once: what is timed is the file
    capsys.readouterr()
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: ") and err.count("\n") == 1, err[:300]
    assert words in err and filename in err
    assert elapsed < 1.0, f"{elapsed:.2f} s"


def test_the_urdf_parser_prints_nothing_urpc_says_it(tmp_path, capfd):
    path = tmp_path / "arm.urdf"
    path.write_text(RR_URDF.replace('effort="1000" velocity="20"', 'velocity="20"', 1))
    assert main(["check", str(path)]) == 2
    out, err = capfd.readouterr()  # file descriptors: what C++ writes is seen too
    assert err.count("\n") == 1 and err.startswith("error: "), err
    assert "limit has no effort" in err and "joint.cpp" not in err


def test_captured_stderr_takes_what_is_written_on_descriptor_2(capfd):
    with captured_stderr() as captured:
        os.write(2, b"Error:   something native\n   at line 1\n")
    assert captured.first_line == "something native"
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize(
    "filename", ["package://nowhere/arm.stl", "$(find arm)/meshes/arm.stl", "meshes/none.stl"]
)
def test_missing_meshes_are_named_by_the_mujoco_plant(filename, tmp_path, capsys):
    pytest.importorskip("mujoco")
    link = '<link name="link2">'
    mesh = f'<visual><geometry><mesh filename="{filename}"/></geometry></visual>'
    (tmp_path / "arm.urdf").write_text(RR_URDF.replace(link, link + mesh, 1))
    (tmp_path / "box.yaml").write_text("links: {link2: {mass: [5, 10]}}\n")
    argv = ["simulate", "--robot", str(tmp_path / "arm.urdf"), "-u", str(tmp_path / "box.yaml")]
    assert main([*argv, "--plant", "mujoco", "--duration", "0.01", "--json"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("warning: ") and filename in err
