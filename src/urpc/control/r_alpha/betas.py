"""The bounds ``beta0..beta3`` of the r-alpha design, estimated by seeded uniform sampling of the
full dynamics over the parameter box (the paper's procedure), with Pinocchio regressors."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...errors import InputError
from ...model.regressor import link_regressor_map
from ...model.robot import Robot
from ...model.uncertainty import ParameterBox


@dataclass(frozen=True)
class Betas:
    """Bounds of the r-alpha design (design.md section 4).

    Attributes:
        beta0: Lower bound of ``lambda_min(M(q))`` [kg m^2].
        beta1: Upper bound of ``lambda_max(M(q))`` [kg m^2].
        beta2: ``||C(q, qd)|| <= beta2 ||qd||`` [kg m^2], from ``sqrt(sum_i ||L_i||^2)``.
        beta3: Upper bound of ``||g(q) - d||`` [N m].
        n_samples: Number of samples they were estimated from (``None``: given, not estimated).
        seed: Seed of the sampling (``None``: given, not estimated).
    """

    beta0: float
    beta1: float
    beta2: float
    beta3: float
    n_samples: int | None = None
    seed: int | None = None

    def as_dict(self) -> dict[str, float]:
        return {"beta0": self.beta0, "beta1": self.beta1, "beta2": self.beta2, "beta3": self.beta3}


#: The values Giusti & Althoff report (Sec. IV-C, 1e5 samples), for reports and for reproducing
#: their controller exactly.
PAPER_BETAS = Betas(beta0=0.86, beta1=34.27, beta2=9.95, beta3=210.65, n_samples=100_000)


@dataclass(frozen=True)
class DynamicsSamples:
    """Per-sample quantities behind :class:`Betas` (one row per sample).

    Attributes:
        q: Joint positions [rad], shape ``(n, dof)``.
        points: Parameter points, link name -> coordinates of its box's kind, ``(n, 10)`` each.
        disturbance: Input disturbance ``d`` [N m], ``(n, dof)``, uniform in ``[-b, b]^dof``.
        lambda_min, lambda_max: Extreme eigenvalues of ``M(q)`` [kg m^2], ``(n,)``.
        coriolis_gain: ``sqrt(sum_i ||L_i(q)||_2^2)`` [kg m^2], ``(n,)``.
        gravity_disturbance: ``||g(q) - d||`` [N m], ``(n,)``.
    """

    q: np.ndarray
    points: dict[str, np.ndarray]
    disturbance: np.ndarray
    lambda_min: np.ndarray
    lambda_max: np.ndarray
    coriolis_gain: np.ndarray
    gravity_disturbance: np.ndarray

    def betas(self, seed: int | None = None) -> Betas:
        """The extremes over the samples."""
        return Betas(
            beta0=float(self.lambda_min.min()),
            beta1=float(self.lambda_max.max()),
            beta2=float(self.coriolis_gain.max()),
            beta3=float(self.gravity_disturbance.max()),
            n_samples=len(self.q),
            seed=seed,
        )


def sample_dynamics(
    robot: Robot,
    box: ParameterBox,
    n_samples: int = 100_000,
    seed: int = 0,
    q_range: tuple[float | Sequence[float], float | Sequence[float]] = (0.0, 2 * np.pi),
    disturbance_bound: float = 10.0,
) -> DynamicsSamples:
    """Draw ``q``, the parameters and ``d`` uniformly and evaluate the quantities the betas bound.

    Parameters are drawn uniformly in each link box (its own coordinates: physical or
    barycentric), ``q`` uniformly in ``q_range`` per joint, ``d`` uniformly in the box
    ``[-disturbance_bound, disturbance_bound]^dof`` (the paper's ``-beta_d <= d_i <= beta_d``).

    ``M``, ``C`` and ``g`` are linear in the standard parameters ``pi``, so Pinocchio's joint-torque
    regressor ``Y(q, v, a)`` (``Y pi = M a + C(q, v) v + g``) is evaluated 1 + dof + dof(dof+1)/2
    times per sample and contracted with that sample's ``pi``: ``M e_j`` from ``Y(q, 0, e_j)``,
    ``C(q, e_k) e_j`` from the polarization ``c(e_k + e_j) - c(e_k) - c(e_j) = 2 C(q, e_k) e_j``.

    Raises:
        InputError: ``n_samples < 1``, a negative disturbance bound, or a bad ``q_range``.
    """
    if int(n_samples) < 1:
        raise InputError(f"n_samples={n_samples} must be >= 1", field="n_samples")
    if not np.isfinite(disturbance_bound) or disturbance_bound < 0:
        raise InputError(
            f"disturbance_bound={disturbance_bound} must be a finite number >= 0 [N m]",
            field="disturbance_bound",
        )
    robot = box.nominal_robot(robot)
    n, dof = int(n_samples), robot.dof
    q_low = np.broadcast_to(np.asarray(q_range[0], dtype=float), (dof,))
    q_high = np.broadcast_to(np.asarray(q_range[1], dtype=float), (dof,))
    if not (np.all(np.isfinite(q_low)) and np.all(np.isfinite(q_high)) and np.all(q_low <= q_high)):
        raise InputError(f"q_range={q_range} must be finite with low <= high", field="q_range")

    rng = np.random.default_rng(seed)
    points = {b.link: rng.uniform(b.lower, b.upper, size=(n, 10)) for b in box.links}
    q = rng.uniform(q_low, q_high, size=(n, dof))
    disturbance = rng.uniform(-disturbance_bound, disturbance_bound, size=(n, dof))
    parameters = _body_parameters(robot, box, points)

    lambda_min = np.empty(n)
    lambda_max = np.empty(n)
    coriolis_gain = np.empty(n)
    gravity = np.empty((n, dof))
    evaluator = _RegressorEvaluator(robot)
    # samples per batch: regressor stacks of at most ~4e6 numbers (32 MB)
    chunk = max(1, min(4096, 4_000_000 // (len(evaluator.arguments) * dof * 10 * dof)))
    for start in range(0, n, chunk):
        stop = min(start + chunk, n)
        M, L, g = evaluator(q[start:stop], parameters[start:stop])
        eigenvalues = np.linalg.eigvalsh(M)
        lambda_min[start:stop] = eigenvalues[:, 0]
        lambda_max[start:stop] = eigenvalues[:, -1]
        # L[c, i] is symmetric (Christoffel symbols), so its 2-norm is its largest |eigenvalue|.
        norms = np.abs(np.linalg.eigvalsh(L)).max(axis=-1)
        coriolis_gain[start:stop] = np.sqrt((norms**2).sum(axis=-1))
        gravity[start:stop] = g
    return DynamicsSamples(
        q=q,
        points=points,
        disturbance=disturbance,
        lambda_min=lambda_min,
        lambda_max=lambda_max,
        coriolis_gain=coriolis_gain,
        gravity_disturbance=np.linalg.norm(gravity - disturbance, axis=1),
    )


def estimate_betas(
    robot: Robot,
    box: ParameterBox,
    n_samples: int = 100_000,
    seed: int = 0,
    q_range: tuple[float | Sequence[float], float | Sequence[float]] = (0.0, 2 * np.pi),
    disturbance_bound: float = 10.0,
) -> Betas:
    """Estimate ``beta0..beta3`` by seeded uniform sampling (the paper's procedure).

    ``beta0 = min lambda_min(M)``, ``beta1 = max lambda_max(M)``,
    ``beta2 = max sqrt(sum_i ||L_i||_2^2)``, ``beta3 = max ||g - d||`` over the samples of
    :func:`sample_dynamics` (same arguments). Estimated extremes are not guaranteed bounds: fresh
    samples exceed them with a small probability. Results are cached per robot, box and arguments.
    """
    key = _cache_key(robot, box, n_samples, seed, q_range, disturbance_bound)
    if key not in _BETAS_CACHE:
        samples = sample_dynamics(robot, box, n_samples, seed, q_range, disturbance_bound)
        _BETAS_CACHE[key] = samples.betas(seed)
    return _BETAS_CACHE[key]


_BETAS_CACHE: dict[tuple, Betas] = {}


def _cache_key(robot, box, n_samples, seed, q_range, disturbance_bound) -> tuple:
    bounds = tuple(
        (b.link, b.kind, b.lower.tobytes(), b.upper.tobytes(), b.nominal.tobytes())
        for b in box.links
    )
    q_bytes = tuple(np.asarray(v, dtype=float).tobytes() for v in q_range)
    robot_key = (str(robot.urdf_path), robot.dof, robot.nominal_parameters.tobytes())
    return (robot_key, bounds, int(n_samples), seed, q_bytes, float(disturbance_bound))


def _standard_parameters(kind: str, values: np.ndarray) -> np.ndarray:
    """Vectorized standard parameters ``[m, m c, I_O]`` (about the link origin) of ``(n, 10)``
    coordinates of a link box (the batched form of ``LinkBox.standard_parameters``)."""
    if kind == "barycentric":
        return values
    m = values[:, 0]
    cx, cy, cz = values[:, 1], values[:, 2], values[:, 3]
    out = np.empty_like(values)
    out[:, 0] = m
    out[:, 1:4] = m[:, None] * values[:, 1:4]
    # I_O = I_C + m (|c|^2 1 - c c^T), components in Pinocchio order xx, xy, yy, xz, yz, zz.
    out[:, 4] = values[:, 4] + m * (cy**2 + cz**2)
    out[:, 5] = values[:, 5] - m * cx * cy
    out[:, 6] = values[:, 6] + m * (cx**2 + cz**2)
    out[:, 7] = values[:, 7] - m * cx * cz
    out[:, 8] = values[:, 8] - m * cy * cz
    out[:, 9] = values[:, 9] + m * (cx**2 + cy**2)
    return out


def _body_parameters(robot: Robot, box: ParameterBox, points: dict[str, np.ndarray]) -> np.ndarray:
    """Standard parameters of the moving bodies (regressor column order), ``(n, 10 dof)``."""
    n = len(next(iter(points.values()))) if points else 1
    nominal = np.broadcast_to(robot.nominal_parameters, (n, 10 * robot.dof))
    if not points:
        return nominal
    names = [b.link for b in box.links]
    B = link_regressor_map(robot, names)
    deviation = np.concatenate(
        [
            _standard_parameters(b.kind, points[b.link]) - b.standard_parameters(b.nominal)[None, :]
            for b in box.links
        ],
        axis=1,
    )
    return nominal + deviation @ B.T


class _RegressorEvaluator:
    """``M``, the ``L_i`` matrices and ``g`` at many ``(q, pi)`` pairs from Pinocchio regressors.

    Per sample, the regressor ``Y(q, v, a)`` is evaluated at ``(0, 0)`` (``g``), ``(0, e_j)``
    (``M e_j + g``), ``(e_k, 0)`` (``c(e_k) + g``) and ``(e_k + e_j, 0)`` for ``k < j``, stacked and
    contracted with that sample's parameters in one product.
    """

    def __init__(self, robot: Robot):
        self.robot = robot
        self.data = robot.model.createData()
        dof = robot.dof
        unit, zero = np.eye(dof), np.zeros(dof)
        self.pairs = [(k, j) for k in range(dof) for j in range(k + 1, dof)]
        self.arguments = (
            [(zero, zero)]
            + [(zero, unit[j]) for j in range(dof)]
            + [(unit[k], zero) for k in range(dof)]
            + [(unit[k] + unit[j], zero) for k, j in self.pairs]
        )

    def __call__(
        self, q: np.ndarray, parameters: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``M`` ``(n, dof, dof)``, ``L`` ``(n, dof, dof, dof)`` (``L[:, i]`` is ``L_i``), ``g``."""
        n, dof = q.shape
        model, data = self.robot.model, self.data
        regressor = pin.computeJointTorqueRegressor
        stacked = np.empty((n, len(self.arguments), dof, parameters.shape[1]))
        for s in range(n):
            config = self.robot.configuration(q[s])
            for row, (v, a) in enumerate(self.arguments):
                stacked[s, row] = regressor(model, data, config, v, a)
        torques = np.einsum("scnp,sp->scn", stacked, parameters)
        g = torques[:, 0]
        torques = torques - g[:, None, :]  # remove gravity from every evaluation
        M = np.swapaxes(torques[:, 1 : 1 + dof], 1, 2)  # column j is M e_j
        c = torques[:, 1 + dof : 1 + 2 * dof]  # c(e_k) = C(q, e_k) e_k
        # Cv[s, k, j, i] = (C(q, e_k) e_j)_i, symmetric in (k, j) (Christoffel symbols).
        Cv = np.empty((n, dof, dof, dof))
        for k in range(dof):
            Cv[:, k, k] = c[:, k]
        for p, (k, j) in enumerate(self.pairs):
            Cv[:, k, j] = Cv[:, j, k] = 0.5 * (torques[:, 1 + 2 * dof + p] - c[:, k] - c[:, j])
        # L[s, i, k, j] = (C(q, e_k) e_j)_i, so that (C(q, qd) v)_i = qd^T L_i v.
        L = np.moveaxis(Cv, 3, 1)
        return 0.5 * (M + np.swapaxes(M, 1, 2)), L, g
