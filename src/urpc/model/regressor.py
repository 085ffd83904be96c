"""The Slotine-Li regressor: ``M(q) qdd_a + C(q, qd) qd_a + g(q) = Y_SL(q, qd, qd_a, qdd_a) pi``.

``pi`` stacks the standard parameters of the moving bodies (Pinocchio order, 10 per joint body,
about the joint frame). ``C`` is the Christoffel-consistent Coriolis matrix, whose product
``C(q, v) w`` is the symmetric bilinear form polarizing ``c(q, x) = C(q, x) x``::

    C(q, v) w = (c(q, v + w) - c(q, v - w)) / 4

Pinocchio's ``computeJointTorqueRegressor`` ``Y_g(q, v, a)`` (``Y_g pi = M a + c(q, v) + g``, for
gravity ``g``) is linear in ``(a, g)`` and quadratic in ``v``. Two calls, one on a model copy with
gravity ``4 g`` and one on a copy without gravity, give::

    4 Y_SL = Y_{4g}(q, qd + qd_a, 4 qdd_a) - Y_0(q, qd - qd_a, 0)

(the first call carries ``4 (M qdd_a + g)`` and ``c(qd + qd_a)``, the second only ``c(qd - qd_a)``;
their difference of velocity products is ``4 C(q, qd) qd_a``). The factors 4 are powers of two, so
they add no rounding. :meth:`SlotineLiRegressor.scaled` returns ``4 Y_SL`` without the final
scaling: the bound methods fold ``1/4`` into the matrices they precompute, which saves one array
operation per control step.

Rounding. Each call's entries are sums of products of size up to ``|qd +- qd_a|^2`` (times lever
arms and parameters), while their difference is of size ``|qd| |qd_a|``: at high joint rates with a
small ``qd_a`` the rounding error of ``4 Y_SL`` follows the magnitude of the terms *before* the
subtraction, not of the result. Every evaluation therefore also computes the scalar envelope
(``docs/bounds.md`` section 7)::

    E = (1 + R + sum_prismatic |q_k|)^2 (2 (sum |qd_k| + sum |qd_a_k|)^2 + 4 sum |qdd_a_k| + 4 |g|)

with ``R`` the sum of the joint placements' translations [m] (a bound of every lever arm): every
entry of either call is at most a small multiple of ``E`` in magnitude, and the bound methods
inflate their enclosures by ``ROUNDING_RECURSION E`` times their parameter magnitudes. The
envelope doubles as the check of the state: a NaN, an infinite value or a state so large that
``E`` overflows raises :class:`~urpc.errors.InputError` naming the vector.

A link fixed to body ``j`` by the placement ``X`` contributes ``A(X) pi_link`` to ``pi_j``, a linear
map of its own standard parameters (link frame); :func:`placement_matrix` builds ``A(X)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pinocchio as pin

from ..errors import InputError, UrpcError
from .robot import Robot


class SlotineLiRegressor:
    """Evaluates ``Y_SL`` for one robot (keeps its own model copies and data buffers).

    Args:
        robot: The robot (only its kinematics matter; inertias are ignored by regressors).
    """

    #: :meth:`scaled` returns ``SCALE * Y_SL``.
    SCALE = 4.0
    #: Largest rounding envelope accepted [N m per unit parameter and lever arm squared]; beyond
    #: it the regressor's entries (and the enclosures built on them) may overflow double precision.
    ENVELOPE_LIMIT = 1e280

    def __init__(self, robot: Robot):
        self.robot = robot
        gravity = np.asarray(robot.model.gravity.linear)
        self._model_gravity = robot.model.copy()
        self._model_gravity.gravity.linear = self.SCALE * gravity
        self._model_free = robot.model.copy()
        self._model_free.gravity.linear = np.zeros(3)
        self._data_gravity = self._model_gravity.createData()
        self._data_free = self._model_free.createData()
        self._zero = np.zeros(robot.dof)
        model = robot.model
        #: ``R`` [m]: the sum of the joint placements' translations, a bound of every lever arm.
        self.reach = float(
            sum(
                np.linalg.norm(model.jointPlacements[j].translation)
                for j in range(1, model.njoints)
            )
        )
        self._prismatic = np.array(
            [model.joints[j].idx_v for j in range(1, model.njoints)
             if model.joints[j].shortname().startswith("JointModelP")],
            dtype=np.int64,
        )  # fmt: skip
        self._gravity_norm = float(np.linalg.norm(gravity))
        # What rounding_envelope reads: dof, R, |g|, then the prismatic joints' indices.
        self._constants = np.array(
            [robot.dof, self.reach, self._gravity_norm, *self._prismatic], dtype=float
        )
        #: The rounding envelope ``E`` of the last evaluation (see the module docstring).
        self.envelope = math.nan
        #: The largest envelope of all evaluations so far.
        self.largest_envelope = 0.0
        self._last = None
        # Joint angles are the Pinocchio configuration unless a joint is continuous (cos, sin).
        self._configuration = None if robot.model.nq == robot.model.nv else robot.configuration

    def __call__(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> np.ndarray:
        """``Y_SL`` [N m per unit parameter], shape ``(dof, 10 * dof)``.

        Args:
            q: Joint positions [rad or m].
            qd: Joint velocities [rad/s or m/s].
            qd_a: The controller's reference velocity ``qd_d + Kr e`` [rad/s or m/s].
            qdd_a: The controller's reference acceleration ``qdd_d + Kr ed`` [rad/s^2 or m/s^2].
        """
        Y = self.scaled(q, qd, qd_a, qdd_a)
        Y *= 1.0 / self.SCALE
        self._last = Y
        return Y

    def envelope_of(self, Y: np.ndarray) -> float:
        """The rounding envelope for a regressor matrix ``Y`` made by this regressor: its last
        call's if ``Y`` is that call's result, else the largest of all its calls so far (so a
        matrix kept from an earlier call stays covered). Pass the envelope explicitly for a
        matrix made elsewhere.

        Raises:
            UrpcError: this regressor has never been called (the state of ``Y`` is unknown).
        """
        if Y is self._last or Y is self._last_scaled:
            return self.envelope
        if not self.largest_envelope > 0:
            raise UrpcError(
                "this regressor matrix was not made by the bound's own regressor, so the "
                "rounding envelope of its state is unknown: call bound.regressor(q, qd, qd_a, "
                "qdd_a) and pass its result, or pass envelope=regressor.envelope"
            )
        return self.largest_envelope

    def envelope_at_rest(self) -> float:
        """The envelope with ``qd = qd_a = qdd_a = 0`` (gravity only; leaves :attr:`envelope`)."""
        zero = self._zero
        return rounding_envelope(zero, zero, zero, zero, self._constants)

    def state_envelope(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> float:
        """The rounding envelope ``E`` of a state (module docstring), after checking the state.

        Raises:
            InputError: a vector of the wrong shape, a NaN or infinite entry, or a state so large
                that ``E`` exceeds :attr:`ENVELOPE_LIMIT` (the result would overflow).
        """
        try:
            envelope = rounding_envelope(q, qd, qd_a, qdd_a, self._constants)
        except TypeError:  # not contiguous float vectors: convert (slow path)
            try:
                vectors = [np.ascontiguousarray(v, dtype=float) for v in (q, qd, qd_a, qdd_a)]
            except (TypeError, ValueError):
                vectors = None
            if vectors is None or any(v.ndim != 1 for v in vectors):
                raise state_vector_error(
                    self.robot, q=q, qd=qd, qd_a=qd_a, qdd_a=qdd_a
                ) or TypeError("q, qd, qd_a and qdd_a must be vectors of numbers") from None
            envelope = rounding_envelope(*vectors, self._constants)
        if not envelope <= self.ENVELOPE_LIMIT:  # NaN, inf, wrong shape or overflow
            raise state_vector_error(self.robot, q=q, qd=qd, qd_a=qd_a, qdd_a=qdd_a) or InputError(
                "the state is too large for double precision: the mismatch torque's terms "
                f"(rounding envelope {envelope:.3g}) overflow; |qd| = {np.max(np.abs(qd)):.3g}, "
                f"|qd_a| = {np.max(np.abs(qd_a)):.3g}, |qdd_a| = {np.max(np.abs(qdd_a)):.3g}",
                field="qd",
            )
        self.envelope = envelope
        self.largest_envelope = max(self.largest_envelope, envelope)
        return envelope

    def scaled(
        self,
        q: np.ndarray,
        qd: np.ndarray,
        qd_a: np.ndarray,
        qdd_a: np.ndarray,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """``SCALE * Y_SL`` (exactly, the scale is a power of two), written into ``out`` if given.

        The fast path of the bound methods, which fold ``1 / SCALE`` into their own matrices.
        Also sets :attr:`envelope` (and checks the state, see :meth:`state_envelope`).
        """
        try:  # the fast path of state_envelope, inlined (this is the control step's hot path)
            envelope = rounding_envelope(q, qd, qd_a, qdd_a, self._constants)
        except TypeError:  # lists or strided arrays: checked, then converted (slow path)
            envelope = self.state_envelope(q, qd, qd_a, qdd_a)
            q, qd, qd_a, qdd_a = (
                np.ascontiguousarray(v, dtype=float) for v in (q, qd, qd_a, qdd_a)
            )
        if envelope <= self.ENVELOPE_LIMIT:
            self.envelope = envelope
            if envelope > self.largest_envelope:
                self.largest_envelope = envelope
        else:
            self.state_envelope(q, qd, qd_a, qdd_a)  # converts, or raises the error
        try:
            config = q if self._configuration is None else self._configuration(q)
            with_gravity = pin.computeJointTorqueRegressor(
                self._model_gravity, self._data_gravity, config, qd + qd_a, self.SCALE * qdd_a
            )
            free = pin.computeJointTorqueRegressor(
                self._model_free, self._data_free, config, qd - qd_a, self._zero
            )
        except (ValueError, TypeError, IndexError) as exc:
            # Only on failure (free on the fast path): say which vector has the wrong shape.
            raise (
                state_vector_error(self.robot, q=q, qd=qd, qd_a=qd_a, qdd_a=qdd_a) or exc
            ) from None
        # Pinocchio hands back a fresh copy, which can take the difference in place.
        result = np.subtract(with_gravity, free, out=with_gravity if out is None else out)
        if result.ndim == 1:  # Pinocchio returns a one-row matrix as a vector (one joint)
            result = result.reshape(1, -1)
        self._last_scaled = result
        return result

    _last_scaled = None


@numba.njit("f8(f8[::1], f8[::1], f8[::1], f8[::1], f8[::1])", cache=True, nogil=True)
def rounding_envelope(q, qd, qd_a, qdd_a, constants):
    """``E = (1 + R + sum_prismatic |q_k|)^2 (2 (sum |qd| + sum |qd_a|)^2 + 4 sum |qdd_a| + 4 |g|)``,
    with ``constants = [dof, R, |g|, prismatic joint indices...]``; NaN when a vector does not have
    ``dof`` entries or one is NaN or infinite. Compiled (numba, cached on disk): one call costs
    less than one numpy reduction."""
    n = int(constants[0])
    if q.shape[0] != n or qd.shape[0] != n or qd_a.shape[0] != n or qdd_a.shape[0] != n:
        return math.nan
    rates = 0.0
    acceleration = 0.0
    check = 0.0  # stays 0 unless a q is NaN or infinite (0 * inf = NaN)
    for k in range(n):
        rates += abs(qd[k]) + abs(qd_a[k])
        acceleration += abs(qdd_a[k])
        check += 0.0 * q[k]
    arm = 1.0 + constants[1]
    for j in range(3, constants.shape[0]):
        arm += abs(q[int(constants[j])])
    return arm * arm * (2.0 * rates * rates + 4.0 * acceleration + 4.0 * constants[2]) + check


def state_vector_error(robot: Robot, **vectors) -> InputError | None:
    """An error naming the first state vector that is not ``dof`` finite numbers, if any."""
    for name, value in vectors.items():
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return InputError(f"{name} is not a vector of {robot.dof} numbers", field=name)
        if array.shape != (robot.dof,):
            return InputError(
                f"{name} has shape {array.shape}, but {robot.name} has {robot.dof} joints "
                f"({', '.join(robot.joint_names)})",
                field=name,
            )
        if not np.isfinite(array).all():
            with np.printoptions(precision=6, threshold=20):
                return InputError(
                    f"{name} = {array} contains a NaN or infinite value: every state vector must "
                    "be finite",
                    field=name,
                )
    return None


def placement_matrix(placement: pin.SE3) -> np.ndarray:
    """The 10x10 matrix ``A`` with ``pi_body = A pi_link`` for a link at ``placement`` in the body
    frame (standard parameters, Pinocchio order). Exact up to rounding: ``Inertia.se3Action`` is
    linear in the standard parameters, so the columns are differences of two actions. The identity
    placement gives exactly the identity matrix."""
    base = np.zeros(10)
    base[0] = 1.0
    acted_base = np.asarray(
        placement.act(pin.Inertia.FromDynamicParameters(base)).toDynamicParameters()
    )
    A = np.empty((10, 10))
    for k in range(10):
        pi = base.copy()
        pi[k] += 1.0
        acted = placement.act(pin.Inertia.FromDynamicParameters(pi)).toDynamicParameters()
        A[:, k] = np.asarray(acted) - acted_base
    return A


def link_regressor_map(robot: Robot, links: list[str]) -> np.ndarray:
    """``(10 * dof, 10 * len(links))`` matrix ``B`` such that ``Y_SL @ B`` is the regressor of the
    named links' own standard parameters (each in its link frame), side by side."""
    B = np.zeros((10 * robot.dof, 10 * len(links)))
    for column, name in enumerate(links):
        link = robot.link(name)
        if link.joint_index == 0:
            raise ValueError(f"link '{name}' is fixed to the base and has no regressor")
        # Pinocchio's regressor columns follow joint order; body j sits at rows 10 (j-1).
        row = 10 * (link.joint_index - 1)
        B[row : row + 10, 10 * column : 10 * column + 10] = placement_matrix(link.placement)
    return B
