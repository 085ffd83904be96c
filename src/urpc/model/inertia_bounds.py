"""Sound Loewner bounds of the joint-space inertia over a parameter box: ``M_L(q) <= M(q, pi) <= M_U(q)``.

``M(q, pi) = sum_b J_b(q)^T Sigma_b(pi_b) J_b(q)`` is a sum over bodies of the 6x6 spatial inertias
``Sigma_b`` seen through the body Jacobians. If every link's spatial inertia is bounded in the
Loewner order by constant matrices, ``L_l <= Sigma_l(pi_l) <= U_l`` for every point of its box,
then ``M_L(q) = sum J^T L J`` and ``M_U(q) = sum J^T U J`` bound ``M(q, pi)`` at **every** ``q``
(congruence preserves the order). Both are one CRBA of a model copy whose links carry ``L_l`` or
``U_l`` as their inertias, so each costs what ``M0(q)`` costs. The bounds are built once.

Physical box (mass ``m in [m_lo, m_hi]``, CoM ``c``, inertia about the CoM ``I_c``), with
``Sigma(m, c, I_c) = m G(c)^T G(c) + diag(0, I_c)`` and ``G(c) = [1, -S(c)]``. For any
``theta in (0, 1)``, ``(a + b)^T (a + b) >= (1 - theta) a^T a - (1/theta - 1) b^T b`` and
``S(d)^T S(d) <= |d|^2 1`` give, with ``Delta = max |c - c0|`` over the box::

    Sigma >= spatial(m_lo (1 - theta), c0, I_c0 - (mu_lo + m_hi (1/theta - 1) Delta^2) 1)
    Sigma <= spatial(m_hi (1 + theta), c0, I_c0 + (mu_hi + m_hi (1 + 1/theta) Delta^2) 1)

where ``mu_lo >= lambda_max(I_c0 - I_c)`` and ``mu_hi >= lambda_max(I_c - I_c0)`` over the box
(Gershgorin discs of the interval matrices). The joints' armature adds ``diag(Ia)`` to
``M``: its lower and upper ends go to ``M_L`` and ``M_U``. Barycentric box (``pi = [m, h, I_O]`` in intervals):
``Sigma(pi) - Sigma(pi0) = Sigma(delta)`` and, for any ``alpha > 0``,
``[[0, -S(h)], [S(h), 0]] >= -diag(alpha 1, |h|^2 / alpha 1)``, so::

    Sigma >= Sigma(pi0) + diag((dm_lo - alpha) 1, (l_lo - H^2 / alpha) 1)
    Sigma <= Sigma(pi0) + diag((dm_hi + alpha) 1, (l_hi + H^2 / alpha) 1)

with ``H = max |delta h|`` and ``l_lo <= lambda(delta I_O) <= l_hi`` (Gershgorin). A lower bound
whose mass would be negative is replaced by zero, which is sound for every physical point
(``Sigma >= 0``). ``theta = min(0.9, s Delta)`` and ``alpha = s H`` trade the two losses through one
length scale ``1/s`` [m], chosen at construction to maximise ``beta`` (below) on sample
configurations; any ``s`` gives sound bounds.

``beta(q) = lambda_min(M_U^{-1/2} M_L M_U^{-1/2})`` (so ``M_L >= beta M`` for every plant of the box)
is the relative tightness the sampled-data law's contraction depends on (``docs/sampled-data.md``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import scipy.linalg

from .robot import Robot
from .uncertainty import LinkBox, ParameterBox

#: Candidate inverse length scales ``s`` [1/m] tried when building the bounds.
_SCALES = (0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)


class InertiaBounds:
    """``M_L(q) <= M(q, pi) <= M_U(q)`` for every parameter point ``pi`` of ``box``.

    Args:
        robot: The nominal robot (payloads of ``box`` are attached at their nominal point).
        box: The parameter box.
        scale: The inverse length scale ``s`` [1/m] of the construction; ``None`` picks the one
            that maximises the smallest ``beta`` over sample configurations.

    Attributes:
        lower_robot, upper_robot: Model copies whose ``M(q)`` are ``M_L(q)`` and ``M_U(q)``.
        scale: The inverse length scale used [1/m].
        max_upper_eigenvalue: ``max lambda_max(M_U(q))`` [kg m^2] over 64 configurations within
            the joint limits (sets the sampled law's adaptation ceiling; not a bound).
    """

    def __init__(self, robot: Robot, box: ParameterBox, scale: float | None = None):
        self.robot = box.nominal_robot(robot)
        self.box = box
        if scale is None:
            samples = sample_configurations(self.robot, 12, seed=0)
            scale = max(_SCALES, key=lambda s: _min_beta(*self._copies(s), samples))
        self.lower_robot, self.upper_robot = self._copies(scale)
        self.scale = float(scale)
        configurations = sample_configurations(self.robot, 64, seed=1)
        #: ``max lambda_max(M_U(q))`` [kg m^2] over 64 configurations within the joint limits.
        self.max_upper_eigenvalue = max(
            float(np.linalg.eigvalsh(self.upper(q))[-1]) for q in configurations
        )

    def _copies(self, scale: float) -> tuple[Robot, Robot]:
        """The model copies whose links carry the lower and the upper spatial bounds."""
        lower, upper = {}, {}
        for link_box in self.box.uncertain_links:
            lower[link_box.link], upper[link_box.link] = spatial_bounds(link_box, scale)
        lower_robot = self.robot.with_link_inertias(lower)
        upper_robot = self.robot.with_link_inertias(upper)
        joints = self.box.joints
        if joints is not None and joints.uncertain[0].any():  # armature adds to the diagonal
            values = self.robot.joint_parameters
            values[0] = joints.lower[0]
            lower_robot = lower_robot.with_joint_parameters(values)
            values[0] = joints.upper[0]
            upper_robot = upper_robot.with_joint_parameters(values)
        return lower_robot, upper_robot

    def lower(self, q: np.ndarray) -> np.ndarray:
        """``M_L(q)`` [kg m^2]: ``M(q, pi) - M_L(q)`` is positive semi-definite on the box."""
        return self.lower_robot.M(q)

    def upper(self, q: np.ndarray) -> np.ndarray:
        """``M_U(q)`` [kg m^2]: ``M_U(q) - M(q, pi)`` is positive semi-definite on the box."""
        return self.upper_robot.M(q)

    def beta(self, q: np.ndarray) -> float:
        """``lambda_min(M_U^{-1/2} M_L M_U^{-1/2})`` at ``q``: ``M_L >= beta M`` on the box."""
        return _beta(self.lower_robot, self.upper_robot, q)


def _beta(lower: Robot, upper: Robot, q: np.ndarray) -> float:
    return float(scipy.linalg.eigh(lower.M(q), upper.M(q), eigvals_only=True)[0])


def _min_beta(lower: Robot, upper: Robot, configurations: np.ndarray) -> float:
    return min(_beta(lower, upper, q) for q in configurations)


def spatial_bounds(box: LinkBox, scale: float) -> tuple[pin.Inertia, pin.Inertia]:
    """``(L, U)`` with ``L <= Sigma(pi) <= U`` (6x6 Loewner order) over a link box (module doc)."""
    if box.kind == "physical":
        return _physical_bounds(box, scale)
    return _barycentric_bounds(box, scale)


def _symmetric(components: np.ndarray) -> np.ndarray:
    """The 3x3 matrix of Pinocchio-ordered components ``(xx, xy, yy, xz, yz, zz)``."""
    xx, xy, yy, xz, yz, zz = components
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _gershgorin_max(lower: np.ndarray, upper: np.ndarray) -> float:
    """An upper bound of ``lambda_max(X)`` over the symmetric interval matrix ``[lower, upper]``."""
    radius = np.maximum(np.abs(lower), np.abs(upper))
    np.fill_diagonal(radius, 0.0)
    return float(np.max(np.diag(upper) + radius.sum(axis=1)))


def _spatial(mass: float, lever: np.ndarray, inertia_at_com: np.ndarray) -> pin.Inertia:
    """A spatial inertia that may be non-physical (Pinocchio's constructor refuses those)."""
    inertia = pin.Inertia.Zero()
    inertia.mass = float(mass)
    inertia.lever = np.asarray(lever, dtype=float)
    inertia.inertia = np.asarray(inertia_at_com, dtype=float)
    return inertia


def _physical_bounds(box: LinkBox, scale: float) -> tuple[pin.Inertia, pin.Inertia]:
    nominal, lo, hi = box.nominal, box.lower, box.upper
    m_lo, m_hi = max(float(lo[0]), 0.0), float(hi[0])
    c0 = nominal[1:4]
    delta_sq = float(np.sum(np.maximum((lo[1:4] - c0) ** 2, (hi[1:4] - c0) ** 2)))
    I0 = _symmetric(nominal[4:10])
    mu_lo = _gershgorin_max(I0 - _symmetric(hi[4:10]), I0 - _symmetric(lo[4:10]))
    mu_hi = _gershgorin_max(_symmetric(lo[4:10]) - I0, _symmetric(hi[4:10]) - I0)
    theta = min(0.9, scale * np.sqrt(delta_sq))
    if theta > 0.0:
        loss, gain = m_hi * (1.0 / theta - 1.0) * delta_sq, m_hi * (1.0 + 1.0 / theta) * delta_sq
    else:
        loss = gain = 0.0
    identity = np.eye(3)
    lower = _spatial(m_lo * (1.0 - theta), c0, I0 - (mu_lo + loss) * identity)
    upper = _spatial(m_hi * (1.0 + theta), c0, I0 + (mu_hi + gain) * identity)
    return lower, upper


def _barycentric_bounds(box: LinkBox, scale: float) -> tuple[pin.Inertia, pin.Inertia]:
    nominal = box.nominal
    d_lo, d_hi = box.lower - nominal, box.upper - nominal
    h_radius_sq = float(np.sum(np.maximum(d_lo[1:4] ** 2, d_hi[1:4] ** 2)))
    alpha = scale * np.sqrt(h_radius_sq)
    coupling = h_radius_sq / alpha if alpha > 0.0 else 0.0
    l_hi = _gershgorin_max(_symmetric(d_lo[4:10]), _symmetric(d_hi[4:10]))
    l_lo = -_gershgorin_max(-_symmetric(d_hi[4:10]), -_symmetric(d_lo[4:10]))
    shift = np.zeros(10)

    def shifted(mass_shift: float, inertia_shift: float) -> np.ndarray:
        shift[:] = 0.0
        shift[0] = mass_shift
        shift[[4, 6, 9]] = inertia_shift
        return nominal + shift

    lower = shifted(d_lo[0] - alpha, l_lo - coupling)
    upper = shifted(d_hi[0] + alpha, l_hi + coupling)
    # A lower bound with no positive mass is replaced by zero (Sigma >= 0 at physical points).
    lower_inertia = (
        pin.Inertia.FromDynamicParameters(lower) if lower[0] > 0.0 else pin.Inertia.Zero()
    )
    return lower_inertia, pin.Inertia.FromDynamicParameters(upper)


def sample_configurations(robot: Robot, count: int, seed: int = 0) -> np.ndarray:
    """``count`` configurations drawn uniformly within the joint limits (angles of unlimited
    joints in ``[-pi, pi]``), the first one the zero configuration clipped into the limits."""
    lower, upper = robot.position_limits
    lower = np.where(np.isfinite(lower), lower, -np.pi)
    upper = np.where(np.isfinite(upper), upper, np.pi)
    rng = np.random.default_rng(seed)
    samples = rng.uniform(lower, upper, size=(count, robot.dof))
    samples[0] = np.clip(np.zeros(robot.dof), lower, upper)
    return samples
