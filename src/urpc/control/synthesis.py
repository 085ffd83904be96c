"""Synthesis: build the interval passivity controller from a robot and a parameter box.

Synthesis is separate from running: :func:`synthesize` validates the gains, builds the bound
method once (its model copies and constant matrices), and returns a controller whose only
internal state is explicit, so the same controller can be simulated many times.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..bounds import default_method, make_bound
from ..errors import InputError
from ..model.inertia_bounds import InertiaBounds
from ..model.robot import Robot
from ..model.uncertainty import ParameterBox
from ..validation import check_type, number_in
from . import SAMPLED_LAWS
from .base import sample_period_of
from .interval import IntervalPassivityController

#: The smallest epsilon [rad or m] a controller is synthesized for: an error below it is lost in
#: the rounding of joint positions of order 1 (2.2e-16 relative), and ``Kr = 3 / sqrt(epsilon)``
#: then overflows the dynamics' enclosures.
MIN_EPSILON = 1e-12


def synthesize(
    robot: Robot,
    box: ParameterBox,
    epsilon: float,
    *,
    method: str | None = None,
    kappa_P: float = 2.0,
    kappa_I: float = 1.0,
    phi_P: float = 1.0,
    phi_I: float = 1e6,
    Kr: float | Sequence[float] | np.ndarray | None = None,
    sample_period: float | None = None,
    sampled_law: str = "implicit",
    delay: int = 0,
) -> IntervalPassivityController:
    """The paper's controller for ``robot`` with uncertain parameters in ``box``.

    Theorem 2 (adaptive gains) when ``box.disturbance_bound`` is ``None``, Theorem 1 (constant
    gains ``kappa_P``, ``phi_P``, disturbance included in the enclosure) otherwise. Defaults are the
    paper's gains.

    Args:
        robot: The nominal robot (payloads of ``box`` are attached at their nominal point).
        box: Uncertain link parameters and the disturbance bound.
        epsilon: Required tracking precision ``||q_d - q|| < epsilon`` [rad], finite, > 0.
        method: Bound method name (``urpc.bounds.METHODS``); ``None`` picks
            :func:`urpc.bounds.default_method` for the box.
        kappa_P: [s/rad], >= 1 (Theorem 1).
        kappa_I: [1/rad^2], > 0 (Theorem 2).
        phi_P: [N m s/rad], >= 1 (Theorem 1).
        phi_I: [N m/rad^2], > 0 (Theorem 2).
        Kr: Diagonal gain [1/s]: a positive scalar, ``dof`` positive numbers, or a diagonal
            ``dof x dof`` matrix; ``None`` gives the paper's ``3 / sqrt(epsilon)``.
        sample_period: The control period [s] when the controller runs sampled (zero-order
            hold). ``None``: continuous time, the paper's law.
        sampled_law: With ``sample_period``: ``"implicit"`` (default), the sampled-data law of
            :mod:`urpc.control.feedback` that stays stable on every plant of the box and is
            certified by :func:`urpc.certify`; ``"paper"``, the paper's law unchanged (it can
            diverge on light plants at 0.5-1 kHz).
        delay: Samples between a state and the period its torque acts over: 0 (the ideal
            zero-order hold) or 1 (most torque interfaces): the law then predicts one period
            ahead (:class:`urpc.control.delay.DelayedIntervalController`); needs a
            ``sample_period``.

    Raises:
        InputError: a gain or ``epsilon`` out of range (the message names the field and the valid
            range), an unknown bound method.
    """
    check_type("robot", robot, Robot, "a Robot (urpc.load_robot(...))")
    epsilon = number_in(
        "epsilon", epsilon,
        f"a finite number >= {MIN_EPSILON:g} [rad] (a smaller error is lost in the rounding of "
        "q, and the default Kr = 3 / sqrt(epsilon) overflows the dynamics)",
        lambda x: x >= MIN_EPSILON,
    )  # fmt: skip
    kappa_P = number_in("kappa_P", kappa_P, "a finite number >= 1 (Theorem 1)", lambda x: x >= 1)
    phi_P = number_in("phi_P", phi_P, "a finite number >= 1 (Theorem 1)", lambda x: x >= 1)
    kappa_I = number_in("kappa_I", kappa_I, "a finite number > 0 (Theorem 2)", lambda x: x > 0)
    phi_I = number_in("phi_I", phi_I, "a finite number > 0 (Theorem 2)", lambda x: x > 0)
    gains = gain_diagonal(Kr, epsilon, robot.dof)
    sample_period = sample_period_of(sample_period)
    if sampled_law not in SAMPLED_LAWS:
        raise InputError(
            f"{sampled_law!r} is not a sampled law; valid: {', '.join(SAMPLED_LAWS)}",
            field="sampled_law",
        )
    if isinstance(delay, bool) or delay not in (0, 1):
        raise InputError(f"{delay!r} is not a delay; valid: 0, 1 [samples]", field="delay")
    if delay and sample_period is None:
        raise InputError(
            "a delay needs a sample period (a delay of one sample of continuous time is "
            "undefined); give sample_period",
            field="delay",
        )
    if method is None:
        method = default_method(box)
    bound = make_bound(method, robot, box)
    implicit = sample_period is not None and sampled_law == "implicit"
    law = IntervalPassivityController
    if delay:
        from .delay import DelayedIntervalController as law
    return law(
        bound,
        epsilon,
        kappa_P=kappa_P,
        kappa_I=kappa_I,
        phi_P=phi_P,
        phi_I=phi_I,
        Kr=gains,
        sample_period=sample_period,
        sampled_law=sampled_law,
        inertia_bounds=InertiaBounds(robot, box) if implicit else None,
    )


def gain_diagonal(Kr, epsilon: float, dof: int) -> np.ndarray:
    """The diagonal of ``Kr`` [1/s] (length ``dof``) as :func:`synthesize` takes it: ``None``
    (``3 / sqrt(epsilon)``), a scalar, ``dof`` numbers or a diagonal matrix.

    Raises:
        InputError: anything else (field ``Kr``)."""
    if Kr is None:
        return np.full(dof, 3.0 / math.sqrt(epsilon))
    expected = f"a scalar, {dof} numbers or a diagonal {dof}x{dof} matrix, all finite and > 0 [1/s]"
    if isinstance(Kr, str | bytes | bool):  # as epsilon: a text or a flag is not a gain
        raise InputError(
            f"{Kr!r} is a {type(Kr).__name__}, not a number; expected {expected}", field="Kr"
        )
    try:
        gains = np.array(Kr, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{Kr!r} is not numeric; expected {expected}", field="Kr") from None
    if gains.ndim == 0:
        gains = np.full(dof, float(gains))
    elif gains.shape == (dof, dof):
        if np.any(gains - np.diag(np.diag(gains))):
            raise InputError(f"the matrix is not diagonal; expected {expected}", field="Kr")
        gains = np.diag(gains).copy()
    elif gains.shape != (dof,):
        raise InputError(f"shape {gains.shape} does not fit; expected {expected}", field="Kr")
    if not np.all(np.isfinite(gains)) or np.any(gains <= 0):
        raise InputError(
            f"{gains.tolist()} has an entry out of range; expected {expected}", field="Kr"
        )
    return gains
