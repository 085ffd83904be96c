"""What :func:`~urpc.sim.simulation.simulate` takes besides the run's physics: the integrator's
settings (:class:`SolverOptions`), and the keywords of its older signature, still accepted for one
release with a :class:`DeprecationWarning` (:func:`legacy_arguments`)."""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from typing import Any

from ..errors import InputError
from ..validation import positive_number
from .continuous import CONTINUOUS_ATOL, CONTINUOUS_METHOD, CONTINUOUS_RTOL


@dataclass(frozen=True)
class SolverOptions:
    """How a run is integrated and recorded (no physics: another choice changes a run by the
    integration error only).

    Attributes:
        method, rtol, atol: :func:`scipy.integrate.solve_ivp`'s method and tolerances
            (continuous time).
        output_rate: Recording rate [Hz] of a continuous run.
        integration_step: Largest RK4 step [s] inside one sample period (sampled runs).
        max_state: Bound on ``|q|`` [rad] and ``|qd|`` [rad/s] (the norm of ``(q, qd)`` in a
            sampled run) beyond which the run counts as diverged; the default 1e4 is far beyond
            any arm and keeps a diverging continuous run from crawling through ever stiffer
            dynamics.

    Raises:
        InputError: ``output_rate``, ``integration_step`` or ``max_state`` not a finite number
            > 0 (the field named).
    """

    method: str = CONTINUOUS_METHOD
    rtol: float = CONTINUOUS_RTOL
    atol: float = CONTINUOUS_ATOL
    output_rate: float = 1000.0
    integration_step: float = 1e-4
    max_state: float = 1e4

    def __post_init__(self) -> None:
        # scipy.integrate.solve_ivp's methods (a class of its own is a user's choice to make)
        known = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
        if isinstance(self.method, str) and self.method not in known:
            raise InputError(
                f"unknown integration method {self.method!r}; valid: {', '.join(known)}",
                field="method",
            )
        for name, units in (
            ("rtol", "relative tolerance"),
            ("atol", "absolute tolerance"),
            ("output_rate", "Hz"),
            ("integration_step", "s"),
            ("max_state", "rad, rad/s"),
        ):
            value = positive_number(name, getattr(self, name), f"a finite number > 0 [{units}]")
            object.__setattr__(self, name, value)


#: The older keywords of ``simulate`` -> where they went (``solver.NAME`` or the result's label).
_SOLVER = tuple(f.name for f in dataclasses.fields(SolverOptions))
_LABELS = {"scenario": "scenario", "plant_description": "plant"}


def legacy_arguments(
    solver: SolverOptions | None, given: dict[str, Any]
) -> tuple[SolverOptions, dict[str, Any]]:
    """The solver settings and the result's labels (``scenario``, ``plant``) of a call to
    ``simulate``: ``solver`` (``None``: the defaults), or the older keywords in ``given``,
    warned about once each kind.

    Raises:
        TypeError: a keyword ``simulate`` never took, or solver settings given both ways.
        InputError: ``solver`` is no :class:`SolverOptions`, or one of its values is invalid.
    """
    unknown = [name for name in given if name not in _SOLVER and name not in _LABELS]
    if unknown:
        raise TypeError(f"simulate() got an unexpected keyword argument {unknown[0]!r}")
    if solver is not None and not isinstance(solver, SolverOptions):
        raise InputError(
            f"expected urpc.SolverOptions(...), got {type(solver).__name__}", field="solver"
        )
    moved = {name: given[name] for name in _SOLVER if name in given}
    if moved:
        if solver is not None:
            raise TypeError(
                f"simulate() got solver= and {', '.join(moved)}: give them in solver= only"
            )
        settings = ", ".join(f"{name}=..." for name in moved)
        warnings.warn(
            f"simulate({settings}) is deprecated: pass solver=urpc.SolverOptions({settings})",
            DeprecationWarning,
            stacklevel=3,
        )
        solver = SolverOptions(**moved)
    labels = {_LABELS[name]: given[name] for name in _LABELS if name in given}
    if labels:
        used = ", ".join(f"{name}=..." for name in _LABELS if name in given)
        label = ", ".join(f"{name}=..." for name in labels)
        warnings.warn(
            f"simulate({used}) is deprecated: label the result, simulate(...).labelled({label})",
            DeprecationWarning,
            stacklevel=3,
        )
    return solver if solver is not None else SolverOptions(), labels
