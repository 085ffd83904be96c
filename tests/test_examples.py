"""Every script in examples/ runs headless, as a user runs it, on short durations
(``URPC_EXAMPLE_DURATION``, ``URPC_EXAMPLE_RUNS``), and prints what it promises."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

#: Script -> lines its output must contain (what the example is for).
EXPECTED = {
    "own_arm_from_urdf.py": ("rr_planar: 2 joints", "met ||e|| < 0.01 rad", "final gains: phi ="),
    "own_trajectory.py": ("Circle: met", "SinusoidTrajectory: met"),
    "read_certificate.py": ("certified:", "epsilon floor:", "max sample period:", "holds"),
    "modular_arm.py": ("arm_tool_gripper: 3 joints", "arm_tool_vacuum: 3 joints"),
    "campaign.py": ("2 runs on a local pool", "worst final error"),
}


def test_every_example_is_listed():
    assert sorted(EXPECTED) == sorted(
        p.name for p in EXAMPLES.glob("*.py") if not p.name.startswith("_")
    )


@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_example_runs_headless(script, tmp_path):
    env = {
        **os.environ,
        "URPC_EXAMPLE_DURATION": "0.2",
        "URPC_EXAMPLE_RUNS": "2",
        "URPC_EXAMPLE_DASK": "0",  # a cluster takes longer to start than the runs
        "MPLBACKEND": "Agg",
    }
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / script)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    for line in EXPECTED[script]:
        assert line in done.stdout, (line, done.stdout)
