"""The one-period bound of the implicit law (docs/sampled-data.md §2) over the cells' enclosures.

:class:`~urpc.control.cells.CellFloor` encloses every quantity over cells of time, the tube and
the box; :class:`PeriodBound` turns those enclosures into the argument's figures for a period
``T`` and a disturbance ``d``: each cell's contraction ``a``, perturbation ``b``, quasi-static
error, disturbance response and forcing (:meth:`PeriodBound.cell_terms`), the ultimate bound of
``||e||`` as their extremes over the cells and pieces (:meth:`PeriodBound.floor_at`), and the
torque the law commands in that regime (:meth:`PeriodBound.torque_bound`).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .cells import CellFloor, plant_torque

#: The cells within this fraction of a term's extreme are split (:meth:`PeriodBound.critical_cells`).
CRITICAL_SHARE = 0.05
#: ... unless more than this fraction of the cells are (the term is nearly flat over them).
FLAT_FRACTION = 0.25
#: ... and more than this many (on a short reference of a few cells, a quarter of them is no
#: sign that the term is flat: z1 at 8 us over 0.5 s, 25 cells, none split, floor 1.67e-2
#: against 8.0e-3 over 2 s).
FLAT_CELLS = 16


class PeriodBound:
    """The floor and its parts from a :class:`CellFloor`'s enclosures (same controller)."""

    def __init__(self, cells: CellFloor):
        self.cells = cells
        self.controller = cells.controller
        self.joints = cells.joints
        self.Kr = cells.Kr
        self.dof = cells.dof

    def gain(self, T: float) -> float:
        """The gain ``D`` [N m s/rad] the argument counts on at period ``T``: the feedback law's
        own ceiling at ``T`` (Theorem 2, shared with the law, so it needs no bound of its own) or
        ``phi_P`` (Theorem 1)."""
        c = self.controller
        return c.gain_law.settled_phi(c.feedback.phi_ceiling(c.phi_P, T))

    def gain_varies(self, T: float) -> bool:
        """Whether the law's ``D`` can differ from one sample to the next once the gains have
        saturated: the implicit law caps ``D`` at its ceiling, which Theorem 2's gains reach
        (and Theorem 1's ``phi_P`` when it is at least the ceiling), so ``D`` is then the cap
        at every sample; below it ``D = kappa ||rho|| + phi_P`` moves with ``||rho||``."""
        c = self.controller
        return self.gain(T) < c.feedback.phi_ceiling(c.phi_P, T)

    def floor_at(
        self, T: float, d: float, quantities: dict, tube: float | None = None
    ) -> tuple[float, dict]:
        """The ultimate bound of ``||e||`` for period ``T`` [s] and disturbance ``d`` [N m] in the
        tube ``||e|| <= tube`` (at most the tube the quantities were enclosed over); the worst
        piece (the largest floor; among pieces with none, the least margin ``a - b``), with its
        parts."""
        tube = quantities["tube"] if tube is None else tube
        if tube > quantities["tube"] * (1 + 1e-12):
            raise ValueError("the tube exceeds the one the quantities were enclosed over")
        d = d + self.joints.coulomb
        D = self.gain(T)
        worst, parts = -math.inf, {}
        for piece_index, p in enumerate(quantities["pieces"]):
            floor, piece_parts = self._piece_floor(T, d, D, quantities, p, tube)
            piece_parts["piece"] = piece_index
            # The worst piece: the largest floor, and among infinite ones the least margin.
            if not parts or (floor, -piece_parts["margin"]) > (worst, -parts["margin"]):
                worst, parts = floor, piece_parts
        return worst, parts

    def critical_cells(
        self, T: float, d: float, quantities: dict, tube: float, share: float = CRITICAL_SHARE
    ) -> np.ndarray:
        """The cells that decide the floor at period ``T`` in the tube ``tube`` (indices along
        the cell axis), the ones to split: on every piece whose floor is within ``share`` of the
        worst, the cells where the contraction margin ``a - b`` is not positive; when none is,
        the cells within ``share`` of an extreme of a term the floor takes over the cells (the
        least margin, the largest quasi-static error plus response, pushed deviation and
        forcing). Failing margins and the terms are left alone where more than
        :data:`FLAT_FRACTION` of the cells are near (the period, not the cells' width, is then
        the cause). (Cells whose inertia models fail are split before, by
        :meth:`~urpc.control.sampled_search.SampledSearch.floor`.)"""
        d = d + self.joints.coulomb
        D = self.gain(T)
        floors, terms_of = [], []
        for p in quantities["pieces"]:
            floors.append(self._piece_floor(T, d, D, quantities, p, tube)[0])
            terms_of.append(self.cell_terms(T, d, D, quantities, p, tube))
        worst = max(floors)
        chosen = np.zeros(len(quantities["cell_start"]), dtype=bool)
        for floor, p, terms in zip(floors, quantities["pieces"], terms_of, strict=True):
            if floor < worst * (1 - share):
                continue
            failing = p["valid"] & ~(terms["margin"] > 0)
            if failing.any() or not p["valid"].all():
                near = [failing]
            else:
                near = [terms["margin"] <= terms["margin"].min() * (1 + share)]
                near += [
                    terms[k] >= terms[k].max() * (1 - share) for k in ("slow", "pushed", "forcing")
                ]
            # A term nearly flat over the cells (or failing on most of them: the period, not the
            # cells' width, is the cause) gains little from splitting.
            for cells in near:
                if cells.sum() <= max(FLAT_CELLS, FLAT_FRACTION * len(cells)):
                    chosen |= cells
        return np.flatnonzero(chosen)

    def cell_floors(self, T: float, d: float, quantities: dict, tube: float) -> np.ndarray:
        """Per cell, the floor that cell alone would give at ``rho = 0`` on its worst piece (its
        quasi-static error and response plus its pushed deviation over its own margin and its
        forcing, back from the plant's metric; ``inf`` where the margin or a model fails): what
        ranks the cells that decide the floor."""
        d = d + self.joints.coulomb
        D = self.gain(T)
        score = np.zeros(len(quantities["cell_start"]))
        for p in quantities["pieces"]:
            terms = self.cell_terms(T, d, D, quantities, p, tube)
            with np.errstate(divide="ignore", invalid="ignore"):
                per_cell = terms["slow"] + (
                    terms["pushed"] / terms["margin"] + terms["forcing"]
                ) / np.sqrt(np.maximum(terms["lam_L"], 1e-300))
            per_cell = np.where((terms["margin"] > 0) & p["valid"], per_cell, np.inf)
            score = np.maximum(score, per_cell)
        return score

    def failing_cells(self, T: float, d: float, quantities: dict) -> int:
        """How many cells fail (an inertia model, or a contraction margin ``a - b`` that is not
        positive at ``rho = 0``) on any piece."""
        d = d + self.joints.coulomb
        D = self.gain(T)
        failing = np.zeros(len(quantities["cell_start"]), dtype=bool)
        for p in quantities["pieces"]:
            terms = self.cell_terms(T, d, D, quantities, p, 0.0)
            failing |= ~p["valid"] | ~(terms["margin"] > 0)
        return int(failing.sum())

    def cell_terms(self, T, d, D, q: dict, p: dict, tube: float) -> dict[str, np.ndarray]:
        """The per-cell terms of the floor for one piece (the floor takes their extremes)."""
        n = self.dof
        R, RM, V, Rs = (p[name][0] + tube * p[name][1] for name in ("R", "RM", "V", "Rs"))
        # ||ed|| <= ||r|| + Kr ||e|| moves w along the tube's Jacobian.
        error_rate = q["r_max"] + float(self.Kr.max()) * tube
        # The rate of M_L^-1 w, in the Euclidean norm and straight in the plant's metric.
        rate_inverse = p["rate_inverse"] + error_rate * p["R"][1] + p["inverse_change"] * Rs
        rate_inverse_M = p["rate_inverse_M"] + error_rate * p["RM"][1] + p["inverse_change_M"] * Rs
        rate = p["rate"] + error_rate * p["V"][1]
        lag = p["lag"] + error_rate * p["lag_e"]
        lag_M = p["lag_M"] + error_rate * p["lag_M_e"]
        beta, lam_L, lam_U = p["beta"], p["lam_L"], p["lam_U"]
        with np.errstate(invalid="ignore"):  # beta = -inf where an inertia model fails
            a = beta * D * T / (D * T + beta * lam_U)
        growth = 0.5 * T * p["metric_rate"]  # the metric M(q) changes within the period
        damping = self.joints.damping / lam_L if self.joints.damping else 0.0
        b = T * (p["K"] * (0.5 + p["nu"]) + p["coriolis"] + damping) + growth
        sqrt_L, sqrt_U = np.sqrt(lam_L), np.sqrt(lam_U)
        equilibrium = T * (R + 0.5 * T * lag) + V / D
        safe_a = np.maximum(a, 1e-300)
        response = disturbance_response(T, d, D, q["trace_inverse"], q["law_lam_L"], lam_L, a, n)
        rate_M = np.minimum(rate_inverse_M, sqrt_U * rate_inverse)
        equilibrium_M = T * (RM + 0.5 * T * lag_M) + sqrt_U * V / D
        response_M = T * d / (safe_a * sqrt_L)
        # The disturbance's response r_d is that of the plant frozen at the sample (any history
        # of ||d_j|| <= d): it moves as the plant does. In the plant's metric, with
        # Phi_j = (1 - A)^j T M^-1, ||M^1/2 dPhi_j/dt M^1/2|| <= j (1 - a)^(j - 1) (mu + mu_L) T +
        # (1 - a)^j mu T (A's rate from M's and from the law's M_L's), summed over the history:
        # ((mu + mu_L) / a + mu) T d / (a sqrt(lambda_L)) per unit time.
        mu = p["metric_rate"]
        response_motion = T * ((mu + q["mu_law"]) / safe_a + mu) * response_M
        forcing = (T * (T * rate_M + sqrt_U * rate / D) + response_motion) * (1 + growth)
        # Where the gain D = kappa ||rho|| + phi_P moves from one sample to the next with
        # ||rho|| (only D >= phi_P is known; gain_varies), r* and r_d are those of the
        # dead-beat loop (D = inf, T K = M_L: r* = T M_L^-1 w; every bound above holds for it),
        # and the law's K_k differs from it by ||M^-1/2 T (K_inf - K_k) M^-1/2|| <= lambda_U /
        # (D T) (per mode lambda_L - lambda_L / (1 + lambda_L / (D T))), acting on r* + r_d.
        # Where D is capped and saturated it is the same at every sample: nothing to add.
        gain_change = np.minimum(lam_U / (D * T), 1.0) * float(self.gain_varies(T))
        return {
            "valid": p["valid"],
            "contraction": a,
            "margin": a - b,
            "lam_L": lam_L,
            "equilibrium": equilibrium,
            "response": response,
            "slow": equilibrium + response,
            "forcing": forcing,
            "pushed": forcing + (b + gain_change) * (equilibrium_M + response_M) * (1 + growth),
            "gain_change": gain_change,
            "mismatch": T * R + V / D,
            "torque_lag": 0.5 * T * T * lag,
        }

    @staticmethod
    def invalid_parts(p: dict, D: float) -> dict | None:
        """The parts of a piece where an inertia model fails on some cell (no floor), or
        ``None``."""
        if np.all(p["valid"]):
            return None
        cell = int(np.flatnonzero(~p["valid"])[0])
        return {"margin": -math.inf, "invalid_cell": cell, "gain_D": D}

    @staticmethod
    def margin_parts(terms: dict, D: float, contraction: float) -> dict:
        """The least margin over the cells, where it is, the gain and the contraction."""
        worst_cell = int(np.argmin(terms["margin"]))
        return {
            "contraction": contraction,
            "margin": float(terms["margin"][worst_cell]),
            "gain_D": float(D),
            "margin_cell": worst_cell,
        }

    def _piece_floor(self, T, d, D, q: dict, p: dict, tube: float) -> tuple[float, dict]:
        invalid = self.invalid_parts(p, D)
        if invalid is not None:
            return math.inf, invalid
        terms = self.cell_terms(T, d, D, q, p, tube)
        parts = self.margin_parts(terms, D, float(np.min(terms["contraction"])))
        margin = parts["margin"]
        if not margin > 0:
            return math.inf, parts
        sqrt_L_min = float(np.sqrt(terms["lam_L"].min()))
        forcing_max = float(np.max(terms["forcing"]))
        deviation = float(np.max(terms["pushed"])) / margin
        slow = terms["slow"]
        r_sup = float(np.max(slow)) + (deviation + forcing_max) / sqrt_L_min
        floor = r_sup / float(self.Kr.min())
        # Which term dominates, and where (for the report).
        shares = {
            "mismatch": float(np.max(terms["mismatch"])),
            "torque_lag": float(np.max(terms["torque_lag"])),
            "disturbance": float(np.max(terms["response"])),
            "deviation": (deviation + forcing_max) / sqrt_L_min,
        }
        parts.update(
            r_sup=r_sup,
            r_equilibrium=float(np.max(terms["equilibrium"])),
            shares=shares,
            slow_cell=int(np.argmax(slow)),
            lambda_L_min=float(terms["lam_L"].min()),
        )
        return floor, parts

    def torque_bound(
        self, T: float, d: float, quantities: dict, tube: float, r_sup: float
    ) -> np.ndarray:
        """Per joint, a bound [N m] of the torque the law commands once ``||e||`` is within the
        floor's regime (docs/sampled-data.md §3, "Torques"): with ``r = r* + r_d + delta`` (the
        dead-beat loop's ``r* = T M_L^-1 w`` and ``r_d``), ``tau0 + K r* = tau0 + w - (M_L - T
        K) M_L^-1 w`` is the plant's own torque over the regime's tube ``||e|| <= tube``
        (:func:`~urpc.control.cells.plant_torque`) less at most ``sqrt(M_ii) g ||M_L^-1/2 w||``
        (``g = lambda_U / (D T)``), ``K r_d = sum_j M^1/2 A (1 - A_inf)^j M^-1/2 d_j`` is at most
        ``sqrt(M_ii) (S(a) + g / a) d / sqrt(lambda_L)`` with ``S(a) = sum_j max_{a <= x <= 1}
        x (1-x)^j``, and ``K delta = M^1/2 (A / T) M^1/2 delta`` at most ``sqrt(M_ii)
        ||delta||_M / T``; the law's nominal torque at ``r != 0`` adds ``torque_per_r ||r||``
        with ``||r|| <= r_sup``; the largest over the cells and pieces."""
        d = d + self.joints.coulomb
        D = self.gain(T)
        bound = np.zeros(self.dof)
        for p in quantities["pieces"]:
            terms = self.cell_terms(T, d, D, quantities, p, tube)
            margin = float(np.min(terms["margin"]))
            if not np.all(p["valid"]) or not margin > 0:
                return np.full(self.dof, math.inf)
            delta_M = float(np.max(terms["pushed"])) / margin + float(np.max(terms["forcing"]))
            root = np.sqrt(p["upper_diagonal"])
            a, change = terms["contraction"], terms["gain_change"]
            response = (response_sum(a) + change / a) * d / np.sqrt(p["lam_L"])
            mismatch = change * (p["RM"][0] + tube * p["RM"][1])  # >= g ||M_L^-1/2 w||
            piece = (
                plant_torque(quantities, tube)
                + quantities["torque_per_r"] * r_sup
                + root * ((response + mismatch)[:, None] + delta_M / T)
            )
            bound = np.maximum(bound, piece.max(axis=0))
        return bound * (1 + 1e-12)


def disturbance_response(T, d, D, trace_inverse, law_lam_L, lam_L, a, n: int) -> np.ndarray:
    """A bound of ``||r_d||`` [rad/s], the response of the loop frozen at a sample to any history
    of disturbances ``||d_j|| <= d`` [N m]: ``r_d = sum_j Phi_j d_j`` with ``Phi_j = T M^-1/2 (1 -
    A)^j M^-1/2`` positive semi-definite, summing to ``S = T (T K)^-1 = T (M_L^-1 + (D T)^-1)``
    (docs/sampled-data.md §2), so ``||r_d|| <= d sup_x sum_j ||Phi_j x||`` over unit ``x``. The
    smaller of two bounds of that sum: the trace, ``sum_j ||Phi_j|| <= tr S``, and
    Cauchy-Schwarz, ``sum_j ||Phi_j x|| <= (sum_j ||Phi_j||)^1/2 (x^T S x)^1/2`` with ``sum_j
    ||Phi_j|| <= T / (lambda_L a)`` and ``x^T S x <= T (1 / lambda_L(M_L) + 1 / (D T))``. The
    second wins when several modes are light (the Panda), the first when one is (the UR5, whose
    trace is 1.3 times its lightest mode's inverse).

    ``trace_inverse`` bounds ``tr M_L^-1`` of the law's model from above, ``law_lam_L`` its least
    eigenvalue from below, ``lam_L`` the plant's, ``a`` the contraction (``A >= a``)."""
    safe_a = np.maximum(a, 1e-300)
    trace = trace_inverse + n / (D * T)
    inverse_law = 1.0 / np.maximum(law_lam_L, 1e-300) + 1.0 / (D * T)
    with np.errstate(invalid="ignore"):  # a is nan where an inertia model fails: the trace
        return T * d * np.fmin(trace, np.sqrt(inverse_law / (lam_L * safe_a)))


def response_sum(a: np.ndarray, terms: int = 4096) -> np.ndarray:
    """``S(a) = sum_j max_{a <= x <= 1} x (1 - x)^j`` per entry of ``a`` (in (0, 1]): the sum
    of ``||A (1 - A)^j||`` over the loop's memory for ``a I <= A <= I``. Each term is at its
    maximum ``x = max(a, 1 / (j + 1))``: ``1 / (j + 1)`` for ``j < J`` (``J`` the first ``j``
    with ``1 / (j + 1) < a``), a table of partial sums independent of ``a``, and ``a`` from
    ``J`` on, whose terms ``a (1 - a)^j`` sum to ``(1 - a)^J`` exactly. ``a`` below
    ``1 / terms`` (past the table) gives ``inf``."""
    a = np.asarray(a, dtype=float)
    partial = _harmonic_partial_sums(terms)
    usable = a * terms >= 1.0
    safe = np.where(usable, a, 1.0)
    # J: the first j with 1 / (j + 1) < a, found from floor(1 / a) with the same comparison
    # as the terms themselves (at most two steps either way).
    J = np.clip(np.floor(1.0 / safe) - 2, 0, terms).astype(int)
    for _ in range(5):
        J = np.where((J < terms) & (1.0 / (J + 1) >= safe), J + 1, J)
    total = partial[J] + (1 - safe) ** J
    return np.where(usable, total * (1 + 1e-12), math.inf)


@functools.cache
def _harmonic_partial_sums(terms: int) -> np.ndarray:
    """``sum_{j < J} x_j (1 - x_j)^j`` with ``x_j = 1 / (j + 1)``, for ``J = 0 .. terms``."""
    j = np.arange(terms, dtype=float)
    x = 1.0 / (j + 1)
    return np.concatenate([[0.0], np.cumsum(x * (1 - x) ** j)])
