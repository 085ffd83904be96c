"""The sampled-data floor of the implicit law on a grid of the reference (docs/sampled-data.md §2).

:class:`FloorGrid` evaluates, at points of the reference and per piece of the box, the quantities
of the one-period bound ``||delta+||_M <= (1 - a + b) ||delta||_M + f + b ||r*||_M`` and solves
for the ultimate bound of ``||e||`` (a fixed point over the tube around the reference), and for the
largest period at which it stays below a requested ``epsilon``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg

from ..bounds.base import link_body_placement
from ..bounds.hull import barycentric_enclosure
from ..model.inertia_bounds import InertiaBounds
from ..model.uncertainty import ParameterBox
from ..trajectories import Trajectory
from .interval import PHI_MAX_FACTOR, IntervalPassivityController
from .sampled_joints import JointTerms

#: Grid points along the reference where the certificate's quantities are evaluated.
GRID_POINTS = 120


class FloorGrid:
    """The certificate's quantities on a grid of the reference, per piece of the box.

    The box is split into pieces along its widest mass intervals (:func:`split_box`); each piece
    gets its own inertia bounds, so that the mismatch of a heavy plant is measured in the metric
    of a heavy plant (pairing the largest mismatch with the lightest inertia is what a single
    box would do). The law's own ``M_L`` (of the whole box) enters the contraction of each piece.
    """

    def __init__(self, controller: IntervalPassivityController, trajectory: Trajectory, duration):
        self.controller = controller
        robot = controller.robot
        self.bound = controller.bound
        self.law_bounds = controller.inertia_bounds or InertiaBounds(robot, self.bound.box)
        self.Kr = controller.Kr
        times = np.linspace(0.0, float(duration), GRID_POINTS)
        self.q, self.qd, self.qdd = (np.atleast_2d(x) for x in trajectory.evaluate(times))
        n, step = robot.dof, 1e-4
        upper = self.law_bounds.upper_robot
        self.nominal_inertia = [robot.M(q) for q in self.q]
        self.law_inertia = [self.law_bounds.lower(q) for q in self.q]
        # Coriolis matrices at unit velocities (nominal and heaviest model) and the change of the
        # torque along the reference, shared by the pieces.
        self.coriolis = [[m.C(q, u) for m in (robot, upper) for u in np.eye(n)] for q in self.q]
        ahead = trajectory.evaluate(times + step)
        self.torque_rate = [
            (upper.inverse_dynamics(qa, qda, qdda) - upper.inverse_dynamics(q, qd, qdd)) / step
            for q, qd, qdd, qa, qda, qdda in zip(self.q, self.qd, self.qdd, *ahead, strict=True)
        ]
        self.law_inverse = [np.linalg.inv(M) for M in self.law_inertia]
        #: ``||M_L^-1 dtau/dt||`` [rad/s^2 / s]: the held torque lags the reference by T/2.
        self.trace_inverse = np.array([np.trace(Mi) for Mi in self.law_inverse])
        self.lag = np.array(
            [
                np.linalg.norm(Mi @ rate)
                for Mi, rate in zip(self.law_inverse, self.torque_rate, strict=True)
            ]
        )
        self.grid_step = float(times[1] - times[0])
        self.joints = JointTerms(self.bound.joints)
        self._regressors: dict[float, list[list[np.ndarray]]] = {}
        self.pieces = [_Piece(self, piece) for piece in split_box(self.bound.box)]

    def figures(self) -> dict[str, float]:
        pieces = self.pieces
        return {
            "pieces": float(len(pieces)),
            "lambda_L": float(min(np.min(p.lam_L) for p in pieces)),
            "lambda_U": float(max(np.max(p.lam_U) for p in pieces)),
            "beta": float(min(np.min(p.beta) for p in pieces)),
            "nu": float(max(np.max(p.nu) for p in pieces)),
        }

    def regressors(self, tube: float) -> list[list[np.ndarray]]:
        """``Y_SL`` at ``r = 0`` for the tube ``||e|| <= tube``: per grid point, at ``e = 0``, at
        ``+-tube`` along each joint and along 4 fixed random directions."""
        key = round(tube, 15)
        if key not in self._regressors:
            n, Kr = len(self.Kr), self.Kr
            random = np.random.default_rng(0).standard_normal((4, n))
            directions = np.vstack(
                [
                    np.zeros(n),
                    np.eye(n),
                    -np.eye(n),
                    random / np.linalg.norm(random, axis=1)[:, None],
                ]
            )
            regressor = self.bound.regressor
            self._regressors[key] = [
                [
                    regressor(q - e, qd + Kr * e, qd + Kr * e, qdd - Kr * Kr * e)
                    for e in tube * directions
                ]
                for q, qd, qdd in zip(self.q, self.qd, self.qdd, strict=True)
            ]
        return self._regressors[key]

    def gain(self, T: float) -> float:
        """The gain ``D`` [N m s/rad] the argument may count on: Theorem 2, the ceiling the
        adaptation reaches at this period; Theorem 1, ``phi_P``."""
        c = self.controller
        if not c.adaptive:
            return c.phi_P
        return max(c.phi_P, PHI_MAX_FACTOR * self.law_bounds.max_upper_eigenvalue / T)

    def _floor_at(self, T: float, d: float, tube: float) -> tuple[float, dict]:
        """The floor for a fixed tube: the worst piece (the joints' Coulomb friction counts as
        disturbance, :class:`JointTerms`)."""
        worst, parts = -math.inf, {}
        d = d + self.joints.coulomb
        for piece in self.pieces:
            floor, piece_parts = piece.floor_at(T, d, tube, self.gain(T))
            if floor > worst or not parts:
                worst, parts = floor, piece_parts
            if not math.isfinite(floor):
                break
        return worst, parts

    def valid(self) -> bool:
        return all(np.all(p.lam_L > 0) for p in self.pieces)

    def floor(self, T: float, d: float, epsilon: float) -> tuple[float, dict]:
        """The smallest tube radius that reproduces itself (fixed point from ``tube = 0``), and
        the parts of the bound (at that tube, or at ``epsilon`` when there is none)."""
        if not self.valid() or not math.isfinite(d):
            return math.inf, {"margin": -math.inf}
        tube = 0.0
        for _ in range(30):
            floor, parts = self._floor_at(T, d, tube)
            if not math.isfinite(floor) or floor > 1e3 * max(epsilon, 1e-9):
                break
            if floor <= tube * (1 + 1e-3):
                return tube, parts
            tube = floor * 1.001
        return math.inf, self._floor_at(T, d, epsilon)[1]

    def max_sample_period(self, epsilon: float, d: float) -> float:
        """The largest ``T`` with ``floor(T) <= epsilon`` in the tube ``||e|| <= epsilon``."""
        if not self.valid():
            return 0.0

        def ok(T: float) -> bool:
            return self._floor_at(T, d, epsilon)[0] <= epsilon

        low, high = 1e-8, 1e-1
        if not ok(low):
            return 0.0
        if ok(high):
            return high
        for _ in range(30):
            middle = math.sqrt(low * high)
            low, high = (middle, high) if ok(middle) else (low, middle)
        return low

    def theorem1_floor(self, kappa_P: float) -> float:
        """Theorem 1: ``||r|| <= sqrt(lambda_max / lambda_min) / kappa_P``, ``||e|| <= ||r|| / Kr``."""
        if not self.valid():
            return math.inf
        figures = self.figures()
        ratio = figures["lambda_U"] / figures["lambda_L"]
        return float(math.sqrt(ratio) / kappa_P / self.Kr.min())


class _Piece:
    """One piece of the box: its inertia bounds and the quantities of the bound on the grid."""

    def __init__(self, grid: FloorGrid, box: ParameterBox):
        self.grid = grid
        bounds = InertiaBounds(grid.controller.robot, box)
        count = len(grid.q)
        self.lam_L, self.lam_U, self.beta, self.nu, self.gamma = (
            np.full(count, math.inf) for _ in range(5)
        )
        #: ``U^T M_L_law^-1`` with ``M_U = U U^T``: ``||M^{1/2} M_L^-1 x|| <= ||U^T M_L^-1 x||``.
        self.to_metric: list[np.ndarray | None] = []
        self.lag_metric = np.full(count, math.inf)
        robot = grid.bound.robot
        self.links = [_link_vertices(robot, b) for b in box.uncertain_links]
        for j, q in enumerate(grid.q):
            ML, MU, M0 = bounds.lower(q), bounds.upper(q), grid.nominal_inertia[j]
            self.lam_L[j] = np.linalg.eigvalsh(ML)[0]
            self.lam_U[j] = np.linalg.eigvalsh(MU)[-1]
            if self.lam_L[j] <= 0:
                self.to_metric.append(None)
                self.beta[j] = -math.inf
                continue
            self.to_metric.append(np.linalg.cholesky(MU).T @ grid.law_inverse[j])
            self.lag_metric[j] = np.linalg.norm(self.to_metric[j] @ grid.torque_rate[j])
            # The law predicts with the whole box's M_L: M_L_law >= beta M on this piece.
            self.beta[j] = scipy.linalg.eigh(grid.law_inertia[j], MU, eigvals_only=True)[0]
            self.nu[j] = max(
                1.0 - scipy.linalg.eigh(M0, MU, eigvals_only=True)[0],
                scipy.linalg.eigh(M0, ML, eigvals_only=True)[-1] - 1.0,
            )
            # In the metric of M >= M_L: ||M^-1/2 X M^-1/2|| <= ||L^-1 X L^-T||.
            L = np.linalg.cholesky(ML)
            n = len(q)
            scaled = [_scaled(L, _scaled(L, C).T) for C in grid.coriolis[j]]
            self.gamma[j] = max(
                math.sqrt(sum(np.linalg.norm(X, 2) ** 2 for X in scaled[:n])),
                math.sqrt(sum(np.linalg.norm(X, 2) ** 2 for X in scaled[n:])),
            )
        Kr = grid.Kr
        uniform = np.ptp(Kr) == 0
        self.K = Kr.max() * (
            1.0 if uniform else np.sqrt(self.lam_U / np.maximum(self.lam_L, 1e-300))
        )
        self._mismatch: dict[float, np.ndarray] = {}

    def mismatch(self, tube: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Over this piece and the tube ``||e|| <= tube``, at each grid point, with ``w`` at
        ``r = 0`` (the part proportional to ``r`` is in ``b``): ``R_j >= ||M_L^-1 w||`` (``M_L``
        the law's prediction inertia), ``RM_j >= ||M^{1/2} M_L^-1 w||`` for every plant of the
        piece, ``V_j >= ||w||`` and ``S_j`` >= the rate of change of
        ``M_L^-1 w`` along the reference (finite difference to the next grid point).

        ``w = sum_l Y_l (pi_l - pi0_l)`` over uncertain links: per link, the maximum of a convex
        norm of ``Y_l delta`` over the barycentric hull of the piece is attained at a vertex, so
        the vertices are enumerated; links are summed (triangle inequality)."""
        key = round(tube, 15)
        if key not in self._mismatch:
            grid = self.grid
            regressors = grid.regressors(tube)
            count = len(regressors)
            R, RM, V, S = (np.zeros(count) for _ in range(4))
            for j in range(count):
                inverse = grid.law_inverse[j]
                for Y in regressors[j]:
                    equilibrium = in_metric = magnitude = 0.0
                    for columns, A, vertices in self.links:
                        torques = Y[:, columns] @ A @ vertices
                        equilibrium += np.sqrt(np.max(np.sum((inverse @ torques) ** 2, axis=0)))
                        image = self.to_metric[j] @ torques
                        in_metric += np.sqrt(np.max(np.sum(image**2, axis=0)))
                        magnitude += np.sqrt(np.max(np.sum(torques**2, axis=0)))
                    R[j], V[j] = max(R[j], equilibrium), max(V[j], magnitude)
                    RM[j] = max(RM[j], in_metric)
                # The joints' smooth terms, per component at most c (triangle inequality).
                c = grid.joints.smooth(grid.qd[j], grid.qdd[j], grid.Kr, tube)
                R[j] += np.linalg.norm(np.abs(inverse) @ c)
                RM[j] += np.linalg.norm(np.abs(self.to_metric[j]) @ c)
                V[j] += np.linalg.norm(c)
                if j + 1 < count:
                    change = 0.0
                    for columns, A, vertices in self.links:
                        step = grid.law_inverse[j + 1] @ regressors[j + 1][0][:, columns]
                        step = (step - inverse @ regressors[j][0][:, columns]) @ A @ vertices
                        change += np.sqrt(np.max(np.sum(step**2, axis=0)))
                    S[j] = (change + grid.joints.change(grid, j, tube)) / grid.grid_step
            S[-1] = S[-2] if count > 1 else 0.0
            self._mismatch[key] = (R, RM, V, S)
        return self._mismatch[key]

    def floor_at(self, T: float, d: float, tube: float, D: float) -> tuple[float, dict]:
        """The floor of this piece for a fixed tube (fixed point of ``||r||`` on the velocity).

        Split ``r = r* + r_d + delta``: ``r* = (T K)^-1 T w`` the equilibrium of the held loop
        for a frozen mismatch (``||r*|| <= T R + V / D``); ``r_d`` the response to the
        disturbance, ``sum_k (1 - M^-1 T K)^k M^-1 T d_k``, whose terms are positive
        semi-definite matrices summing to ``(T K)^-1``, so ``||r_d|| <= T d tr((T K)^-1)`` for
        any sequence ``||d_k|| <= d``; ``delta`` is contracted by ``1 - a + b`` per period and
        forced by the motion of ``r*`` and by ``b`` acting on ``r`` (docs/sampled-data.md)."""
        grid, Kr = self.grid, self.grid.Kr
        R, RM, V, S = self.mismatch(tube)
        beta, lam_L, lam_U = self.beta, self.lam_L, self.lam_U
        a = beta * D * T / (D * T + beta * lam_U)
        speed = np.linalg.norm(grid.qd, axis=1) + Kr.max() * tube
        sqrt_L, sqrt_U = np.sqrt(lam_L), np.sqrt(lam_U)
        equilibrium = T * (R + 0.5 * T * grid.lag) + V / D
        # tr((T K)^-1) = tr(M_L^-1) + n / (D T) for K = D (M_L + D T)^-1 M_L.
        response = T * d * (grid.trace_inverse + len(Kr) / (D * T))
        forcing = sqrt_U * T * (T * S)
        # The same in the plant's metric, ||M^{1/2} x||, for b acting on them.
        equilibrium_M = T * (RM + 0.5 * T * self.lag_metric) + sqrt_U * V / D
        response_M = T * d / (a * sqrt_L)
        r_sup = 0.0
        for _ in range(50):
            b = T * (
                self.K * (0.5 + self.nu)
                + (1.0 + self.nu) * self.gamma * (speed + r_sup)
                + grid.joints.damping / lam_L
            )
            margin = float(np.min(a - b))
            if r_sup == 0.0:
                parts = {"contraction": float(np.min(a)), "margin": margin, "gain_D": float(D)}
            if not margin > 0:
                return math.inf, parts
            deviation = float(np.max(forcing + b * (equilibrium_M + response_M))) / margin
            slow = float(np.max(equilibrium + response))
            new = slow + (deviation + float(forcing.max())) / sqrt_L.min()
            if abs(new - r_sup) <= 1e-6 * new:
                break
            r_sup = new
        parts.update(r_sup=new, r_equilibrium=float(equilibrium.max()))
        return float(new / Kr.min()), parts


def _scaled(L: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``L^{-1} X`` for a lower-triangular ``L``."""
    return scipy.linalg.solve_triangular(L, X, lower=True)


#: At most this many pieces of the box in the certificate (cost grows linearly with it).
PIECES = 4


def split_box(box: ParameterBox, pieces: int = PIECES) -> list[ParameterBox]:
    """The box cut along its widest mass intervals (at most 3, relative to their upper end) into
    at most ``pieces`` boxes whose union is the box."""
    masses = [(link.upper[0] - link.lower[0]) / link.upper[0] for link in box.links]
    order = [k for k in np.argsort(masses)[::-1] if masses[k] > 0][:3]
    if not order:
        return [box]
    cuts = max(2, int(round(pieces ** (1.0 / len(order)))))
    while cuts ** len(order) > pieces and len(order) > 1:
        order = order[:-1]
        cuts = max(2, int(round(pieces ** (1.0 / len(order)))))
    result = [box]
    for k in order:
        split = []
        for piece in result:
            link = piece.links[k]
            edges = np.linspace(link.lower[0], link.upper[0], cuts + 1)
            for low, high in zip(edges[:-1], edges[1:], strict=True):
                lower, upper = link.lower.copy(), link.upper.copy()
                lower[0], upper[0] = low, high
                links = list(piece.links)
                links[k] = dataclasses.replace(link, lower=lower, upper=upper)
                split.append(dataclasses.replace(piece, links=tuple(links)))
        result = split
    return result


def _link_vertices(robot, box) -> tuple[slice, np.ndarray, np.ndarray]:
    """Where a link enters ``Y_SL`` (columns, placement ``A``) and the vertices of its
    barycentric hull relative to the nominal, one per column (uncertain coordinates only)."""
    body, A = link_body_placement(robot, box.link)
    lower, upper = barycentric_enclosure(box)
    nominal = box.standard_parameters(box.nominal)
    free = np.flatnonzero(upper > lower)
    corners = np.array(np.meshgrid(*[(0, 1)] * len(free), indexing="ij")).reshape(len(free), -1)
    vertices = np.zeros((10, corners.shape[1]))
    vertices[free] = np.where(corners, upper[free, None], lower[free, None]) - nominal[free, None]
    return slice(10 * body, 10 * body + 10), A, vertices
