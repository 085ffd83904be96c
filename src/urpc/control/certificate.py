"""The certificate of a synthesized controller: for which ``epsilon`` and which sample period the
tracking guarantee holds, and which condition fails when it does not.

Continuous time: Theorems 1-2 of the paper (their gain conditions). Under a zero-order hold of
period ``T`` with the implicit law of :mod:`urpc.control.interval`, the argument of
``docs/sampled-data.md``: in the metric of the true inertia, ``z = M^{1/2} r``, one period gives::

    ||z+|| <= (1 - a + b) ||z|| + T c

    a = beta D T / (D T + beta lambda_U)            contraction of the implicit feedback
    b = T (K (1/2 + nu) + (1 + nu) Gamma v)          Kr and Coriolis terms, proportional to r
    c = W + d / sqrt(lambda_L) + T G / 2              mismatch, disturbance, drift

with ``lambda_L = lambda_min(M_L)``, ``lambda_U = lambda_max(M_U)``, ``beta`` the relative tightness
of the inertia bounds, ``nu >= ||M^{-1/2} (M - M0) M^{-1/2}||``, ``K`` the ``Kr`` gain seen in that
metric, ``Gamma`` the Coriolis coefficient in that metric (``||L^-1 C(q, u) L^-T||``, ``M_L = L L^T``), ``v`` the velocity in the tube, ``W`` a bound of the mismatch
``||M_L^{-1/2} w||`` over the box in the tube, ``d`` the disturbance bound and ``G`` the rate of change of
the torque along the reference. Once the adaptive gain reaches its ceiling ``phi_max`` (it does
while ``||e|| >= epsilon``), ``||z||`` is ultimately below ``T c / (a - b)``, hence::

    ||r|| <= (T c / (a - b) + T c) / sqrt(lambda_L),       ||e|| <= ||r|| / min(Kr)  =: floor

evaluated as the worst case over a grid of the reference (and of a tube of radius ``floor``
around it, by a fixed point). The ultimate bound of a run is ``max(epsilon, floor)``: the gains
stop adapting once ``||e|| < epsilon``. ``inertia bounds`` are sound at every grid point; ``W``,
``Gamma``, ``G`` are evaluated on the grid (not an interval proof between grid points).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import scipy.linalg

from ..bounds.base import link_body_placement
from ..bounds.hull import barycentric_enclosure
from ..model.inertia_bounds import InertiaBounds
from ..sim.trajectories import Trajectory
from .interval import PHI_MAX_FACTOR, IntervalPassivityController

#: Grid points along the reference where the certificate's quantities are evaluated.
GRID_POINTS = 200


@dataclass(frozen=True)
class Condition:
    """One condition of the argument: ``holds`` when ``value`` satisfies ``limit``."""

    name: str
    holds: bool
    value: float
    limit: float
    explanation: str


@dataclass(frozen=True)
class Certificate:
    """What the guarantee covers for one controller, reference and disturbance.

    Attributes:
        certified: Every condition holds: ``||e||`` ends up below ``epsilon`` on every plant of
            the box (at the samples, for a sampled law).
        epsilon: The requested precision [rad].
        epsilon_floor: The smallest precision the argument guarantees at this period [rad]
            (0 in continuous time under Theorem 2; ``inf`` when no bound follows).
        max_sample_period: The largest period at which the implicit law is certified for
            ``epsilon`` [s] (0 when none is).
        sample_period: The controller's period [s], ``None`` in continuous time.
        law: ``"continuous"``, ``"implicit"`` or ``"paper"``.
        conditions: Every condition of the argument, failed ones first.
        figures: The quantities the floor is made of (``beta``, ``lambda_L`` ...), for reports.
    """

    certified: bool
    epsilon: float
    epsilon_floor: float
    max_sample_period: float
    sample_period: float | None
    law: str
    conditions: tuple[Condition, ...]
    figures: dict[str, float] = field(default_factory=dict)

    @property
    def failed(self) -> tuple[Condition, ...]:
        return tuple(c for c in self.conditions if not c.holds)

    def summary(self) -> str:
        """One line: certified or not, the floor, and the first failed condition."""
        period = (
            "continuous time" if self.sample_period is None else f"T = {self.sample_period:g} s"
        )
        head = (
            f"{'certified' if self.certified else 'NOT certified'} ({self.law} law, {period}): "
            f"epsilon = {self.epsilon:g} rad, floor = {self.epsilon_floor:.3g} rad, "
            f"max sample period {self.max_sample_period:.3g} s"
        )
        if self.certified:
            return head
        first = self.failed[0]
        return f"{head}; fails: {first.name} ({first.explanation})"

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready fields; a non-finite number (an infinite floor) becomes ``None``."""
        return _finite_or_none(asdict(self))


def certify(
    controller: IntervalPassivityController,
    trajectory: Trajectory,
    *,
    duration: float,
    disturbance_bound: float | None = None,
) -> Certificate:
    """The certificate of ``controller`` tracking ``trajectory`` over ``[0, duration]`` [s].

    Args:
        controller: A synthesized interval controller (its robot, box, gains, period and law).
        trajectory: The reference the guarantee is asked for.
        duration: The time span of the reference to cover [s].
        disturbance_bound: ``||d||`` bound [N m] the plant sees. Theorem 2 does not need it in
            continuous time, but the sampled-data floor does; defaults to the box's bound.
    """
    box = controller.bound.box
    d = box.disturbance_bound if disturbance_bound is None else float(disturbance_bound)
    conditions = _theorem_conditions(controller)
    law = "continuous" if controller.sample_period is None else controller.sampled_law
    grid = _Grid(controller, trajectory, duration)
    if d is None:
        conditions.append(
            Condition(
                "disturbance bound given", False, math.nan, math.nan,
                "the sampled-data floor needs ||d||: give the scenario's `disturbance` or "
                "--disturbance-bound",
            )
        )  # fmt: skip
        d = math.nan
    figures = grid.figures()
    max_period = grid.max_sample_period(controller.epsilon, d) if math.isfinite(d) else 0.0
    if controller.sample_period is None:
        floor = 0.0 if controller.adaptive else grid.theorem1_floor(controller.kappa_P)
    elif law == "paper":
        floor = math.inf
        limit = 2.0 * figures["lambda_L"] / controller.sample_period
        gain = math.inf if controller.adaptive else controller.phi_P
        conditions.append(
            Condition(
                "paper law: gain below the hold's stability limit 2 lambda_L / T",
                gain < limit, gain, limit,
                "the paper's gain grows without bound under Theorem 2 and diverges once D T > "
                "2 lambda: use the implicit sampled law (sampled_law: implicit)",
            )
        )  # fmt: skip
    else:
        floor, parts = grid.floor(controller.sample_period, d, controller.epsilon)
        figures.update(parts)
        conditions += _sampled_conditions(figures, floor, controller.epsilon, max_period)
    holds = all(c.holds for c in conditions) and floor <= controller.epsilon
    if controller.sample_period is None and not controller.adaptive:
        conditions.append(
            Condition(
                "Theorem 1 ultimate bound below epsilon", floor <= controller.epsilon, floor,
                controller.epsilon, "raise kappa_P or Kr, or use Theorem 2 (disturbance: unknown)",
            )
        )  # fmt: skip
    ordered = tuple(sorted(conditions, key=lambda c: c.holds))
    return Certificate(
        bool(holds), controller.epsilon, float(floor), float(max_period),
        controller.sample_period, law, ordered, figures,
    )  # fmt: skip


def _theorem_conditions(controller: IntervalPassivityController) -> list[Condition]:
    if controller.adaptive:
        specs = [
            ("Theorem 2: kappa_I > 0", controller.kappa_I, 0.0, "choose kappa_I > 0"),
            ("Theorem 2: phi_I > 0", controller.phi_I, 0.0, "choose phi_I > 0"),
        ]
        return [Condition(n, v > lim, v, lim, x) for n, v, lim, x in specs]
    specs = [
        ("Theorem 1: kappa_P >= 1", controller.kappa_P, 1.0, "choose kappa_P >= 1"),
        ("Theorem 1: phi_P >= 1", controller.phi_P, 1.0, "choose phi_P >= 1"),
    ]
    return [Condition(n, v >= lim, v, lim, x) for n, v, lim, x in specs]


def _sampled_conditions(
    figures: dict[str, float], floor: float, epsilon: float, max_period: float
) -> list[Condition]:
    return [
        Condition(
            "inertia lower bound M_L positive definite", figures["lambda_L"] > 0,
            figures["lambda_L"], 0.0,
            "the box allows a joint with no inertia: narrow the mass/inertia intervals",
        ),
        Condition(
            "relative inertia bound beta > 0", figures["beta"] > 0, figures["beta"], 0.0,
            "the box's inertia bounds are vacuous: narrow the mass/inertia intervals",
        ),
        Condition(
            "contraction a exceeds the perturbation b (at r = 0)", figures["margin"] > 0,
            figures["margin"], 0.0,
            "shorten the sample period or lower Kr (b grows with T Kr and T |qd|)",
        ),
        Condition(
            "ultimate bound below epsilon", floor <= epsilon, floor, epsilon,
            (f"raise epsilon to {floor:.3g} rad or shorten" if math.isfinite(floor)
             else "no epsilon is guaranteed at this period: shorten")
            + f" the period to {max_period:.3g} s",
        ),
    ]  # fmt: skip


class _Grid:
    """The certificate's quantities on a grid of the reference."""

    def __init__(self, controller: IntervalPassivityController, trajectory: Trajectory, duration):
        self.controller = controller
        robot = controller.robot
        self.bound = controller.bound
        self.bounds = controller.inertia_bounds or InertiaBounds(robot, controller.bound.box)
        self.Kr = controller.Kr
        times = np.linspace(0.0, float(duration), GRID_POINTS)
        self.q, self.qd, self.qdd = (np.atleast_2d(x) for x in trajectory.evaluate(times))
        n = robot.dof
        lam_L, lam_U, beta, nu, gamma, drift = (np.full(len(times), math.inf) for _ in range(6))
        self.lower_matrices: list[np.ndarray | None] = []
        self.links = [_link_vertices(self.bound.robot, b) for b in self.bound.box.uncertain_links]
        upper_robot, step = self.bounds.upper_robot, 1e-4
        for j, q in enumerate(self.q):
            ML, MU, M0 = self.bounds.lower(q), self.bounds.upper(q), robot.M(q)
            lam_L[j] = np.linalg.eigvalsh(ML)[0]
            lam_U[j] = np.linalg.eigvalsh(MU)[-1]
            self.lower_matrices.append(ML if lam_L[j] > 0 else None)
            if lam_L[j] <= 0:
                beta[j] = -math.inf
                continue
            beta[j] = scipy.linalg.eigh(ML, MU, eigvals_only=True)[0]
            nu[j] = max(
                1.0 - scipy.linalg.eigh(M0, MU, eigvals_only=True)[0],
                scipy.linalg.eigh(M0, ML, eigvals_only=True)[-1] - 1.0,
            )
            # In the metric of M >= M_L: ||M^-1/2 X M^-1/2|| <= ||L^-1 X L^-T||, ||M^-1/2 x|| <= ||L^-1 x||.
            L = np.linalg.cholesky(ML)

            def scaled(X, L=L):
                return scipy.linalg.solve_triangular(L, X, lower=True)

            gamma[j] = max(
                math.sqrt(
                    sum(np.linalg.norm(scaled(scaled(m.C(q, u)).T), 2) ** 2 for u in np.eye(n))
                )
                for m in (robot, upper_robot)
            )
            ahead = trajectory.evaluate(times[j] + step)
            change = upper_robot.inverse_dynamics(*ahead) - upper_robot.inverse_dynamics(
                q, self.qd[j], self.qdd[j]
            )
            drift[j] = np.linalg.norm(scaled(change)) / step
        self.lam_L, self.lam_U, self.beta, self.nu, self.gamma, self.drift = (
            lam_L, lam_U, beta, nu, gamma, drift,
        )  # fmt: skip
        uniform = np.ptp(self.Kr) == 0
        self.K = self.Kr.max() * (1.0 if uniform else np.sqrt(lam_U / np.maximum(lam_L, 1e-300)))
        self._mismatch_cache: dict[float, np.ndarray] = {}

    def figures(self) -> dict[str, float]:
        return {
            "lambda_L": float(np.min(self.lam_L)),
            "lambda_U": float(np.max(self.lam_U)),
            "beta": float(np.min(self.beta)),
            "nu": float(np.max(self.nu)),
        }

    def mismatch(self, tube: float) -> np.ndarray:
        """``W_j >= ||M_L^{-1/2} w||`` over the box and the tube ``||e|| <= tube`` at each grid point,
        with ``w`` at ``r = 0`` (the part proportional to ``r`` is in ``b``).

        ``w = sum_l Y_l (pi_l - pi0_l)`` over uncertain links: per link, the maximum of the convex
        ``||L^{-1} Y_l delta||`` over the barycentric hull of its box is attained at a vertex
        (``M_L = L L^T``), so the vertices are enumerated; the links are summed (triangle
        inequality), keeping the correlation of one link's parameters that a per-joint ``rho``
        loses."""
        key = round(tube, 15)
        if key in self._mismatch_cache:
            return self._mismatch_cache[key]
        n, Kr = len(self.Kr), self.Kr
        random = np.random.default_rng(0).standard_normal((4, n))
        directions = np.vstack(
            [np.zeros(n), np.eye(n), -np.eye(n), random / np.linalg.norm(random, axis=1)[:, None]]
        )
        regressor = self.bound.regressor
        W = np.zeros(len(self.q))
        for j in range(len(self.q)):
            cholesky = np.linalg.cholesky(self.lower_matrices[j])
            for direction in directions:
                e = tube * direction
                qd_a = self.qd[j] + Kr * e
                Y = regressor(self.q[j] - e, qd_a, qd_a, self.qdd[j] - Kr * Kr * e)
                total = 0.0
                for columns, A, vertices in self.links:
                    G = scipy.linalg.solve_triangular(cholesky, Y[:, columns] @ A, lower=True)
                    total += np.sqrt(np.max(np.sum((G @ vertices) ** 2, axis=0)))
                W[j] = max(W[j], total)
        self._mismatch_cache[key] = W
        return W

    def _floor_at(self, T: float, d: float, tube: float, W: np.ndarray) -> tuple[float, dict]:
        """The floor for a fixed tube (``||e||`` and ``||r||`` fixed points on the velocity)."""
        c = self.controller
        # Theorem 2: the gain the adaptation reaches (phi_max at this T); Theorem 1: its floor.
        D = (
            max(c.phi_P, PHI_MAX_FACTOR * self.bounds.max_upper_eigenvalue / T)
            if c.adaptive
            else c.phi_P
        )
        beta, lam_L, lam_U = self.beta, self.lam_L, self.lam_U
        a = beta * D * T / (D * T + beta * lam_U)
        speed = np.linalg.norm(self.qd, axis=1) + self.Kr.max() * tube
        sqrt_L = np.sqrt(lam_L)
        cw = W + d / sqrt_L + 0.5 * T * self.drift
        r_sup = 0.0
        for _ in range(50):
            b = T * (self.K * (0.5 + self.nu) + (1.0 + self.nu) * self.gamma * (speed + r_sup))
            margin = float(np.min(a - b))
            if r_sup == 0.0:
                parts = {"contraction": float(np.min(a)), "margin": margin, "gain_D": float(D)}
            if not margin > 0:
                return math.inf, parts
            z = T * cw.max() / margin
            new = (z + T * cw.max()) / sqrt_L.min()
            if abs(new - r_sup) <= 1e-6 * new:
                break
            r_sup = new
        parts.update(r_sup=float(new), mismatch_W=float(W.max()))
        return float(new / self.Kr.min()), parts

    def floor(self, T: float, d: float, epsilon: float) -> tuple[float, dict]:
        """The smallest tube radius that reproduces itself (fixed point from ``tube = 0``), and
        the parts of the bound (at that tube, or at ``epsilon`` when there is none)."""
        if not np.all(self.lam_L > 0) or not math.isfinite(d):
            return math.inf, {"margin": -math.inf}
        tube = 0.0
        for _ in range(30):
            floor, parts = self._floor_at(T, d, tube, self.mismatch(tube))
            if not math.isfinite(floor) or floor > 1e3 * max(epsilon, 1e-9):
                break
            if floor <= tube * (1 + 1e-3):
                return tube, parts
            tube = floor * 1.001
        return math.inf, self._floor_at(T, d, epsilon, self.mismatch(epsilon))[1]

    def max_sample_period(self, epsilon: float, d: float) -> float:
        """The largest ``T`` with ``floor(T) <= epsilon`` in the tube ``||e|| <= epsilon``."""
        if not np.all(self.lam_L > 0):
            return 0.0
        W = self.mismatch(epsilon)

        def ok(T: float) -> bool:
            return self._floor_at(T, d, epsilon, W)[0] <= epsilon

        low, high = 1e-8, 1e-1
        if not ok(low):
            return 0.0
        if ok(high):
            return high
        for _ in range(40):
            middle = math.sqrt(low * high)
            low, high = (middle, high) if ok(middle) else (low, middle)
        return low

    def theorem1_floor(self, kappa_P: float) -> float:
        """Theorem 1: ``||r|| <= sqrt(lambda_max / lambda_min) / kappa_P``, ``||e|| <= ||r|| / Kr``."""
        if not np.all(self.lam_L > 0):
            return math.inf
        ratio = np.max(self.lam_U) / np.min(self.lam_L)
        return float(math.sqrt(ratio) / kappa_P / self.Kr.min())


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


def _finite_or_none(value):
    if isinstance(value, dict):
        return {key: _finite_or_none(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_none(item) for item in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
