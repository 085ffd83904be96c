"""What the laws of the interval controller give its certificate: conditions and a law's part of
the argument.

:func:`urpc.control.certificate.certify` asks each law of the controller for its part instead of
branching on the controller's flags: the gain law (:mod:`urpc.control.gain_laws`) for the gain
conditions of Theorem 1 or 2, the feedback law (:mod:`urpc.control.feedback`) for the floor, its
conditions and figures at the law's period. This module imports nothing of urpc, so that the laws
(on the control step's path) do not load the certificate's machinery.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Condition:
    """One condition of the argument: ``holds`` when ``value`` satisfies ``limit``."""

    name: str
    holds: bool
    value: float
    limit: float
    explanation: str


@dataclass(frozen=True)
class LawArgument:
    """A feedback law's part of the certificate.

    Attributes:
        floor: The ultimate bound of ``||e||`` the argument gives [rad] (``inf``: none).
        conditions: The law's conditions, in the order the certificate lists them.
        figures: The quantities the floor is made of (``lambda_L``, ``beta`` ...), for reports.
        max_sample_period: The largest period at which the law is certified [s] (0: none, or
            continuous time).
    """

    floor: float
    conditions: list[Condition]
    figures: dict[str, Any] = field(default_factory=dict)
    max_sample_period: float = 0.0
