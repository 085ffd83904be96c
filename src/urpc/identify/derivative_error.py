"""The torque error caused by the derivatives' estimation error (:mod:`urpc.identify.data`),
bounded over the prior box of body parameters; added to the torque noise of each sample."""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .data import Samples

if TYPE_CHECKING:
    from .problem import Problem


def derivative_torque_error(problem: Problem, samples: Samples) -> np.ndarray:
    """``(K, n)`` bound of the torque change when ``qd``, ``qdd`` move within their error bounds,
    over the prior box of body parameters (``problem.body_center``, ``body_radius``)::

        |M(q) da| + |2 Gamma(q; qd, dv)| + |Gamma(q; dv, dv)| + Ia da + Dv dv

    with the Christoffel form ``Gamma(q; u, v) = (c(q, u + v) - c(q, u - v)) / 4`` evaluated by
    the gravity-free regressor, each entry bounded over the box by ``|Y p_c| + |Y| p_r``.
    """
    K, n = samples.count, problem.robot.dof
    error = np.zeros((K, n))
    if not samples.estimated:
        return error
    model = problem.robot.model.copy()
    model.gravity.linear = np.zeros(3)
    data = model.createData()
    pc, pr = problem.body_center, problem.body_radius
    eye = np.eye(n)
    zero = np.zeros(n)

    def regressor(config, v, a):
        return np.asarray(pin.computeJointTorqueRegressor(model, data, config, v, a)).reshape(n, -1)

    def magnitude(Y):
        return np.abs(Y @ pc) + np.abs(Y) @ pr

    joints = problem.joints
    for k in range(K):
        dv, da = samples.velocity_error[k], samples.acceleration_error[k]
        if not (np.any(dv) or np.any(da)):
            continue
        config = problem.robot.configuration(samples.q[k])
        v = samples.qd[k]
        total = np.zeros(n)
        for j in np.flatnonzero(da):
            total += magnitude(regressor(config, zero, eye[j])) * da[j]
        for j in np.flatnonzero(dv):
            gamma = (regressor(config, v + eye[j], zero) - regressor(config, v - eye[j], zero)) / 4
            total += 2 * magnitude(gamma) * dv[j]
        active = np.flatnonzero(dv)
        for a, b in itertools.combinations_with_replacement(active, 2):
            gamma = (
                regressor(config, eye[a] + eye[b], zero) - regressor(config, eye[a] - eye[b], zero)
            ) / 4
            total += magnitude(gamma) * dv[a] * dv[b] * (1 if a == b else 2)
        if joints is not None:
            total += joints.upper[0] * da + joints.upper[1] * dv
        error[k] = total * (1 + 1e-9)
    return error
