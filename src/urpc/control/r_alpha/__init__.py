"""The r-alpha tracking controller of Zenieh & Corless (1997), the paper's baseline.

The original text is not available; this is the reconstruction of the design brief (design.md,
section 4), which reproduces exactly the design conditions Giusti & Althoff quote. For the plant
``M qdd + C qd + g = u + d`` and the error ``e = q - q_d``::

    s      = ed + Lambda e,      qd_r = qd_d - Lambda e,      qdd_r = qdd_d - Lambda ed
    rho_ra = beta1 ||qdd_r|| + beta2 ||qd|| ||qd_r|| + beta3                      [N m]
    u      = -Q s - rho_ra^2 / (rho_ra ||s|| + eta) * s                           [N m]

The law has **no model feedforward**: ``rho_ra`` bounds the whole torque the tracking needs,
``||M qdd_r + C qd_r + g - d|| <= rho_ra``, because the bounds are those of the full dynamics::

    lambda_min(M(q)) >= beta0,   lambda_max(M(q)) <= beta1,
    ||C(q, qd)|| <= beta2 ||qd||,   ||g(q) - d|| <= beta3

(the paper's ``beta3 = 210.65 N m`` covers gravity, which a mismatch bound would not; the paper
also says the law runs "without online computation of the model terms"). With
``V = s^T M s / 2`` and ``Mdot - 2C`` skew, ``Vdot = s^T (u - M qdd_r - C qd_r - g + d)
<= -s^T Q s + eta``: the error converges at rate ``alpha`` when ``lambda_min(Lambda) >= alpha`` and
``lambda_min(Q) >= alpha beta1``, and ``limsup ||s|| <= alpha r`` when
``eta <= (alpha r)^2 lambda_min(Q) beta0 / beta1``.

The betas are *estimated* by sampling (:func:`estimate_betas`), as the paper did, so the
r-alpha guarantees are not formal. ``beta2`` uses Zenieh & Corless's bound
``beta2 >= sqrt(sum_i ||L_i||^2)`` where ``(C(q, qd) v)_i = qd^T L_i(q) v``.

Modules: ``betas`` (the sampled estimation of the betas) and ``law`` (:class:`RAlphaController`,
its design conditions and :func:`synthesize_r_alpha`).
"""

from .betas import PAPER_BETAS, Betas, DynamicsSamples, estimate_betas, sample_dynamics
from .law import DesignConditions, RAlphaController, gain_matrix, synthesize_r_alpha

__all__ = [
    "PAPER_BETAS",
    "Betas",
    "DesignConditions",
    "DynamicsSamples",
    "RAlphaController",
    "estimate_betas",
    "gain_matrix",
    "sample_dynamics",
    "synthesize_r_alpha",
]
