"""Start-up stays lean: what ``import urpc`` and the CLI's argument parsing import.

Timings are measured by ``scripts/bench_startup.py`` (ratios to ``import numpy``), not here; these
tests pin the cause of a slow start-up instead: a heavy module imported before a command runs.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import urpc

HEAVY = ("pinocchio", "scipy", "numba", "matplotlib", "pydantic", "flint", "mujoco")


def _imported_after(code: str) -> set[str]:
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    modules = json.loads(done.stdout.strip().splitlines()[-1])
    return {m.split(".")[0] for m in modules}


def test_import_urpc_imports_no_heavy_module():
    assert not _imported_after("import urpc") & {*HEAVY, "numpy"}


def test_parsing_the_command_line_imports_no_heavy_module():
    code = (
        "from urpc.cli import build_parser\n"
        "parser = build_parser()\n"
        "parser.parse_args(['init', 'ur10', '--out', 'box.yaml'])"
    )
    assert not _imported_after(code) & set(HEAVY)


def test_every_public_name_resolves_lazily():
    for name in urpc.__all__:
        assert getattr(urpc, name) is not None
    from urpc import ParameterBox, load_robot, load_scenario, make_bound  # noqa: F401

    assert set(urpc.__all__) <= set(dir(urpc))
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        urpc.nothing  # noqa: B018
