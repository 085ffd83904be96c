"""The feasible set of identification as a polytope: unknowns, prior, data.

**Unknowns.** Per unknown link (or payload) with a *physical* prior box, 28 variables::

    x = [m, h (3), I_O (6) | c (3), I_C (6) | w (9)]

``m, h = m c, I_O`` are the standard parameters about the link origin (Pinocchio's order, the
columns of the regressor), ``c`` the center of mass and ``I_C`` the inertia about it (the file's
fields), and ``w_jk`` stands for ``h_j c_k = m c_j c_k``. The map between them is
``I_O = I_C + m S(c)^T S(c)``, linear in ``(I_C, w)``::

    I_O,xx = I_C,xx + w_yy + w_zz    I_O,xy = I_C,xy - w_xy    (and so on)

and the bilinear terms ``h = m c``, ``w = h c`` are relaxed by their McCormick envelopes over the
current bounds of ``m, c, h`` (four inequalities each; equalities when a factor is exact, e.g.
``h = m c0`` for a known center of mass). With ``w_jk = w_kj`` and the rigid-body cuts below,
every rigid body of the prior box that explains the data is a point of the polytope, so the
polytope's enclosing box is sound. A link with a *barycentric* prior has its 10 standard
parameters as variables, bounded by the prior box. Per uncertain joint drive parameter
(armature, viscous damping, Coulomb friction) one variable in its prior interval.

**Rigid bodies.** ``Sigma = tr(I_C)/2 1 - I_C`` is positive semi-definite for every rigid body
(principal moments obeying the triangle inequality), so ``u^T Sigma u >= 0`` and
``u^T I_C u >= 0`` for the axes and the six diagonals ``(e_i +- e_j)/sqrt 2``: linear cuts every
rigid body satisfies (a linearization of the physical-consistency LMI, not the LMI itself).

**Data.** Each sample ``k`` and joint ``i`` gives two inequalities::

    |Y_i(q, qd, qdd) pi + Ia_i qdd_i + Dv_i qd_i + Fc_i s - tau_i| <= N_i + e_ki

with ``Y`` Pinocchio's ``computeJointTorqueRegressor`` (the known links' part moved to the
right-hand side), ``s = sign(qd_i)`` when ``|qd_i|`` exceeds the stiction band plus the velocity
error, else any ``s in [-1, 1]`` (the set-valued law at rest and the plants' regularization
alike), ``N_i`` the torque noise bound and ``e_ki`` the torque error caused by the derivatives'
estimation error (:func:`derivative_torque_error`) plus the rounding of the regressor.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..model.joint_dynamics import JOINT_FIELDS, STICTION_VELOCITY, JointBox
from ..model.parameter_box import LinkBox
from ..model.regressor import link_regressor_map
from ..model.robot import Robot
from .data import Samples
from .derivative_error import derivative_torque_error
from .envelopes import LinkBounds
from .lp import Polytope

#: Variables of a link with a physical prior, and where each group starts.
PHYSICAL_SIZE = 28
STANDARD, COM, INERTIA_C, W = 0, 10, 13, 19
#: The component order of I (Pinocchio's): xx, xy, yy, xz, yz, zz as (row, column).
_COMPONENTS = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))
#: Relative rounding allowance of a regressor row times the parameters.
ROUNDING = 1e-10


# ============================================================================ unknowns
@dataclass
class Unknown:
    """One unknown body: its prior box and where its variables start."""

    box: LinkBox
    offset: int

    @property
    def physical(self) -> bool:
        return self.box.kind == "physical"

    @property
    def size(self) -> int:
        return PHYSICAL_SIZE if self.physical else 10

    @property
    def standard(self) -> slice:
        return slice(self.offset, self.offset + 10)


class Problem:
    """The identification polytope for a robot, a prior box and samples (module docstring).

    Args:
        robot: The robot (rigid, as loaded; the prior's payload and drives are added here).
        prior: The prior box (links, payload, joints).
        samples: The records.
        noise: Torque noise bound per joint [N m], shape ``(dof,)``.
        unknown_links: Names of the links/payload identified; ``None``: every uncertain one.
        identify_joints: Whether the prior's uncertain drive parameters are unknowns (else
            they are taken at their nominal values).
        rigid_body_cuts: Whether to add the rigid-body cuts.
    """

    def __init__(
        self,
        robot: Robot,
        prior,
        samples: Samples,
        noise: np.ndarray,
        unknown_links: list[str] | None = None,
        identify_joints: bool = True,
        rigid_body_cuts: bool = True,
    ):
        self.robot = prior.nominal_robot(robot)
        self.prior = prior
        self.samples = samples
        self.noise = np.asarray(noise, dtype=float)
        self.rigid_body_cuts = rigid_body_cuts
        if unknown_links is None:
            unknown_links = [b.link for b in prior.uncertain_links]
        self.unknowns: list[Unknown] = []
        offset = 0
        for name in unknown_links:
            box = prior.link_box(name)
            self.unknowns.append(Unknown(box, offset))
            offset += PHYSICAL_SIZE if box.kind == "physical" else 10
        joints = prior.joint_box(self.robot) if prior.joints is not None else None
        self.joints: JointBox | None = joints
        #: ``(row, column)`` of each unknown drive parameter (rows: JOINT_FIELDS).
        self.joint_unknowns: list[tuple[int, int]] = []
        if joints is not None and identify_joints:
            self.joint_unknowns = [tuple(rc) for rc in np.argwhere(joints.uncertain)]
        self.joint_offset = offset
        self.size = offset + len(self.joint_unknowns)
        self.bounds = {u.box.link: LinkBounds.of_prior(u.box) for u in self.unknowns if u.physical}
        self._regress()

    # ------------------------------------------------------------------ regressor and data
    def _regress(self) -> None:
        robot, samples = self.robot, self.samples
        names = [u.box.link for u in self.unknowns]
        B = link_regressor_map(robot, names) if names else np.zeros((10 * robot.dof, 0))
        phi0 = (
            np.concatenate([u.box.standard_parameters(u.box.nominal) for u in self.unknowns])
            if names
            else np.zeros(0)
        )
        known_body = robot.nominal_parameters - B @ phi0
        model = robot.model
        data = model.createData()
        K, n = samples.count, robot.dof
        Y_u = np.empty((K, n, B.shape[1]))
        tau_known = np.empty((K, n))
        magnitude = np.empty((K, n))
        for k in range(K):
            config = robot.configuration(samples.q[k])
            Y = pin.computeJointTorqueRegressor(model, data, config, samples.qd[k], samples.qdd[k])
            Y = np.asarray(Y).reshape(n, -1)
            Y_u[k] = Y @ B
            tau_known[k] = Y @ known_body
            magnitude[k] = np.abs(Y) @ np.abs(known_body)
        self.Y_u = Y_u
        self.tau_known = tau_known
        phi_scale = (
            np.concatenate(
                [
                    np.maximum(np.abs(lo), np.abs(hi))
                    for lo, hi in (self._standard_box(u) for u in self.unknowns)
                ]
            )
            if names
            else np.zeros(0)
        )
        rounding = ROUNDING * (magnitude + np.abs(Y_u) @ phi_scale + np.abs(samples.tau)) + 1e-12
        self.body_center, self.body_radius = self._body_enclosure(B, known_body)
        self.error = rounding + derivative_torque_error(self, samples)
        # Coulomb sign range per sample and joint.
        v, dv = samples.qd, samples.velocity_error
        positive = v - dv >= STICTION_VELOCITY
        negative = v + dv <= -STICTION_VELOCITY
        self.sign_low = np.where(positive, 1.0, -1.0)
        self.sign_high = np.where(negative, -1.0, 1.0)

    def _standard_box(self, unknown: Unknown) -> tuple[np.ndarray, np.ndarray]:
        if unknown.physical:
            return self.bounds[unknown.box.link].standard()
        return unknown.box.lower.copy(), unknown.box.upper.copy()

    def _body_enclosure(self, B, known_body):
        if not self.unknowns:
            return known_body, np.zeros_like(known_body)
        boxes = [self._standard_box(u) for u in self.unknowns]
        lo = np.concatenate([b[0] for b in boxes])
        hi = np.concatenate([b[1] for b in boxes])
        center = known_body + B @ (0.5 * (lo + hi))
        radius = np.abs(B) @ (0.5 * (hi - lo))
        return center, radius * (1 + 1e-12)

    # ------------------------------------------------------------------ the polytope
    def polytope(self) -> Polytope:
        """The polytope over the current bounds (prior, or tightened by earlier rounds)."""
        lower, upper = np.zeros(self.size), np.zeros(self.size)
        rows_ub, rhs_ub, rows_eq, rhs_eq = [], [], [], []
        for unknown in self.unknowns:
            if unknown.physical:
                self._physical_block(unknown, lower, upper, rows_ub, rhs_ub, rows_eq, rhs_eq)
            else:
                lower[unknown.standard] = unknown.box.lower
                upper[unknown.standard] = unknown.box.upper
        joints = self.joints
        for n, (row, column) in enumerate(self.joint_unknowns):
            lower[self.joint_offset + n] = joints.lower[row, column]
            upper[self.joint_offset + n] = joints.upper[row, column]
        A_data, b_data = self._data_rows()
        A_ub = np.vstack([np.array(rows_ub).reshape(-1, self.size), A_data])
        b_ub = np.concatenate([np.array(rhs_ub, dtype=float), b_data])
        A_eq = np.array(rows_eq, dtype=float).reshape(-1, self.size)
        return Polytope(
            A_ub, b_ub, A_eq, np.array(rhs_eq, dtype=float), lower, upper, always=len(rhs_ub)
        )

    def _data_rows(self) -> tuple[np.ndarray, np.ndarray]:
        samples, joints = self.samples, self.joints
        K, n = samples.count, self.robot.dof
        residual = samples.tau - self.tau_known
        bound = self.noise[None, :] + self.error
        high_side = np.zeros((K, n, self.size))  # <= residual + bound, with s = sign_low
        for i, unknown in enumerate(self.unknowns):
            high_side[:, :, unknown.standard] = self.Y_u[:, :, 10 * i : 10 * i + 10]
        low_side = high_side.copy()  # >= residual - bound, with s = sign_high
        known_high = np.zeros((K, n))  # the known drive torque on each side
        known_low = np.zeros((K, n))
        if joints is not None:
            unknown = set(self.joint_unknowns)
            for row, column in itertools.product(range(3), range(n)):
                if (row, column) in unknown:
                    continue
                value = joints.nominal[row, column]
                if value == 0.0:
                    continue
                if row == 0:
                    term = value * samples.qdd[:, column]
                    known_high[:, column] += term
                    known_low[:, column] += term
                elif row == 1:
                    term = value * samples.qd[:, column]
                    known_high[:, column] += term
                    known_low[:, column] += term
                else:
                    known_high[:, column] += value * self.sign_low[:, column]
                    known_low[:, column] += value * self.sign_high[:, column]
            for m, (row, column) in enumerate(self.joint_unknowns):
                index = self.joint_offset + m
                if row == 0:
                    high_side[:, column, index] = low_side[:, column, index] = samples.qdd[
                        :, column
                    ]
                elif row == 1:
                    high_side[:, column, index] = low_side[:, column, index] = samples.qd[:, column]
                else:
                    high_side[:, column, index] = self.sign_low[:, column]
                    low_side[:, column, index] = self.sign_high[:, column]
        A = np.vstack([high_side.reshape(K * n, -1), -low_side.reshape(K * n, -1)])
        b = np.concatenate(
            [
                (residual - known_high + bound).reshape(-1),
                -(residual - known_low - bound).reshape(-1),
            ]
        )
        return A, b

    def _physical_block(self, unknown, lower, upper, rows_ub, rhs_ub, rows_eq, rhs_eq) -> None:
        o, b = unknown.offset, self.bounds[unknown.box.link]
        lo_std, hi_std = b.standard()
        lower[o : o + 10], upper[o : o + 10] = lo_std, hi_std
        for k in range(3):
            lower[o + COM + k], upper[o + COM + k] = b.com[k]
        for k in range(6):
            lower[o + INERTIA_C + k], upper[o + INERTIA_C + k] = b.inertia[k]
        for j, k in itertools.product(range(3), range(3)):
            lower[o + W + 3 * j + k], upper[o + W + 3 * j + k] = b.w_bounds(j, k)

        def mccormick(product, x, y, bx, by):
            """Rows of the McCormick envelope of ``product = x y`` over ``bx x by``."""
            (xl, xu), (yl, yu) = bx, by
            for sign, (xa, ya) in ((-1, (xl, yl)), (-1, (xu, yu)), (1, (xu, yl)), (1, (xl, yu))):
                # sign -1: product >= xa y + ya x - xa ya; sign +1: product <= xa y + ya x - xa ya
                row = np.zeros(self.size)
                row[product] = sign
                row[y] += -sign * xa
                row[x] += -sign * ya
                rows_ub.append(row)
                rhs_ub.append(-sign * xa * ya)

        for k in range(3):  # h_k = m c_k
            mccormick(o + 1 + k, o, o + COM + k, b.mass, b.com[k])
        for j, k in itertools.product(range(3), range(3)):  # w_jk = h_j c_k
            mccormick(o + W + 3 * j + k, o + 1 + j, o + COM + k, b.h[j], b.com[k])
        for j, k in itertools.combinations(range(3), 2):  # w_jk = w_kj
            row = np.zeros(self.size)
            row[o + W + 3 * j + k], row[o + W + 3 * k + j] = 1.0, -1.0
            rows_eq.append(row)
            rhs_eq.append(0.0)
        # I_O = I_C + m S(c)^T S(c): diagonal adds the other two w_jj, products subtract w_jk.
        for n, (r, c) in enumerate(_COMPONENTS):
            row = np.zeros(self.size)
            row[o + 4 + n], row[o + INERTIA_C + n] = 1.0, -1.0
            if r == c:
                for other in range(3):
                    if other != r:
                        row[o + W + 4 * other] = -1.0
            else:
                row[o + W + 3 * r + c] = 1.0
            rows_eq.append(row)
            rhs_eq.append(0.0)
        if self.rigid_body_cuts:
            for u in _cut_directions():
                for sigma in (True, False):
                    # u^T Sigma u = tr(I)/2 - u^T I u >= 0 and u^T I u >= 0, linear in I_C.
                    row = np.zeros(self.size)
                    for n, (r, c) in enumerate(_COMPONENTS):
                        quadratic = u[r] * u[c] * (1.0 if r == c else 2.0)
                        trace = 0.5 if (sigma and r == c) else 0.0
                        row[o + INERTIA_C + n] = -(trace - quadratic) if sigma else -quadratic
                    rows_ub.append(row)
                    rhs_ub.append(0.0)

    # ------------------------------------------------------------------ objectives
    def objective(self, unknown: Unknown, index: int) -> np.ndarray:
        f = np.zeros(self.size)
        f[unknown.offset + index] = 1.0
        return f

    def joint_objective(self, n: int) -> np.ndarray:
        f = np.zeros(self.size)
        f[self.joint_offset + n] = 1.0
        return f

    def regressor_matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """``(W, r)``: the stacked regressor of the unknowns' standard parameters and drive
        parameters and the residual torque, for least squares (Coulomb friction with the middle
        of its sign range, 0 inside the stiction band)."""
        A, b = self._data_rows()
        K, n = self.samples.count, self.robot.dof
        bound = (self.noise[None, :] + self.error).reshape(-1)
        columns = []
        for unknown in self.unknowns:
            columns.extend(range(unknown.offset, unknown.offset + 10))
        columns.extend(range(self.joint_offset, self.size))
        W = 0.5 * (A[: K * n] - A[K * n :])[:, columns]
        r = 0.5 * ((b[: K * n] - bound) - (b[K * n :] - bound))
        return W, r


def _cut_directions() -> list[np.ndarray]:
    directions = [np.eye(3)[i] for i in range(3)]
    for i, j in itertools.combinations(range(3), 2):
        for sign in (1.0, -1.0):
            u = np.zeros(3)
            u[i], u[j] = 1.0, sign
            directions.append(u / np.sqrt(2.0))
    return directions


__all__ = ["JOINT_FIELDS", "Problem", "Unknown", "derivative_torque_error"]
