"""The enclosing box of a polytope, by linear programs (scipy's HiGHS).

:class:`Polytope` holds ``{x : A_ub x <= b_ub, A_eq x = b_eq, lower <= x <= upper}``. Its
variables are scaled to ``x = center + radius z`` with ``z in [-1, 1]`` (a variable of zero width
is a constant and leaves the programs), and each inequality row is divided by its largest
coefficient, so that HiGHS's absolute tolerances mean the same for a payload's mass [kg] and its
inertia [kg m^2].

* :meth:`Polytope.range` gives ``min`` and ``max`` of a linear function ``f . x``;
* :meth:`Polytope.ratio_range` gives those of a linear-fractional one ``(f . x) / (g . x)``
  where ``g . x > 0`` on the polytope, exactly, by the Charnes-Cooper transformation
  ``y = z t, t = 1 / (g . x)``, which turns it into one linear program in ``(y, t)``.

**Soundness against the solver's tolerances.** HiGHS stops within its feasibility and
optimality tolerances (``1e-7`` by default); a reported minimum could then lie above the true
one by about that much of the objective's scale. Every bound is therefore moved outward by
:data:`MARGIN` times the objective's range over the variable box (``sum |f_k| radius_k``), and
``tests/test_identify_lp.py`` compares the result with brute force.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from ..errors import InputError, UrpcError

#: Rows added per cutting-plane iteration, and the violation (of a row scaled to a largest
#: coefficient of 1, in units of the scaled variables) below which a row counts as satisfied.
CUTS = 64
VIOLATION = 1e-9
#: Outward margin of every bound, relative to the objective's range over the variable box.
MARGIN = 1e-6


class InfeasibleData(InputError):
    """No parameter vector of the prior box explains the data within the noise bound."""


def _infeasible() -> InfeasibleData:
    return InfeasibleData(
        "no parameter vector in the prior box explains the data within the noise bound: the "
        "noise bound is too small, the prior box too narrow, or the data do not belong to this "
        "robot (joint order, units, torque sign)",
        field="torque_noise",
    )


@dataclass
class Polytope:
    """``{x : A_ub x <= b_ub, A_eq x = b_eq, lower <= x <= upper}`` (finite bounds)."""

    A_ub: np.ndarray
    b_ub: np.ndarray
    A_eq: np.ndarray
    b_eq: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    #: The first ``always`` inequality rows are in every program (the prior's); the others (the
    #: data's) enter when violated (:meth:`_cutting`).
    always: int = 0

    def __post_init__(self) -> None:
        lower, upper = np.asarray(self.lower, float), np.asarray(self.upper, float)
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise UrpcError("every variable of the identification needs finite prior bounds")
        if np.any(lower > upper):
            raise UrpcError("a variable has lower > upper bound")
        self.center = 0.5 * (lower + upper)
        self.radius = 0.5 * (upper - lower)
        self.free = np.flatnonzero(self.radius > 0)
        R = self.radius[self.free]
        self._A_ub, self._b_ub = self._scaled(self.A_ub, self.b_ub, R, inequality=True)
        always = int(np.sum(self._kept[: self.always])) if self.b_ub.size else 0
        self._A_eq, self._b_eq = self._scaled(self.A_eq, self.b_eq, R, inequality=False)
        self.solves = 0
        #: Rows in the programs solved so far (grown by :meth:`_cutting`); shared by all bounds.
        self._active = np.zeros(self._A_ub.shape[0], dtype=bool)
        self._active[:always] = True

    _kept = np.zeros(0, dtype=bool)

    def _scaled(self, A, b, R, inequality: bool):
        """Rows in the scaled variables, each divided by its largest coefficient. Inequality rows
        that hold on the whole variable box (``b >= sum |A_row|``: most data rows, and rows whose
        coefficients are rounding noise) are dropped; one that no point of the box satisfies
        means the data contradict the prior."""
        A = np.asarray(A, float).reshape(-1, self.center.size)
        b = np.asarray(b, float).reshape(-1) - A @ self.center
        A = A[:, self.free] * R
        keep = np.ones(A.shape[0], dtype=bool)
        if A.shape[0]:
            reach = np.sum(np.abs(A), axis=1)
            if inequality:
                if np.any(b < -reach - 1e-9 * (1 + np.abs(b))):
                    raise _infeasible()
                keep = b < reach
            else:
                keep = reach > 0
            scale = np.max(np.abs(A), axis=1)
            scale[~keep] = 1.0
            A, b = A / scale[:, None], b / scale
        if inequality:
            self._kept = keep
        return A[keep], b[keep]

    def _solve(self, cost: np.ndarray, A_ub, b_ub, A_eq, b_eq, bounds, what: str):
        self.solves += 1
        program = {
            "A_ub": A_ub if A_ub.shape[0] else None,
            "b_ub": b_ub if A_ub.shape[0] else None,
            "A_eq": A_eq if A_eq.shape[0] else None,
            "b_eq": b_eq if A_eq.shape[0] else None,
            "bounds": bounds,
            "method": "highs",
        }
        result = linprog(cost, **program)
        if result.status == 2:  # confirm without presolve (it can misjudge near-degenerate rows)
            result = linprog(cost, **program, options={"presolve": False})
        if result.status == 2:
            raise _infeasible()
        if result.status == 3:
            return None  # unbounded (only the ratio program can be: the caller says what then)
        if result.status != 0:
            raise UrpcError(f"the linear program for {what} failed: {result.message}")
        return result

    def _cutting(self, cost, columns, extra_ub, extra_b, A_eq, b_eq, bounds, what):
        """Solve ``min cost . v`` over the rows of ``A_ub`` mapped by ``columns(A, b)`` to the
        program's variables, adding violated rows until none is violated (cutting planes). Each
        intermediate program is a relaxation (fewer rows), so its value is a lower bound of the
        full program's; the final one is its optimum."""
        A_all, b_all = columns(self._A_ub, self._b_ub)
        while True:
            active = self._active
            A_ub = np.vstack([A_all[active], extra_ub])
            b_ub = np.concatenate([b_all[active], extra_b])
            result = self._solve(cost, A_ub, b_ub, A_eq, b_eq, bounds, what)
            if result is None:
                return None
            violation = A_all @ result.x - b_all
            violation[active] = -np.inf
            worst = np.argsort(violation)[::-1][:CUTS]
            worst = worst[violation[worst] > VIOLATION]
            if worst.size == 0:
                return result
            self._active[worst] = True

    def range(self, f: np.ndarray, what: str = "a bound") -> tuple[float, float]:
        """``(min, max)`` of ``f . x`` over the polytope, moved outward by :data:`MARGIN`."""
        f = np.asarray(f, dtype=float)
        offset = float(f @ self.center)
        cost = f[self.free] * self.radius[self.free]
        spread = float(np.sum(np.abs(cost)))
        if spread == 0.0:
            return offset, offset
        bounds = [(-1.0, 1.0)] * self.free.size
        none = np.zeros((0, self.free.size))

        def same(A, b):
            return A, b

        low = self._cutting(cost, same, none, np.zeros(0), self._A_eq, self._b_eq, bounds, what)
        high = self._cutting(-cost, same, none, np.zeros(0), self._A_eq, self._b_eq, bounds, what)
        lo = max(offset + low.fun, offset - spread)
        hi = min(offset - high.fun, offset + spread)
        margin = MARGIN * spread
        return lo - margin, hi + margin

    def ratio_range(
        self, f: np.ndarray, g: np.ndarray, g_lower: float, what: str = "a ratio"
    ) -> tuple[float, float] | None:
        """``(min, max)`` of ``(f . x) / (g . x)`` over the polytope (Charnes-Cooper), moved
        outward, given ``g . x >= g_lower > 0`` on the polytope (a mass bounded away from zero,
        found by :meth:`range`); ``None`` if a program is unbounded all the same.
        """
        if not g_lower > 0:
            return None
        f, g = np.asarray(f, float), np.asarray(g, float)
        F, G = f[self.free] * self.radius[self.free], g[self.free] * self.radius[self.free]
        f0, g0 = float(f @ self.center), float(g @ self.center)
        n = self.free.size
        # Variables (y, t), y = z t, t = 1 / (g . x) > 0: A z <= b -> A y - b t <= 0, the box
        # |z| <= 1 -> |y| <= t, and the normalization G y + g0 t = 1.
        eye = np.eye(n)
        box = np.vstack([np.column_stack([eye, -np.ones(n)]), np.column_stack([-eye, -np.ones(n)])])

        def homogeneous(A, b):
            return np.column_stack([A, -b]), np.zeros(A.shape[0])

        A_eq = np.vstack([np.column_stack([self._A_eq, -self._b_eq]), np.append(G, g0)[None, :]])
        b_eq = np.zeros(A_eq.shape[0])
        b_eq[-1] = 1.0
        bounds = [(None, None)] * n + [(0.0, 1.0 / g_lower)]
        cost = np.append(F, f0)
        zero = np.zeros(2 * n)
        low = self._cutting(cost, homogeneous, box, zero, A_eq, b_eq, bounds, what)
        high = self._cutting(-cost, homogeneous, box, zero, A_eq, b_eq, bounds, what)
        if low is None or high is None:
            return None
        lo, hi = float(low.fun), float(-high.fun)
        margin = MARGIN * (hi - lo + abs(lo) + abs(hi)) + 1e-15
        return lo - margin, hi + margin
