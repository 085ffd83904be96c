"""What every example shares: its simulated duration, shortened by the test suite.

``URPC_EXAMPLE_DURATION`` [s] overrides each example's own duration (``tests/test_examples.py``
sets it so that the examples run in seconds); ``URPC_EXAMPLE_RUNS`` the number of campaign runs.
"""

from __future__ import annotations

import os


def duration(default: float) -> float:
    """The simulated duration [s]: ``default``, or ``URPC_EXAMPLE_DURATION`` when set."""
    return float(os.environ.get("URPC_EXAMPLE_DURATION", default))


def runs(default: int) -> int:
    """The number of campaign runs: ``default``, or ``URPC_EXAMPLE_RUNS`` when set."""
    return int(os.environ.get("URPC_EXAMPLE_RUNS", default))
