#!/usr/bin/env python
"""The reconfigurable-arm demo, as a script: the same as ``urpc demo reconfigure``.

Runs the shipped assemblies arm_3dof, arm_4dof and arm_4dof_vacuum in turn, each synthesized on
the fly with the same default settings (:func:`urpc.studies.demo.reconfigure_demo`), and writes the figure
and the summary into ``--out`` (default ``urpc-results/reconfigure``)::

    python scripts/reconfigurable_arm.py [--out DIR] [--json] [--no-progress] [--duration S]

``python scripts/reconfigurable_arm.py --help`` lists every option. Exit code 0 on success, 2 for
bad input (one ``error:`` line on stderr).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from urpc.cli import main as urpc_main


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``urpc demo reconfigure`` with ``argv`` (default: the command line)."""
    return urpc_main(["demo", "reconfigure", *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":
    sys.exit(main())
