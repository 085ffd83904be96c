"""Every command's ``--help`` prints its help and exits 0 (issue 21.4: a ``%`` in a help string
crashed ``urpc init --help`` with a traceback); ``urpc --version``; a bare ``urpc`` lists the
commands (issue 21.7)."""

from __future__ import annotations

import argparse
import json

import pytest

import urpc
from urpc.cli import build_parser, main


def _commands(parser: argparse.ArgumentParser, prefix=()):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name)
                yield from _commands(sub, (*prefix, name))


COMMANDS = sorted(set(_commands(build_parser())))


def test_the_commands_are_found():
    assert ("init",) in COMMANDS and ("campaign",) in COMMANDS and len(COMMANDS) >= 10


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_every_help_works(command, capsys):
    with pytest.raises(SystemExit) as info:
        main([*command, "--help"])
    out, err = capsys.readouterr()
    assert info.value.code == 0, err
    assert out.startswith("usage: urpc " + " ".join(command)) and err == ""


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    out, _ = capsys.readouterr()
    assert info.value.code == 0 and out.strip() == f"urpc {urpc.__version__}"


def test_bare_urpc_lists_the_commands(capsys):
    assert main([]) == 0
    out, err = capsys.readouterr()
    assert err == "" and "simulate" in out and "campaign" in out and "init" in out


def test_negative_values_are_values(capsys):
    argv = ["bound", "rr_planar", "--q", "-0.1,0.2", "--qd", "-1,1", "--qd-a", "1,-1e-1"]
    assert main([*argv, "--qdd-a", "2,2", "--json"]) == 0
    assert capsys.readouterr().err == ""


def test_a_urdf_file_is_named_by_its_robot_name(tmp_path, capsys):
    from conftest import RR_DIR

    (tmp_path / "model.urdf").write_text((RR_DIR / "rr_planar.urdf").read_text())
    box = tmp_path / "box.yaml"
    box.write_text("links: {link2: {mass: [5, 10]}}\n")
    argv = ["simulate", "--robot", str(tmp_path / "model.urdf"), "-u", str(box)]
    assert main([*argv, "--duration", "0.02", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["scenario"] == "rr_planar"  # <robot name="rr_planar">, not the stem "model"
