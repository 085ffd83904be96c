"""``rigorous``: an interval Newton-Euler enclosure of ``w`` with outward rounding (Arb balls).

This is the test oracle and the "paper-faithful" mode: the paper evaluated the dynamics over the
parameter box with INTLAB; here the recursive Newton-Euler algorithm (RNEA) is evaluated on
python-flint ``arb`` balls, whose every operation returns a ball that contains the exact result.
It is independent of the fast path: no Pinocchio algorithm, no regressor, no floating-point
arithmetic on the result. Only the model's *data* come from Pinocchio (joint placements, joint
axes, parents, gravity) and from the URDF links (placements, inertias), converted to balls exactly.

The mismatch torque of the paper's eq. (7) over the box ``D``::

    w(D) = tau(q, qd, qd_a, qdd_a; D) - tau(q, qd, qd_a, qdd_a; D0)
    tau  = M(q, D) qdd_a + C(q, qd, D) qd_a + g(q, D)

``C(q, v) w`` is the symmetric bilinear form that polarizes ``c(q, x) = C(q, x) x``, so one RNEA
pass with two velocity sets ``V`` (from ``qd``) and ``W`` (from ``qd_a``) computes ``tau`` when
every quadratic velocity product ``B(x, x)`` of the RNEA is replaced by ``(B(V, W) + B(W, V)) / 2``
(for any bilinear ``B``, ``(B(v+w, v+w) - B(v-w, v-w)) / 4 = (B(v, w) + B(w, v)) / 2``)::

    V_i = X_i V_p + S_i qd_i,   W_i = X_i W_p + S_i qd_a_i,   A_0 = -gravity
    A_i = X_i A_p + S_i qdd_a_i + (V_i x S_i qd_a_i + W_i x S_i qd_i) / 2
    f_i = I_i A_i + (V_i x* I_i W_i + W_i x* I_i V_i) / 2
    tau_i = S_i^T F_i,   F_i = f_i + sum over children k of X_k^* F_k

(Pinocchio's conventions: spatial vectors are ``(linear, angular)``, expressed in the body frame.)
``tau`` is linear in the inertias, so ``w`` is the same recursion with ``f_i`` replaced by
``f_i(box) - f_i(nominal)`` summed over the uncertain links of body ``i`` (exact links cancel
exactly). The interval parameters enter as given by the user: a physical box as mass, center of
mass and inertia about the center of mass (``f_lin = m (a - c x alpha)``,
``f_ang = I_C alpha + c x f_lin``), a barycentric box as ``m, h = m c, I_O``.

Interval evaluation overestimates (each parameter occurs several times in ``f_i``, and rotating an
interval force box wraps it); ``python tests/test_rigorous.py`` measures by how much against a
dense sampled inner hull and against the fast ``hull`` method.

Modules: ``balls`` (precision, conversions, 3-vector algebra), ``spatial`` (spatial algebra and the
body force), ``model`` (joints and link inertias as balls) and ``bound`` (:class:`RigorousBound`).
"""

from .balls import PRECISION, interval_ball, lower_float, upper_float
from .bound import RigorousBound

__all__ = ["PRECISION", "RigorousBound", "interval_ball", "lower_float", "upper_float"]
