"""The one-period bound of the delayed law (``delay: 1``, docs/sampled-data.md §7) over the
cells' enclosures.

The law computed at ``t_k`` acts over ``[t_{k+1}, t_{k+2})`` (:mod:`urpc.control.delay`): it
predicts the state at ``t_{k+1}`` with the nominal model and the torque in flight ``u_{k-1}``, and
evaluates the implicit law there against the reference extrapolated by its Taylor polynomial.
Write ``r^_k`` for the law's prediction of ``r`` at ``t_k`` (made at ``t_{k-1}``, against that
extrapolated reference), ``N = M0(q_k)`` (armature included), ``M = M(q_k)`` the plant's,
``K' = K(q^_k)`` the law's feedback at the predicted position, ``z = N^1/2 r_k``, ``y = N^1/2 r^_k``.
Two exact identities (``Delta tau = tau0(x_k, ref_k) - tau0(x^_k, ref^_k)``, the nominal torque at
the state against at the prediction; ``J(t) = w(t) + Delta tau + lag(t) - C r(t)``, ``w`` the
mismatch with the disturbance, ``lag(t) = tau0(x(t)) - tau0(x_k)``):

    r_{k+1} = r_k + int M(t)^-1 (J(t) - K' r^_k) dt
    r^_{k+1} = r_k + T N^-1 (Delta tau - C0 r_k - K' r^_k) + (Kr T^2 / 2)(qdd_d - qdd0)

(the second is the prediction ``q + T qd + T^2/2 qdd0``, ``qd + T qdd0`` against the Taylor
reference, ``qdd0 = N^-1 (u_{k-1} - C0 qd - g0)``, written out). In ``N``'s metric they are the
loop of :mod:`urpc.control.delay_form` plus a perturbation ``(zeta, eta)``:

    z+ = z - H A y + zeta,    y+ = z - A y + eta,    |zeta| <= f_z + B_z . v,
                                                     |eta|  <= f_y + B_y . v

with ``v = (|z|, |y|, |z - y|)`` (``z - y``: the prediction's error), every entry of ``B`` of order
``T`` and the forcing ``f`` (the disturbance, the torque's lag, the mismatch's change within the
period, the reference's extrapolation, the position's prediction error) bounded over the cell,
the tube and the piece. The ranges of ``A``, ``H`` and the coupling are bounded over every cell of
a piece, and a common form with rate ``rho`` is proved over them
(:func:`~urpc.control.delay_form.common_form`). The mismatch at ``r = 0``, ``w0``, is split off:
the loop frozen at the sample has the equilibrium ``xi* = (N^1/2 r*, N^1/2 r^*)``, ``r^* = K'^-1
w0``, ``r* = r^* + T N^-1 w0``, exactly, and the deviation ``xi - xi*`` obeys, per period,

    ||xi_{k+1} - xi*_{k+1}||_X <= g (rho + ||B||_X) ||xi_k - xi*_k||_X
                                    + g (||f||_X + ||B v*||_X) + ||xi*_k - xi*_{k+1}||_X

(``g = (1 + T mu0)^1/2``: the change of the metric ``M0(q)`` from ``t_k`` to ``t_{k+1}``, ``mu0``
the nominal inertia's relative rate; ``||B||_X`` from the coordinates' scales ``|z| <= l_z
||xi||_X`` ...), so it ends below the largest forcing over the least margin ``1 - g (rho +
||B||_X)`` over the cells. Back to ``r``: the equilibrium's ``||r*||``, plus the deviation through
``l_z`` and ``lambda_min(M0)``, plus the distance of ``r(t)`` from its chord between the samples;
``||e|| <= sup ||r(t)|| / min Kr``, plus the predicted position's error, which the tube must hold
too (the law evaluates ``M_L`` and ``tau0`` there).

Every conversion between the metrics uses the piece's ranges: ``h1 <= lambda(M^-1 M0) <= h2``,
``lambda(M0^-1 M_L) in [b_lo, b_hi]`` (the law's lower bound at the predicted point against the
nominal model at the sample), ``||M^-1/2 X M^-1/2|| <= ||M_L^-1/2 X M_L^-1/2||``, and within a
period ``(1 - mu T) M_k <= M(t) <= (1 + mu T) M_k`` (``mu = 2 Gamma``). The terms are listed in
docs/sampled-data.md §7 and derived in the numbered comments of
:meth:`DelayedPeriodBound._parts`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .cells import plant_torque
from .delay_form import CommonForm, SectorRanges, common_form
from .period_bound import PeriodBound


class DelayedPeriodBound(PeriodBound):
    """:class:`~urpc.control.period_bound.PeriodBound` for the delayed law (module docstring):
    the same interface, so that the search over tubes, cells and periods runs unchanged.

    Its per-cell terms map onto the undelayed ones: ``margin`` is ``1 - g (rho + ||B||_X)``,
    ``slow`` the equilibrium's ``||r*||``, ``pushed`` the deviation's forcing and ``lam_L`` the
    factor back to ``r`` (``lambda_min(M0) / l_z^2``), so that a cell's floor, ``slow +
    pushed / margin / lam_L^1/2``, ranks the cells as for the undelayed law."""

    def ranges(self, T: float, D: float, q: dict, p: dict) -> SectorRanges:
        """The ranges of ``A``, ``H`` and the coupling over every cell of piece ``p``:
        ``D T / (D T + lambda_max(M_L)) b_lo <= A <= b_hi``, ``h1 <= H <= h2``, ``c = 1 / (kappa
        h2)`` (``y.u = v^T (T K')^-1 v >= v^T M_L'^-1 v`` with ``v = T K' r^``, and ``|w|^2 =
        v^T M^-1 N M^-1 v <= h2 kappa v^T M_L'^-1 v``, ``kappa >= lambda_max(M^-1 M_L')``).

        ``M_L' = M_L(q^)`` is the law's bound at the predicted position, ``N``, ``M`` at the
        sample's: ``M_L(q) <= N(q)`` and ``M_L(q) <= M(q)`` hold exactly at one point (the
        nominal model and the plant are in the box), and ``M_L(q^) <= (1 + eta) M_L(q)`` with
        ``eta <= ||q^ - q|| ||dM_L/dq||`` (the predicted position's error), so ``b_hi`` and
        ``kappa`` are also at most ``1 + eta``: the smaller is kept (the cell's enclosures
        cross its whole region, whose relative radii can exceed that by far)."""
        step = D * T
        floor_gain = step / (step + q["law_lam_max"])  # T K' >= D T / (D T + lambda_max) M_L
        Kr_max = float(self.Kr.max())
        r_max, tube = q["r_max"], q["tube"]
        J = float(np.max(q["jerk"]))
        eta = position_error(T, Kr_max, r_max, r_max + Kr_max * tube, J) * q["law_slope_norm"]
        near = 1.0 + eta * (1 + 1e-12)
        kappa = np.minimum(p["kappa"], near)
        coupling = 1.0 / (kappa * p["h2"])
        with np.errstate(invalid="ignore"):
            return SectorRanges(
                float(np.min(floor_gain * q["law_over_nominal_low"])),
                float(np.max(np.minimum(q["law_over_nominal_high"], near))),
                float(np.min(p["h1"])),
                float(np.max(p["h2"])),
                float(np.min(coupling)),
            )

    def form(self, T: float, D: float, q: dict, p: dict) -> CommonForm | None:
        """The piece's common form (``None`` where an inertia model fails or none is proved)."""
        if not np.all(p["valid"]):
            return None
        return common_form(self.ranges(T, D, q, p))

    def cell_terms(self, T, d, D, q: dict, p: dict, tube: float) -> dict[str, np.ndarray]:
        form = self.form(T, D, q, p)
        cells = len(q["cell_start"])
        if form is None:
            nothing = np.full(cells, -math.inf)
            return {
                "valid": p["valid"], "margin": nothing, "contraction": nothing,
                "lam_L": np.ones(cells), "slow": np.zeros(cells), "pushed": np.full(cells, math.inf),
                "forcing": np.zeros(cells), "form": None,
            }  # fmt: skip
        parts = self._parts(T, d, D, q, p, tube, form)
        l_z = form.coordinate_scales()[0]
        return {
            "valid": p["valid"],
            "margin": 1.0 - parts["contraction"],
            "contraction": parts["contraction"],
            "lam_L": q["nominal_lam_min"] / (l_z * l_z),
            "slow": parts["r_star"],
            "pushed": parts["pushed"],
            "forcing": np.zeros(cells),
            "form": form,
            "parts": parts,
        }

    def _parts(self, T, d, D, q, p, tube, form: CommonForm) -> dict:
        """Per cell, the terms of the module docstring. A bound ``|x| <= c0 + c . v`` of a
        vector is kept as ``c0`` (cells,) and ``c`` (3, cells) over ``v = (|z|, |y|, |z - y|)``.
        """
        r_max = q["r_max"]
        Kr = self.Kr
        Kr_max, Kr_min = float(Kr.max()), float(Kr.min())
        lam_N, lam_N_max = q["nominal_lam_min"], q["nominal_lam_max"]
        root_N, root_N_low = np.sqrt(lam_N_max), np.sqrt(lam_N)
        eps0 = np.minimum(q["nominal_eps"], 0.999999)
        a2 = float(form.ranges.a2)
        h1, h2, lam_L = p["h1"], p["h2"], p["lam_L"]
        cells = len(lam_N)
        Z_, Y_, P_ = np.eye(3)[:, :, None] * np.ones(cells)  # the coordinates' unit vectors
        # (1) Within the period (1 - mu T) M_k <= M(t) <= (1 + mu T) M_k, mu = 2 Gamma.
        mu = p["metric_rate"]
        rate_N = q["mu_nominal"]  # N(q_{k+1}) <= (1 + T rate_N) N(q_k)
        with np.errstate(invalid="ignore", divide="ignore"):
            usable = p["valid"] & (mu * T < 1) & (T * rate_N < 1)
            muT = np.where(usable, mu * T, 0.0)
            theta = 0.5 * muT / (1 - muT)  # int ||M^1/2 (M(t)^-1 - M^-1) M^1/2|| dt / T
            s2 = np.sqrt(h2 / (1 - muT))  # ||N^1/2 M(t)^-1/2||
            omega = np.sqrt((1 + muT) / h1)  # ||M(t)^1/2 x|| <= omega |N^1/2 x|
        # (2) ||N^1/2 Kr N^-1/2|| and the nominal Coriolis (and damping) in N's metric.
        kN = Kr_max if np.ptp(Kr) == 0 else Kr_max * np.sqrt(lam_N_max / lam_N)
        damping = self.joints.damping
        gamma0 = q["gamma_nominal"] + damping / lam_N
        # (3) The reference's Taylor extrapolation over one period (J over the whole
        # reference: the period before t_k may lie in the previous cell), in r, in qdd_a.
        J = float(np.max(q["jerk"]))
        dv = T * T * J / 2 + Kr_max * T**3 * J / 6
        dqdd = T * J + Kr_max * T * T * J / 2
        # (4) The position's prediction error, ||q^_k - q_k|| <= T sup ||r(s) - r^(s)|| + T^3
        # J / 6 over the period before (e and e^ follow de/dt = r - Kr e from the same e):
        # ||r(s)|| <= r_max, and the predicted path r^(s) = r_{k-1} + s D1 + (Kr s^2 / 2)(D1 -
        # Kr ed) is its chord (both ends within r_max) plus (Kr T / 8)(|T D1| + Kr T ||ed||).
        ed_max = r_max + Kr_max * tube
        dq = position_error(T, Kr_max, r_max, ed_max, J)
        # (5) |N^-1/2 Delta tau| <= dc + dT . v: with tau0 = tau0(e, 0) + L(e) r, L = N Kr -
        # C0(q, qd_a), Delta tau = L_k (r_k - r') + (L_k - L') r' + (tau0(e_k, 0) - tau0(e',
        # 0)) + the law's reference; r', e' the prediction against the actual reference.
        change_N = 2 * eps0 / (1 - eps0)  # ||N_k^-1/2 (N(q^) - N_k) N_k^-1/2||
        dT = (change_N * kN + 2 * gamma0) * Y_ + (kN + gamma0) * P_
        dc = (
            (kN + gamma0 + change_N * kN + 2 * gamma0) * root_N * dv
            + q["torque_per_error_N"] * root_N * dq
            + root_N * (np.sqrt(1 + change_N) * dqdd + gamma0 * dv)
            + 2.0 * self.joints.coulomb / root_N_low  # nominal Coulomb at qd against qd_a
        )
        # (6) The plant's side, |M(t)^-1/2 J(t)|: w0 (the mismatch at r = 0), disturbance,
        # torque lag; perturbations proportional to r(t) (the Coriolis mismatch, the damping,
        # the plant's C r: c_rest, in the plant's metric) and the Kr terms of w's r-part and of
        # the lag's, (M - M0) Kr r(t) + M0(t) Kr r(t) - M0_k Kr r_k = M Kr (r(t) - r_k) + (M -
        # M0) Kr r_k + (M0(t) - M0_k) Kr r_k, and the lag's C0 terms, -C0(t) (r(t) - r_k) -
        # (C0(t) - C0_k) r_k: on r_k (alpha) and on r(t) - r_k (beta).
        R = p["RM"][0] + tube * p["RM"][1]  # >= |M^-1/2 w0|, |M_L^-1/2 w0|, |M^1/2 M_L^-1 w0|
        R_euclid = p["R"][0] + tube * p["R"][1]  # >= ||M_L^-1 w0||
        V = p["V"][0] + tube * p["V"][1]  # >= ||w0||
        error_rate = r_max + Kr_max * tube
        lag = p["lag_M"] + error_rate * p["lag_M_e"]
        w_rate_M = p["rate_inverse_M"] + error_rate * p["RM"][1]  # |M^-1/2 dw0/dt|
        w_rate = p["rate"] + error_rate * p["V"][1]  # ||dw0/dt||
        c_rest = p["gamma_delta"] + damping / lam_L + p["gamma"]
        alpha0_sup = R + d / np.sqrt(lam_L) + T * lag + s2 * dc
        # w0 frozen at the sample is split off (the equilibrium below): within the period its
        # change is left, with the disturbance and the lag.
        alpha0_int = d / np.sqrt(lam_L) + 0.5 * T * (lag + w_rate_M) + s2 * dc
        alpha = ((c_rest + p["K"] * p["nu"]) * omega + s2 * (rate_N * T * kN + 2 * gamma0)) * Z_
        alpha = alpha + s2 * dT
        beta = (c_rest + p["K"]) * omega + s2 * gamma0
        with np.errstate(invalid="ignore", divide="ignore"):
            denominator = 1 - s2 * beta * T
            usable &= denominator > 0
            denominator = np.where(usable, denominator, 1.0)
        # (7) |N^1/2 dr/dt| <= R0 + Rv . v within the period (beta T carries r(t) - r_k).
        R0 = s2 * alpha0_sup / denominator
        Rv = (s2 * alpha + s2 * s2 * a2 / T * Y_) / denominator
        # (8) zeta (less T N^1/2 M_k^-1 w0_k) and eta, as f + B . v.
        half = 0.5 * beta * T * T
        B_z = h2 * a2 * theta * Y_ + s2 * (T * alpha + half * Rv)
        f_z = s2 * (T * alpha0_int + half * R0) + np.sqrt(h2) * theta * T * R
        predictor = T * (1 + 0.5 * T * kN)
        B_y = predictor * (dT + gamma0 * Z_) + 0.5 * T * kN * a2 * Y_
        f_y = predictor * dc + 0.5 * T * T * Kr_max**2 * root_N * ed_max
        # (9) r(t) less its interpolation between the samples: (T/2) sup |N^1/2 X|, X =
        # dr/dt less its feedback part at M_k.
        E0 = 0.5 * T * s2 * (alpha0_sup + beta * T * R0)
        Ev = 0.5 * T * (s2 * (alpha + beta * T * Rv) + h2 * muT / (1 - muT) * a2 / T * Y_)
        # (10) The equilibrium of the loop frozen at the sample: r^* = K'^-1 w0 = (T M_L'^-1
        # + 1/D) w0, r* = r^* + T N^-1 w0; |z*| <= Z*, |y*| <= Y*, |z* - y*| <= T R.
        Y_star = T * np.sqrt(h2) * R + root_N * V / D
        star = np.stack([Y_star + T * R, Y_star, T * R])
        r_hat_star = T * R_euclid + V / D
        r_star = r_hat_star + T * R / root_N_low
        # (11) Its motion over a period, in the next sample's metric: T M_L^-1 w0 along the
        # motion, w0 / D (where D moves with ||rho||, all of it: gain_varies), the law's M_L
        # at the predicted positions instead of the actual ones, T N^-1 w0.
        jumps = float(self.gain_varies(T))
        rate_law = w_rate_M + p["inverse_change_M"] * (p["Rs"][0] + tube * p["Rs"][1])
        eta = dq * q["law_slope_norm"]
        with np.errstate(invalid="ignore", divide="ignore"):
            usable &= eta < 1
            predicted_M_L = np.where(usable, eta / (1 - eta), 0.0)
            motion_y = (
                T * T * np.sqrt(h2 * (1 + muT)) * rate_law
                + root_N * (T * w_rate + jumps * V) / D
                + 2 * T * predicted_M_L * R / np.sqrt(q["law_over_nominal_low"])
            )
            metric_step = T * rate_N / (1 - T * rate_N) * np.sqrt(1 + T * rate_N)
            # |N_{k+1}^-1/2 x| <= (b_hi)^1/2 |M_L(q(t))^-1/2 x| for the rate at time t.
            across = np.sqrt(q["law_over_nominal_high"])
            motion_z = motion_y + T * (T * across * w_rate_M + metric_step * R)
        # (12) One period: ||xi_{k+1} - xi*_{k+1}||_X <= g (rho + ||B||) ||xi_k - xi*_k||_X
        # + g (||f||_X + ||B v*||_X) + ||motion||_X.
        scales = form.coordinate_scales()[:, None]
        growth = np.sqrt(1 + T * rate_N)
        gain = form.norm_bound(np.sum(B_z * scales, axis=0), np.sum(B_y * scales, axis=0))
        contraction = np.where(usable, growth * (form.rate + gain), math.inf)
        on_star = form.norm_bound(np.sum(B_z * star, axis=0), np.sum(B_y * star, axis=0))
        forcing_parts = np.stack(
            [growth * form.norm_bound(f_z, f_y), growth * on_star,
             form.norm_bound(motion_z, motion_y)]
        )  # fmt: skip
        pushed = np.sum(forcing_parts, axis=0)
        # What the floor is made of (for the report): the quasi-static mismatch, the
        # disturbance, the torque's lag, and the rest (the perturbations on the equilibrium,
        # its motion, the prediction's and the reference's errors), each as a forcing.
        sources = np.stack([
            growth * form.norm_bound(f_z * 0 + T * s2 * R, 0 * f_y),
            growth * form.norm_bound(T * s2 * d / np.sqrt(lam_L), 0 * f_y),
            growth * form.norm_bound(0.5 * T * T * s2 * lag, 0 * f_y),
            pushed,
        ])  # fmt: skip
        return {
            "contraction": contraction, "pushed": pushed, "star": star, "r_star": r_star,
            "r_hat_star": r_hat_star, "sources": sources, "forcing_parts": forcing_parts,
            "f_z": f_z, "f_y": f_y, "motion": (motion_z, motion_y), "B": (B_z, B_y),
            "E0": E0, "Ev": Ev, "dv": dv, "dq": dq, "Kr_min": Kr_min, "J": J,
            "ed_tube": Kr_max * tube,
        }  # fmt: skip

    def _piece_floor(self, T, d, D, q: dict, p: dict, tube: float) -> tuple[float, dict]:
        invalid = self.invalid_parts(p, D)
        if invalid is not None:
            return math.inf, invalid
        terms = self.cell_terms(T, d, D, q, p, tube)
        form = terms["form"]
        if form is None:
            return math.inf, {
                "margin": -math.inf, "gain_D": D,
                "delay_ranges": dataclasses.asdict(self.ranges(T, D, q, p)),
            }  # fmt: skip
        parts = self.margin_parts(terms, D, float(np.max(terms["contraction"])))
        parts.update(delay_rate=form.rate, delay_ranges=dataclasses.asdict(form.ranges))
        margin = parts["margin"]
        if not margin > 0:
            return math.inf, parts
        extent = self.extent(T, terms, q)
        cell = int(np.argmax(terms["pushed"]))
        # The report's shares: the equilibrium (the mismatch), and the deviation's forcing
        # split by source, each carried to the floor.
        sources = terms["parts"]["sources"][:, cell]
        deviation = extent["floor"] - extent["slow"] / extent["Kr_min"]
        named = {
            "mismatch": extent["slow"] / extent["Kr_min"],
            "disturbance": deviation * float(sources[1] / sources[3]),
            "torque_lag": deviation * float(sources[2] / sources[3]),
        }
        named["deviation"] = max(extent["floor"] - sum(named.values()), 0.0)
        parts.update(
            r_sup=extent["r_sup"],
            lambda_L_min=float(np.min(q["nominal_lam_min"])),
            shares=named,
            slow_cell=cell,
            delay_deviation=extent["xi"],
        )
        return extent["floor"], parts

    def extent(self, T: float, terms: dict, q: dict) -> dict[str, float]:
        """The ultimate bound of the deviation ``||xi - xi*||_X`` and what follows: ``||r||``
        over the period (the equilibrium's plus the deviation's, at most ``r_sup`` with the
        predicted state's), ``||r^||`` and the floor of ``||e||`` (the tube, the predicted
        position included)."""
        parts, form = terms["parts"], terms["form"]
        xi = float(np.max(terms["pushed"])) / float(np.min(terms["margin"]))
        scales = form.coordinate_scales()
        v = parts["star"] + xi * scales[:, None]  # |z|, |y|, |z - y| at the ultimate bound
        root_N = np.sqrt(q["nominal_lam_min"])
        # Within a period r(t) is the interpolation of r_k and r_{k+1} (both at most the
        # samples' bound) plus E(t).
        slow = float(np.max(parts["r_star"]))
        samples = float(np.max(parts["r_star"] + xi * scales[0] / root_N))
        within = (parts["E0"] + np.sum(parts["Ev"] * v, axis=0)) / root_N
        moving = samples + float(np.max(within))
        r_hat = float(np.max(parts["r_hat_star"] + xi * scales[1] / root_N))
        predicted = r_hat + float(np.max(np.sqrt(q["nominal_lam_max"]) * parts["dv"] / root_N))
        r_sup = max(moving, predicted) * (1 + 1e-12)
        # The predicted position's error from these bounds (r_max >= r_sup in the regime).
        Kr_max = float(self.Kr.max())
        dq = position_error(T, Kr_max, r_sup, r_sup + parts["ed_tube"], parts["J"])
        floor = (moving / parts["Kr_min"] + dq) * (1 + 1e-12)
        return {
            "xi": xi, "r_sup": r_sup, "floor": floor, "r_hat": r_hat * (1 + 1e-12),
            "slow": slow, "Kr_min": parts["Kr_min"],
        }  # fmt: skip

    def torque_bound(
        self, T: float, d: float, quantities: dict, tube: float, r_sup: float
    ) -> np.ndarray:
        """Per joint, a bound [N m] of the delayed law's torque in the floor's regime. ``u_k =
        tau0(e', r') + (the law's reference) + K' r^`` with ``r^ = r^* + delta``: ``K' r^* =
        w0`` exactly, and ``tau0(e_k, 0) + w0`` is the plant's own torque at ``r = 0``
        (:func:`~urpc.control.cells.plant_torque` over the regime's tube ``||e_k|| <= tube``);
        ``tau0(e', 0) - tau0(e_k, 0)`` is at most ``||G pi0|| ||q^ -
        q_k||``, ``tau0(e', r') - tau0(e', 0)`` at most ``torque_per_r ||r'||``, the law's
        reference ``||N e_i|| (Delta qdd_a + Gamma0 Delta v)`` (with ``N``'s change), and
        ``|e_i^T K' N^-1/2 delta_y| <= ((M_U)_ii b_hi)^1/2 |delta_y| / T``."""
        d = d + self.joints.coulomb
        D = self.gain(T)
        bound = np.zeros(self.dof)
        for p in quantities["pieces"]:
            terms = self.cell_terms(T, d, D, quantities, p, tube)
            if terms["form"] is None or not np.min(terms["margin"]) > 0:
                return np.full(self.dof, math.inf)
            extent = self.extent(T, terms, quantities)
            parts = terms["parts"]
            deviation = extent["xi"] * float(terms["form"].coordinate_scales()[1])
            lam_N_max = quantities["nominal_lam_max"][:, None]
            change = 1 + 2 * quantities["nominal_eps"][:, None] / (
                1 - np.minimum(quantities["nominal_eps"][:, None], 0.999999)
            )
            J = float(np.max(quantities["jerk"]))
            Kr_max = float(self.Kr.max())
            dqdd = T * J + Kr_max * T * T * J / 2
            gamma0 = (
                quantities["gamma_nominal"][:, None]
                + self.joints.damping / quantities["nominal_lam_min"][:, None]
            )
            feedback = np.sqrt(p["upper_diagonal"] * quantities["law_over_nominal_high"][:, None])
            piece = (
                plant_torque(quantities, tube)
                + (quantities["torque_per_error_N"] * quantities["nominal_lam_max"])[:, None]
                * parts["dq"]
                + quantities["torque_per_r"] * extent["r_sup"]
                + lam_N_max * (np.sqrt(change) * dqdd + gamma0 * parts["dv"])
                + feedback * deviation / T
            )
            bound = np.maximum(bound, piece.max(axis=0))
        return bound * (1 + 1e-12)


def position_error(T: float, Kr: float, r_bound: float, ed_bound: float, J: float) -> float:
    """A bound of ``||q^_k - q_k||`` [rad], the predicted position's error: ``T sup ||r(s) -
    r^(s)|| + T^3 J / 6`` over the period before ``t_k`` (``e`` and ``e^`` follow ``de/dt = r -
    Kr e`` from the same error at ``t_{k-1}``; the reference's Taylor remainder), with ``||r(s)||
    <= r_bound`` and the predicted path ``r^(s) = r_{k-1} + s D1 + (Kr s^2 / 2)(D1 - Kr ed)``
    its chord (both ends within ``r_bound``) plus ``(Kr T / 8)(|T D1| + Kr T ||ed||)``, ``|T D1|
    <= 2 r_bound + (Kr T)^2 ||ed|| / 2`` and ``||ed|| <= ed_bound``."""
    step = 2 * r_bound + (Kr * T) ** 2 / 2 * ed_bound
    path = r_bound + Kr * T / 8 * (step + Kr * T * ed_bound)
    return T * (r_bound + path) + T**3 * J / 6
