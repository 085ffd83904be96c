"""Simulated recordings for verification: a true plant's torques along a trajectory, plus
bounded noise.

:func:`record` evaluates the true plant's inverse dynamics (Pinocchio's RNEA, the joints'
armature included) plus its drives' viscous and Coulomb friction (``Dv qd + Fc sat(qd/v_s)``, as
the Pinocchio plant) at the trajectory's states, and adds noise of magnitude at most ``noise``
per joint: ``uniform`` in ``[-noise, noise]``, or ``biased``, a constant offset of 80 % of the
bound plus uniform noise in the remaining 20 % (a sensor offset: bounded, but not zero-mean,
which is what least squares' intervals do not cover).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..model.joint_dynamics import friction_torque
from ..model.robot import Robot
from .data import Samples

NOISE_KINDS = ("uniform", "biased", "none")


def plant_torques(plant: Robot, q, qd, qdd) -> np.ndarray:
    """``(K, n)`` torques of ``plant`` at the states (rigid body, armature, drives)."""
    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    tau = np.array([plant.inverse_dynamics(*state) for state in zip(q, qd, qdd, strict=True)])
    params = plant.joint_parameters
    return tau + friction_torque(params[1], params[2], qd)


def record(
    plant: Robot,
    trajectory,
    times,
    noise,
    rng: np.random.Generator,
    kind: str = "uniform",
) -> Samples:
    """Samples of ``plant`` along ``trajectory`` at ``times`` with bounded torque noise."""
    if kind not in NOISE_KINDS:
        raise InputError(
            f"unknown noise kind '{kind}'; valid: {', '.join(NOISE_KINDS)}", field="kind"
        )
    times = np.asarray(times, dtype=float)
    q, qd, qdd = trajectory.evaluate(times)
    tau = plant_torques(plant, q, qd, qdd)
    bound = np.broadcast_to(np.asarray(noise, dtype=float), (plant.dof,))
    if kind == "uniform":
        tau = tau + rng.uniform(-1, 1, size=tau.shape) * bound
    elif kind == "biased":
        offset = 0.8 * bound * rng.choice([-1.0, 1.0], size=plant.dof)
        tau = tau + offset + 0.2 * rng.uniform(-1, 1, size=tau.shape) * bound
    return Samples.from_arrays(times, q, qd, qdd, tau, source="<simulated>")
