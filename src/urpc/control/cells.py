"""The sampled-data floor of the implicit law, bounded over whole cells of time (docs/sampled-data.md §2).

The reference ``[0, duration]`` (one period of a periodic reference, whose states repeat:
:func:`urpc.trajectories.covered_span`) is cut into cells; each cell is widened by the period
that follows its last sample. Over a cell, the reference lies in a box (:meth:`Trajectory.enclose`, Taylor with
a sound jerk bound), the tube ``||e|| <= rho`` (and ``||r|| <= r_max``) adds a box of errors, and
every quantity of the one-period bound is enclosed over that box of states *and* over the
parameter box by ball arithmetic (:mod:`urpc.model.regressor_balls`): inertia matrices and their
rates, the Slotine-Li regressor and its rate, Coriolis matrices of every plant of the box. No
quantity is taken at a point of the reference: nothing can slip between grid points, whatever the
reference, the period or the duration.

The bounds over one cell are in :mod:`urpc.control.cell_bounds`, the drives' terms in
:mod:`urpc.control.sampled_joints`, the box's pieces in :mod:`urpc.control.box_pieces`; the
one-period floor over the cells' enclosures is :mod:`urpc.control.period_bound`.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.inertia_bounds import InertiaBounds
from ..model.regressor_balls import Ball, BallRegressor, Jet, matvec, parameters_of
from ..model.verified_norms import spectral_norm
from ..trajectories import Trajectory, covered_span
from .box_pieces import split_box
from .cell_bounds import MismatchNorms, coriolis_coefficients, velocity_bound
from .cell_inertia import (
    LAPACK_MARGIN,
    InertiaModel,
    congruence,
    curvatures_for,
    group_curvatures,
    inertia_models,
)
from .cell_partition import CellBatch, Partition, merge_cells
from .interval import IntervalPassivityController
from .parameter_sets import link_parameters, plant_parameters
from .sampled_joints import JointTerms

#: The first cells are cut so that the reference moves at most this far [rad] per joint within
#: one; the search then splits the cells that decide the floor (:meth:`CellFloor.refine`).
CELL_MOTION = 0.02
#: Bounds on the number of first cells.
MIN_CELLS, MAX_CELLS = 8, 4000
#: The second derivatives of M are enclosed over boxes of this many first cells (more on long
#: chains).
CURVATURE_CELLS = 4


class CellFloor:
    """The certificate's quantities over cells of the reference, per piece of the box.

    The cells start coarse and are split where the floor needs it (:meth:`refine`, called by
    the search, :mod:`urpc.control.sampled_search`): each split cell is replaced by its two
    halves, enclosed on their own; every other cell keeps its enclosures. Every cell's
    enclosures hold for every time of the cell (widened by the period that follows), whatever
    the partition: a partition only decides how tight they are.

    Args:
        controller: An implicit sampled-data controller (or any interval controller, for the
            inertia figures of Theorem 1).
        trajectory: The reference; it must give :meth:`Trajectory.jerk_bound`.
        duration: The time span covered [s] (one period of a periodic reference when shorter:
            :attr:`span`).
        cells: Number of first cells (default: the reference moves at most :data:`CELL_MOTION`
            per joint within a cell, between :data:`MIN_CELLS` and :data:`MAX_CELLS`).
    """

    def __init__(
        self,
        controller: IntervalPassivityController,
        trajectory: Trajectory,
        duration: float,
        cells: int | None = None,
    ):
        self.controller = controller
        robot = controller.robot
        self.robot = robot
        self.trajectory = trajectory
        self.duration = float(duration)
        self.Kr = np.asarray(controller.Kr, dtype=float)
        self.dof = robot.dof
        box = controller.bound.box
        self.law_bounds = controller.inertia_bounds or InertiaBounds(robot, box)
        self.joints = JointTerms(controller.bound.joints)
        self.regressor = BallRegressor(robot)
        # A periodic reference repeats its states: one period covers the whole duration.
        self.span = covered_span(trajectory, self.duration)
        if cells is None:
            probe = np.linspace(0.0, self.span, 257)
            speed = float(np.max(np.abs(np.atleast_2d(trajectory.evaluate(probe)[1]))))
            cells = int(math.ceil(self.span * speed / CELL_MOTION))
        first = int(np.clip(cells, MIN_CELLS, MAX_CELLS))
        # The second derivatives of M are enclosed over boxes of consecutive first cells (and
        # reused by their halves): CURVATURE_CELLS of them, times (n + 1) / 8 on chains of more
        # than 7 links, so that their n (n + 1) / 2 pairs cost what the n first derivatives do
        # and the cost grows as n^3 (a second-order term: a coarser box costs little).
        size = max(1, min(CURVATURE_CELLS * math.ceil((self.dof + 1) / 8), first))
        self.partition = Partition(self.span, first, size)
        # Models: nominal, the law's lower bound, then (lower, upper) per piece.
        self.pieces = split_box(box)
        piece_bounds = [InertiaBounds(robot, piece) for piece in self.pieces]
        models = [robot, self.law_bounds.lower_robot]
        for bounds in piece_bounds:
            models += [bounds.lower_robot, bounds.upper_robot]
        self._parameters = np.stack([parameters_of(m) for m in models])
        self._armature = np.stack([np.asarray(m.model.armature, dtype=float) for m in models])
        self._links = [[link_parameters(robot, b) for b in p.uncertain_links] for p in self.pieces]
        self._plant_set = plant_parameters(robot, box)
        self._piece_sets = [plant_parameters(robot, piece) for piece in self.pieces]
        self._cache: dict[tuple, dict] = {}
        self._tube_cache: dict[tuple, dict] = {}
        self._curvature_cache: dict[tuple, Ball] = {}
        self._model_cache: dict[tuple, tuple] = {}

    # ------------------------------------------------------------------------- the partition
    @property
    def cells(self) -> int:
        """The number of cells of the partition."""
        return self.partition.count

    def spans(self) -> tuple[np.ndarray, np.ndarray]:
        """Every cell's ``[start, end]`` [s] (before widening), in the order of the cell axis of
        :meth:`quantities`."""
        cells = self.partition.cells()
        return cells.start, cells.end

    def refine(self, cells, own_curvatures: bool = False) -> int:
        """Split the given cells (indices along the cell axis of :meth:`quantities`) in two
        halves each (:meth:`Partition.split`; ``own_curvatures``: the halves take the second
        derivatives of ``M`` over their own boxes); the halves are enclosed when next asked
        for. Returns how many cells were split."""
        split = self.partition.split(cells, own_curvatures)
        if split:
            self._cache.clear()
        return split

    # ------------------------------------------------------------------------- cell boxes
    def _states(
        self, batch: CellBatch, tube: float, r_max: float, extension: float, along_reference=False
    ):
        """Jets over the cells of a batch: ``q``, ``qd_a`` (= ``qd`` at ``r = 0``), ``qdd_a`` at
        ``r = 0``, and the plant's velocity ball with ``||r|| <= r_max``. The rates are those of
        the actual motion (``e`` moves at ``ed``), or with ``along_reference`` those of the
        reference at a fixed error (the error's own motion is then counted through the tube's
        Jacobian)."""
        Kr = self.Kr
        q, rq, qd, rqd, qdd, rqdd, J = self.trajectory.enclose(batch.start, batch.end + extension)
        e = np.full(self.dof, tube)
        ed = r_max + Kr * tube  # |ed_i| <= ||r|| + Kr_i ||e||
        velocity = Ball(qd, rqd + ed)  # the plant's qd = qd_d - ed
        q_jet = Jet(Ball(q, rq + e), velocity)
        qd_a = Jet(Ball(qd, rqd + Kr * e), Ball(qdd, rqdd + Kr * ed))
        qdd_a = Jet(Ball(qdd, rqdd + Kr * Kr * e), Ball(np.zeros_like(J), J + Kr * Kr * ed))
        if along_reference:
            q_jet = Jet(q_jet.val, Ball(qd, rqd))
            qd_a = Jet(qd_a.val, Ball(qdd, rqdd))
            qdd_a = Jet(qdd_a.val, Ball(np.zeros_like(J), J))
        return q_jet, qd_a, qdd_a, velocity

    def quantities(self, tube: float, r_max: float, extension: float) -> dict:
        """Every cell's enclosures for the tube ``||e|| <= tube``, ``||r|| <= r_max`` [rad, rad/s],
        cells widened by ``extension`` [s] (cached until the next :meth:`refine`): per-cell
        arrays, the cells along their first axis (the last for ``R``, ``RM``, ``V``, ``Rs`` and
        ``R_links``) in the order of :meth:`spans` (also given as ``cell_start``,
        ``cell_end``). The enclosures over the tube (:meth:`_tube_enclosures`, the costly
        part) are computed once per batch of cells and do not depend on ``r_max``: only the
        plant's velocity box and the rates do, and they enter affinely, so a new ``r_max``
        costs a recombination only."""
        partition = self.partition
        key = (round(tube, 15), round(r_max, 12), round(extension, 15), partition.generation)
        if key in self._cache:
            return self._cache[key]
        used = partition.used()
        out = merge_cells(
            [self._batch_quantities(partition.batches[k], k, tube, r_max, extension) for k in used],
            [partition.active[k] for k in used],
        )
        out["cell_start"], out["cell_end"] = self.spans()
        self._cache[key] = out
        return out

    def quantities_of(self, cells, tube: float, r_max: float, extension: float) -> dict:
        """:meth:`quantities` of some cells only (indices along the cell axis), not cached:
        bounds over those cells' times alone (a floor from them is at most the whole
        reference's)."""
        batch = self.partition.cells()[np.asarray(cells, dtype=int)]
        out = self._batch_quantities(batch, None, tube, r_max, extension)
        out["cell_start"], out["cell_end"] = batch.start, batch.end
        return out

    def _batch_quantities(
        self, batch: CellBatch, index: int | None, tube: float, r_max: float, extension: float
    ) -> dict:
        """:meth:`quantities` for the cells of one batch (its enclosures cached under its index
        in the partition, unless ``None``)."""
        enclosed = self._tube_enclosures(batch, index, tube, extension)
        _, qd_a, qdd_a, _ = self._states(batch, tube, r_max, extension)
        # The plant's velocity qd = qd_d - ed: the reference's box plus the error's rate, a ball
        # ||ed|| <= ||r|| + ||Kr e|| (componentwise |ed_i| <= ||r|| + Kr_i ||e||).
        reference_velocity = enclosed["reference_velocity"]
        ed, ed_norm = r_max + self.Kr * tube, r_max + float(self.Kr.max()) * tube
        law = enclosed["law"]
        # ||M_L^-1/2 dM_L/dt M_L^-1/2|| <= sum_k |qd_k| s_k / (1 - eps), qd the plant's velocity.
        slopes = enclosed["law_slopes"]
        law_rate_norm = velocity_bound(
            np.sum(reference_velocity.magnitude * slopes, axis=-1), slopes, 0.0, ed, ed_norm
        ) / (1 - np.minimum(law.eps, 0.999999))
        nominal = enclosed["nominal"]
        slopes = enclosed["nominal_slopes"]
        nominal_rate_norm = velocity_bound(
            np.sum(reference_velocity.magnitude * slopes, axis=-1), slopes, 0.0, ed, ed_norm
        ) / (1 - np.minimum(nominal.eps, 0.999999))
        # Drives: smooth terms per component (values and rates), and the drive torque's rate.
        drive, drive_rate = self.joints.mismatch(qd_a, qdd_a) or (None, None)
        torque_rate_max = enclosed["torque_rate"] + self.joints.nominal_torque_rate(qd_a, qdd_a)
        out = dict(
            enclosed["global"], r_max=float(r_max), mu_law=law_rate_norm,
            mu_nominal=nominal_rate_norm, pieces=[],
        )  # fmt: skip
        for piece in enclosed["pieces"]:
            metrics = piece["metrics"]
            R, RM, Rs, V = piece["R"], piece["RM"], piece["Rs"], piece["V"]
            Rdot, RdotM, Vdot = piece["Rdot"], piece["RdotM"], piece["Vdot"]
            if drive is not None:
                equilibrium, metric, scaled, magnitude = metrics.vector(drive)
                R, RM, Rs, V = R + equilibrium, RM + metric, Rs + scaled, V + magnitude
                equilibrium, metric, _, magnitude = metrics.vector(drive_rate)
                Rdot, RdotM, Vdot = Rdot + equilibrium, RdotM + metric, Vdot + magnitude
            # Rate of the nominal torque (the held torque lags it), in both metrics.
            lag, lag_M = (x[0] for x in metrics.vector(torque_rate_max)[:2])
            # d/dt (M_L^-1 w) = M_L^-1 (dw/dt) - M_L^-1 (dM_L/dt) M_L^-1 w.
            # In the plant's metric: ||M^1/2 M_L^-1/2|| <= beta^-1/2 (M_L >= beta M_U >= beta M).
            lam_law = np.maximum(out["law_lam_L"], 1e-300)
            inverse_change = law_rate_norm / np.sqrt(lam_law)
            beta = piece["static"]["beta"]
            with np.errstate(divide="ignore", invalid="ignore"):
                metric_change = np.where(beta > 0, law_rate_norm / np.sqrt(beta), math.inf)
            # The plant's C on r over the velocity box (affine in its radii), in M_L's metric.
            constant, per_velocity = piece["coriolis_coefficients"]
            gamma = velocity_bound(constant, per_velocity, reference_velocity.rad, ed, ed_norm)
            gamma = gamma * piece["to_lower"] * (1 + LAPACK_MARGIN)
            metric_rate = 2.0 * gamma  # ||M^-1/2 (C + C^T) M^-1/2|| <= 2 ||M^-1/2 C M^-1/2||
            out["pieces"].append(
                dict(
                    piece["static"],
                    R=R, RM=RM, V=V, Rs=Rs,
                    rate_inverse=Rdot[0], inverse_change=inverse_change, rate=Vdot[0],
                    rate_inverse_M=RdotM[0], inverse_change_M=metric_change,
                    lag=lag, lag_M=lag_M,
                    coriolis=gamma + piece["gamma_delta"], metric_rate=metric_rate,
                    gamma=gamma, gamma_delta=piece["gamma_delta"],
                )
            )  # fmt: skip
        # C0 of the nominal plant (in the box, so in a piece) in the metric of any piece's
        # M_L, which M0 dominates: the largest of the pieces' bounds.
        out["gamma_nominal"] = np.max([p["gamma"] for p in out["pieces"]], axis=0)
        return out

    def _tube_enclosures(
        self, batch: CellBatch, index: int | None, tube: float, extension: float
    ) -> dict:
        """The enclosures over the tube ``||e|| <= tube`` that do not depend on ``r_max``, for
        the cells of one batch (cached under its index, unless ``None``): inertia models, the
        mismatch and its rate along the reference, the Coriolis terms as coefficients of the
        velocity radii."""
        key = (index, round(tube, 15), round(extension, 15))
        if index is not None and key in self._tube_cache:
            return self._tube_cache[key]
        cells = len(batch)
        q, qd_a, qdd_a, _ = self._states(batch, tube, 0.0, extension)
        # The reference's own states (e = 0, r = 0): its positions, velocity box, jerk, and the
        # plant's torque along it.
        reference_states = self._states(batch, 0.0, 0.0, extension)
        reference_q = reference_states[0].val
        models, model_slopes = self._batch_models(batch, index, tube, extension)
        nominal, law = models[0], models[1]
        # d/dt w = (rate along the reference at a fixed e) + (Jacobian along e) ed.
        reference = self._states(batch, tube, 0.0, extension, along_reference=True)
        Y = self.regressor.slotine_li(reference[0], reference[1], reference[1], reference[2])
        center, tube_jacobian = self._mismatch_parts(batch, tube, extension)
        # The plant's Coriolis matrix (every plant of the piece, over the plant's velocity box,
        # affine in its radii) and the Coriolis mismatch along qd_a, as centered forms over each
        # piece's own parameter hull, through the piece's M_L factor (cell by cell chunks, see
        # coriolis_coefficients).
        lowers = [models[2 + 2 * k] for k in range(len(self._links))]
        forms = [
            (q.dot.mid, piece_set, lower.inverse_factor)
            for piece_set, lower in zip(self._piece_sets, lowers, strict=True)
        ] + [
            (qd_a.val.mid, piece_set.shifted(self._parameters[0]), lower.inverse_factor)
            for piece_set, lower in zip(self._piece_sets, lowers, strict=True)
        ]
        coefficients = coriolis_coefficients(self.regressor, q.val, reference_q.rad, tube, forms)
        coriolis, coriolis_mismatch = coefficients[: len(lowers)], coefficients[len(lowers) :]
        # d/dt of the nominal torque Y_SL pi0 (held over the period while the reference moves).
        pi0 = Ball.point(self._parameters[0])
        torque_rate = matvec(Y.dot, pi0)
        # The nominal torque's Jacobian along e: |(G pi0) ed|_i <= sqrt(sum_k (G pi0)_ik^2) ||ed||.
        along_error = matvec(tube_jacobian, pi0)  # (cells, k, n)
        torque_per_error_rate = np.sqrt(
            np.sum((np.abs(along_error.mid) + along_error.rad) ** 2, axis=1)
        )
        reference_velocity = reference_states[3]
        # |tau_i| of every plant of the box at r = 0 along the reference, and its growth per
        # unit ||e|| over the tube (the rigid bodies by the regressor over the parameter hull,
        # the tube by the Jacobian, the drives at their ends): plant_torque(quantities, rho).
        rigid = self._plant_set.magnitude(center)
        rigid_along = self._plant_set.magnitude(tube_jacobian)
        plant_torque = rigid + self.joints.plant_torque(reference_states[1], reference_states[2])
        plant_torque_per_error = np.sqrt(np.sum(rigid_along**2, axis=1))
        plant_torque_per_error = plant_torque_per_error + self.joints.plant_torque_per_error(
            self.Kr
        )
        # The law's nominal torque at r != 0 differs from its value at r = 0 by
        # M0 Kr r - C0(q, r) qd_a = M0 Kr r - C0(q, qd_a) r (+ Ia0 Kr r): per joint at most
        # (Kr ||M0 e_i|| + ||row_i C0(q, qd_a)|| + Ia0_i Kr) ||r||, with
        # ||M0 e_i|| <= sqrt(lambda_max(M0) (M0)_ii) (M0 positive definite).
        Kr_max = float(self.Kr.max())
        eps0 = 1 + nominal.eps[:, None]
        rows_M0 = np.sqrt(
            eps0 * np.linalg.eigvalsh(nominal.center)[:, -1:]
            * eps0 * np.diagonal(nominal.center, axis1=-2, axis2=-1)
        )  # fmt: skip
        C0 = self.regressor.coriolis_matrices(q.val, qd_a.val, pi0.mid[None])[:, 0]
        rows_C0 = np.sqrt(np.sum(C0.magnitude**2, axis=-1))
        per_r = Kr_max * rows_M0 * (1 + LAPACK_MARGIN) + rows_C0
        if self.joints.box is not None:
            per_r = per_r + self.joints.box.nominal[0] * Kr_max
        # For the delayed law (urpc.control.delay_bound): the nominal model's range, the law's
        # M_L against it (through the nominal centre's factor), the nominal torque's Jacobian
        # along e in the 2-norm, and the reference's jerk.
        eps0 = np.minimum(nominal.eps, 0.999999)
        eps_law = np.minimum(law.eps, 0.999999)
        law_over_nominal = np.linalg.eigvalsh(congruence(nominal.inverse_factor, law.center))
        jerk = reference_states[2].dot.rad
        # ||M0^-1/2 (G pi0) M0^-1/2|| through the nominal centre's factor P0 (the Jacobian's
        # ball and the products' rounding entrywise), over the cell: / (1 - eps0).
        P0 = nominal.inverse_factor
        jacobian_mid = np.swapaxes(along_error.mid, -1, -2)  # (cells, i, k): d tau_i / d e_k
        slack = np.swapaxes(along_error.rad, -1, -2) + 4 * (self.dof + 1) * np.finfo(
            float
        ).eps * np.abs(jacobian_mid)  # the ball, and the rounding of the centre's products
        torque_per_error_N = (
            spectral_norm(P0 @ jacobian_mid @ np.swapaxes(P0, -1, -2))
            + spectral_norm(np.abs(P0) @ slack @ np.swapaxes(np.abs(P0), -1, -2))
        ) / (1 - eps0)
        if self.joints.box is not None:  # d/de (Ia0 qdd_a + Dv0 qd_a) at r = 0
            Dv0 = self.joints.box.nominal[1]
            # |N^-1/2 diag N^-1/2| <= Kr^2 (Ia0 <= N) + max Dv0 Kr / lambda_min(N)
            torque_per_error_N = (
                torque_per_error_N
                + Kr_max**2
                + float(np.max(Dv0)) * Kr_max / (nominal.lam_min * (1 - eps0))
            )
        enclosed = {
            "reference_velocity": reference_velocity,
            "law": law,
            "law_slopes": model_slopes[1],
            "nominal": nominal,
            "nominal_slopes": model_slopes[0],
            "torque_rate": np.abs(torque_rate.mid) + torque_rate.rad,
            "global": {
                "tube": float(tube),
                "valid": nominal.valid & law.valid,
                "trace_inverse": np.trace(law.inverse, axis1=-2, axis2=-1)
                / (1 - np.minimum(law.eps, 0.999999))
                * (1 + LAPACK_MARGIN),
                "law_lam_L": law.lam_min * (1 - law.eps) * (1 - LAPACK_MARGIN),
                "law_inverse_diagonal": np.diagonal(law.inverse, axis1=-2, axis2=-1),
                "plant_torque_reference": plant_torque * (1 + 1e-12),
                "plant_torque_per_error": plant_torque_per_error * (1 + 1e-12),
                "torque_per_r": per_r * (1 + 1e-12),
                "nominal_lam_min": nominal.lam_min * (1 - eps0) * (1 - LAPACK_MARGIN),
                "nominal_lam_max": nominal.lam_max * (1 + nominal.eps) * (1 + LAPACK_MARGIN),
                "nominal_eps": nominal.eps,
                "law_lam_max": law.lam_max * (1 + law.eps) * (1 + LAPACK_MARGIN),
                "law_over_nominal_low": law_over_nominal[:, 0]
                * (1 - eps_law)
                / (1 + nominal.eps)
                * (1 - LAPACK_MARGIN),
                "law_over_nominal_high": law_over_nominal[:, -1]
                * (1 + law.eps)
                / (1 - eps0)
                * (1 + LAPACK_MARGIN),
                "torque_per_error_N": torque_per_error_N * (1 + 1e-9),
                "jerk": np.sqrt(np.sum(jerk**2, axis=-1)) * (1 + 1e-12),
                # ||M_L^-1/2 (M_L(q') - M_L(q)) M_L^-1/2|| <= ||q' - q|| ||s|| / (1 - eps).
                "law_slope_norm": np.sqrt(np.sum(model_slopes[1] ** 2, axis=-1))
                / (1 - eps_law)
                * (1 + 1e-12),
            },
            "pieces": [],
        }
        valid_global = enclosed["global"]["valid"]
        for k, links in enumerate(self._links):
            lower, upper = models[2 + 2 * k], models[3 + 2 * k]
            lam_L = np.maximum(lower.lam_min * (1 - lower.eps), 0.0) * (1 - LAPACK_MARGIN)
            lam_U = upper.lam_max * (1 + upper.eps) * (1 + LAPACK_MARGIN)
            valid = lower.valid & upper.valid & valid_global
            # Generalized eigenvalues through the Cholesky factors: lambda(A, B) = lambda(P A P^T).
            generalized = np.linalg.eigvalsh(congruence(upper.inverse_factor, law.center))[:, 0]
            low = np.linalg.eigvalsh(congruence(upper.inverse_factor, nominal.center))[:, 0]
            high = np.linalg.eigvalsh(congruence(lower.inverse_factor, nominal.center))[:, -1]
            beta = np.where(valid, generalized * (1 - law.eps) / (1 + upper.eps), -math.inf)
            nu = np.maximum(
                1.0 - low * (1 - nominal.eps) / (1 + upper.eps),
                high * (1 + nominal.eps) / (1 - np.minimum(lower.eps, 0.999999)) - 1.0,
            )
            nu = np.where(valid, nu, math.inf)
            # The spectrum of M^-1 M0 over the piece (the delayed law's H), and the law's M_L
            # against the piece's: lambda_max(M_L,piece^-1 M_L,law) (its coupling).
            h1 = low * (1 - eps0) / (1 + upper.eps) * (1 - LAPACK_MARGIN)
            h2 = high * (1 + nominal.eps) / (1 - np.minimum(lower.eps, 0.999999))
            law_over_lower = np.linalg.eigvalsh(congruence(lower.inverse_factor, law.center))
            kappa = law_over_lower[:, -1] * (1 + law.eps) / (1 - np.minimum(lower.eps, 0.999999))
            beta = beta * (1 - LAPACK_MARGIN)
            nu = nu * (1 + LAPACK_MARGIN) + LAPACK_MARGIN
            metrics = MismatchNorms(law, upper)
            # (centre, per unit of tube) pairs, (2, cells): R(rho) = R[0] + rho R[1].
            R, RM, Rs, V = (np.zeros((2, cells)) for _ in range(4))
            Rdot, RdotM, Vdot = (np.zeros((2, cells)) for _ in range(3))
            per_link = []  # each link's part of R, for the report
            for link in links:
                # Value: the reference cell at e = 0, plus the tube by its Jacobian (mean value).
                columns = link.columns
                equilibrium, metric, scaled, magnitude = metrics.link(
                    center[..., columns], tube_jacobian[..., columns], link
                )
                R, RM, Rs, V = R + equilibrium, RM + metric, Rs + scaled, V + magnitude
                per_link.append(equilibrium)
                # Rate along the reference at a fixed error, over the whole box.
                equilibrium, metric, _, magnitude = metrics.link(Y.dot[..., columns], None, link)
                Rdot, RdotM, Vdot = Rdot + equilibrium, RdotM + metric, Vdot + magnitude
            lag_e, lag_M_e = (x[0] for x in metrics.vector(torque_per_error_rate)[:2])
            to_lower = 1.0 / (1 - np.minimum(lower.eps, 0.999999)) * (1 + LAPACK_MARGIN)
            constant, per_velocity = coriolis_mismatch[k]
            # Along qd_a = qd_d + Kr e: the reference's box plus Kr e with ||e|| <= tube.
            gamma_delta = velocity_bound(
                constant, per_velocity, reference_velocity.rad, self.Kr * tube, tube, self.Kr
            )
            gamma_delta = gamma_delta * to_lower
            uniform = np.ptp(self.Kr) == 0
            K = self.Kr.max() * (1.0 if uniform else np.sqrt(lam_U / np.maximum(lam_L, 1e-300)))
            enclosed["pieces"].append(
                {
                    "metrics": metrics,
                    "R": R, "RM": RM, "Rs": Rs, "V": V, "Rdot": Rdot, "RdotM": RdotM,
                    "Vdot": Vdot,
                    "coriolis_coefficients": coriolis[k],
                    "to_lower": to_lower,
                    "gamma_delta": gamma_delta * (1 + LAPACK_MARGIN),
                    "static": {
                        "valid": valid & (lam_L > 0) & (beta > 0),
                        "lam_L": lam_L, "lam_U": lam_U, "beta": beta, "nu": nu, "K": K,
                        # beta at the cell's centre, without the models' radii (for the advice).
                        "beta_center": generalized,
                        "h1": np.where(valid, h1, 0.0),
                        "h2": np.where(valid, h2 * (1 + LAPACK_MARGIN), math.inf),
                        "kappa": np.where(valid, kappa * (1 + LAPACK_MARGIN), math.inf),
                        "lag_e": lag_e, "lag_M_e": lag_M_e,
                        "R_links": np.array(per_link).reshape(len(links), 2, cells),
                        # M_ii <= (1 + eps_U) (U_c)_ii: the plant's diagonal, for the torques.
                        "upper_diagonal": np.diagonal(upper.center, axis1=-2, axis2=-1)
                        * (1 + upper.eps[:, None])
                        * (1 + LAPACK_MARGIN),
                    },
                }
            )  # fmt: skip
        if index is not None:
            self._tube_cache[key] = enclosed
        return enclosed

    def _batch_models(
        self, batch: CellBatch, index: int | None, tube: float, extension: float
    ) -> tuple[list[InertiaModel], list[np.ndarray]]:
        """Every inertia model over the cells of one batch and the tube (cached under its index,
        unless ``None``)."""
        key = (index, round(tube, 15), round(extension, 15))
        if index is not None and key in self._model_cache:
            return self._model_cache[key]
        q = self._states(batch, tube, 0.0, extension)[0].val
        reference_radii = self._states(batch, 0.0, 0.0, extension)[0].val.rad
        out = self._inertia_models(batch, q, reference_radii, tube, extension)
        if index is not None:
            self._model_cache[key] = out
        return out

    def model_validity(self, tube: float, extension: float) -> tuple[np.ndarray, np.ndarray]:
        """Per cell of the partition (the cell axis of :meth:`quantities`), whether every
        inertia model holds over it and the tube (nominal, the law's ``M_L``, each piece's
        ``M_L`` and ``M_U``: ``M_c`` positive definite and ``eps < 1``), and whether a narrower
        cell could make the failing ones hold (the tube's own part of ``eps`` is below 1).
        Only the inertia models are enclosed (cached for :meth:`quantities`): a cell where one
        fails has no floor at any period, whatever the rest."""
        valid, splittable = [], []
        partition = self.partition
        for index in partition.used():
            batch, active = partition.batches[index], partition.active[index]
            models, _ = self._batch_models(batch, index, tube, extension)
            valid.append(np.all([m.valid for m in models], axis=0)[active])
            splittable.append(np.all([m.eps_tube < 1 for m in models], axis=0)[active])
        return np.concatenate(valid), np.concatenate(splittable)

    def model_figures(self, tube: float, extension: float) -> dict[str, float]:
        """:meth:`figures` from the inertia models alone, for a partition where one fails
        (``beta`` ``-inf`` and ``nu`` ``inf``: they are not bounded there)."""
        lower, upper = math.inf, 0.0
        partition = self.partition
        for index in partition.used():
            batch, active = partition.batches[index], partition.active[index]
            models, _ = self._batch_models(batch, index, tube, extension)
            for low, high in zip(models[2::2], models[3::2], strict=True):
                lam_L = np.where(low.valid, low.lam_min * (1 - low.eps), -math.inf)[active]
                lower = min(lower, float(np.min(lam_L)) * (1 - LAPACK_MARGIN))
                high_U = (high.lam_max * (1 + high.eps))[active]
                upper = max(upper, float(np.max(high_U)) * (1 + LAPACK_MARGIN))
        return {
            "cells": float(self.cells), "pieces": float(len(self.pieces)),
            "lambda_L": lower, "lambda_U": upper, "beta": -math.inf, "nu": math.inf,
        }  # fmt: skip

    def inertia_figures(self, extension: float) -> dict[str, float]:
        """Only ``lambda_L`` (the lightest mode of every piece's lower bound) and ``lambda_U``
        over the cells at ``e = 0``: what Theorem 1 and the paper law's condition need, without
        the mismatch and Coriolis enclosures."""
        figures = self.model_figures(0.0, extension)
        return {name: figures[name] for name in ("cells", "lambda_L", "lambda_U")}

    def _inertia_models(
        self, batch: CellBatch, q: Ball, reference_radii: np.ndarray, tube: float, extension: float
    ) -> tuple[list[InertiaModel], list[np.ndarray]]:
        """Every inertia model (nominal, the law's ``M_L``, each piece's ``M_L`` and ``M_U``) over
        the cells of a batch (:func:`~urpc.control.cell_inertia.inertia_models`), ``q`` the box
        of each cell with the tube."""
        curvatures, group = self._curvatures(batch, q, tube, extension)
        return inertia_models(
            self.regressor, self._parameters, self._armature, q, reference_radii, tube,
            curvatures, group,
        )  # fmt: skip

    def _curvatures(
        self, batch: CellBatch, q: Ball, tube: float, extension: float
    ) -> tuple[Ball, np.ndarray]:
        """The second derivatives of every model's ``M`` over boxes that hold the cells of a
        batch (``q`` their boxes), and the box of each cell (:func:`curvatures_for`), the groups'
        boxes enclosed once per tube."""
        key = (round(tube, 15), round(extension, 15))
        if key not in self._curvature_cache:
            first = self.partition.batches[0]
            box = self._states(first, tube, 0.0, extension)[0].val
            self._curvature_cache[key] = group_curvatures(
                self.regressor, self._parameters, box, first.group
            )
        boxes, curvatures = self._curvature_cache[key]
        return curvatures_for(
            self.regressor, self._parameters, boxes, curvatures, q, batch.group, batch.own
        )

    def _mismatch_parts(self, batch: CellBatch, tube: float, extension: float):
        """``Y_SL`` over each cell of the reference at ``e = 0`` (a ball), and its Jacobian along
        each error direction ``e_k`` over the whole tube (a ball, (cells, k, n, 10 n)): at
        ``r = 0`` the state is ``(q_d - e, qd_d + Kr e, qd_d + Kr e, qdd_d - Kr^2 e)``, so that
        ``w(t, e) = w(t, 0) + sum_k e_k dw/de_k(xi)`` for some ``xi`` in the tube."""
        q0, qd0, qdd0, _ = self._states(batch, 0.0, 0.0, extension)
        center = self.regressor.slotine_li(q0.val, qd0.val, qd0.val, qdd0.val)
        q, qd_a, qdd_a, _ = self._states(batch, tube, 0.0, extension)
        n, Kr = self.dof, self.Kr
        eye = np.eye(n)

        def directed(ball, direction):
            value = ball.val.map(lambda x: np.broadcast_to(x[:, None, :], (x.shape[0], n, n)))
            rate = np.broadcast_to(direction, value.shape)
            return Jet(value, Ball.point(rate))

        jets = (
            directed(q, -eye),
            directed(qd_a, eye * Kr),
            directed(qd_a, eye * Kr),
            directed(qdd_a, -eye * Kr * Kr),
        )
        jacobian = self.regressor.slotine_li(*jets).dot  # (cells, k, n, 10 n)
        return center, jacobian

    def figures(self, quantities: dict) -> dict[str, float]:
        pieces = quantities["pieces"]
        return {
            "cells": float(len(quantities["cell_start"])),
            "pieces": float(len(pieces)),
            "lambda_L": float(min(np.min(p["lam_L"]) for p in pieces)),
            "lambda_U": float(max(np.max(p["lam_U"]) for p in pieces)),
            "beta": float(min(np.min(p["beta"]) for p in pieces)),
            "nu": float(max(np.max(p["nu"]) for p in pieces)),
        }


def plant_torque(quantities: dict, tube: float) -> np.ndarray:
    """``|tau_i|`` [N m] of every plant of the box at ``r = 0`` over the tube ``||e|| <= tube``
    (at most the enclosures' own tube), per cell and joint: the reference's part plus the
    tube's, whose Jacobian is enclosed over the enclosures' tube (the mean value theorem)."""
    if not tube <= quantities["tube"]:
        raise ValueError(f"the tube {tube:g} is wider than the enclosures' {quantities['tube']:g}")
    along, per_error = quantities["plant_torque_reference"], quantities["plant_torque_per_error"]
    return (along + tube * per_error) * (1 + 1e-12)
