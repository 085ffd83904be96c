"""The r-alpha law, its design conditions and its synthesis from a robot and a box (equations in
:mod:`urpc.control.r_alpha`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...errors import InputError
from ...model.robot import Robot
from ...model.uncertainty import ParameterBox
from ...validation import positive_number
from ..base import Controller, Reference, sample_period_of
from .betas import Betas, estimate_betas


@dataclass(frozen=True)
class DesignConditions:
    """The r-alpha design conditions (Zenieh & Corless, as quoted by the paper Sec. IV-C).

    Attributes:
        lambda_min_Lambda: ``lambda_min(Lambda)`` [1/s]; must be ``>= alpha`` [1/s].
        lambda_min_Q: ``lambda_min(Q)`` [N m s/rad]; must be ``>= required_Q = alpha beta1``.
        eta: The smoothing parameter [N m rad/s]; must be ``<= eta_max``
            ``= (alpha r)^2 lambda_min(Q) beta0 / beta1``.
    """

    alpha: float
    r: float
    lambda_min_Lambda: float
    lambda_min_Q: float
    required_Q: float
    eta: float
    eta_max: float

    @property
    def rate_Lambda(self) -> bool:
        """``lambda_min(Lambda) >= alpha``."""
        return self.lambda_min_Lambda >= self.alpha

    @property
    def rate_Q(self) -> bool:
        """``lambda_min(Q) >= alpha beta1`` (convergence rate ``alpha``)."""
        return self.lambda_min_Q >= self.required_Q

    @property
    def tolerance(self) -> bool:
        """``eta <= (alpha r)^2 lambda_min(Q) beta0 / beta1`` (ultimate bound ``r``)."""
        return self.eta <= self.eta_max

    @property
    def hold(self) -> bool:
        return self.rate_Lambda and self.rate_Q and self.tolerance

    def __str__(self) -> str:
        def mark(ok: bool) -> str:
            return "holds" if ok else "VIOLATED"

        return (
            f"lambda_min(Lambda) = {self.lambda_min_Lambda:.4g} >= alpha = {self.alpha:.4g}: "
            f"{mark(self.rate_Lambda)}; lambda_min(Q) = {self.lambda_min_Q:.4g} >= alpha beta1 = "
            f"{self.required_Q:.4g}: {mark(self.rate_Q)}; eta = {self.eta:.4g} <= "
            f"(alpha r)^2 lambda_min(Q) beta0/beta1 = {self.eta_max:.4g}: {mark(self.tolerance)}"
        )


class RAlphaController(Controller):
    """The r-alpha tracking law (module docstring), static (no internal state).

    Args:
        betas: The bounds ``beta0..beta3``.
        dof: Number of joints.
        r: Required ultimate bound on ``||s||`` [rad/s].
        alpha: Required convergence rate [1/s].
        Lambda: Error-to-velocity gain [1/s]: a scalar (times I), a diagonal or a matrix; default I.
        Q: Damping gain [N m s/rad], same forms; default 35 I (the paper's).
        eta: Smoothing parameter [N m rad/s]; default 7e-5 (the paper's).
        sample_period: Control period [s] the law runs at under a zero-order hold; ``None``
            (default): continuous time.

    Raises:
        InputError: a gain of the wrong shape, not symmetric positive definite, or a
            non-positive ``r``, ``alpha`` or ``eta``.
    """

    name = "r-alpha"

    def __init__(
        self,
        betas: Betas,
        dof: int,
        *,
        r: float = 1e-2,
        alpha: float = 1.0,
        Lambda: float | np.ndarray | None = None,
        Q: float | np.ndarray | None = None,
        eta: float = 7e-5,
        sample_period: float | None = None,
    ):
        for label, value in (("r", r), ("alpha", alpha), ("eta", eta)):
            positive_number(label, value, "a finite number > 0")
        self.betas = betas
        self.dof = int(dof)
        self.r = float(r)
        self.alpha = float(alpha)
        self.Lambda = gain_matrix(1.0 if Lambda is None else Lambda, self.dof, "Lambda")
        self.Q = gain_matrix(35.0 if Q is None else Q, self.dof, "Q")
        self.eta = float(eta)
        self.sample_period = sample_period_of(sample_period)

    def design_conditions(self) -> DesignConditions:
        """The three design conditions with their values (``.hold`` tells if all are met)."""
        lambda_min_Q = float(np.linalg.eigvalsh(self.Q)[0])
        b = self.betas
        return DesignConditions(
            alpha=self.alpha,
            r=self.r,
            lambda_min_Lambda=float(np.linalg.eigvalsh(self.Lambda)[0]),
            lambda_min_Q=lambda_min_Q,
            required_Q=self.alpha * b.beta1,
            eta=self.eta,
            eta_max=(self.alpha * self.r) ** 2 * lambda_min_Q * b.beta0 / b.beta1,
        )

    def rho(self, q: np.ndarray, qd: np.ndarray, reference: Reference) -> float:
        """``rho_ra = beta1 ||qdd_r|| + beta2 ||qd|| ||qd_r|| + beta3`` [N m]."""
        e = q - reference.q
        ed = qd - reference.qd
        qd_r = reference.qd - self.Lambda @ e
        qdd_r = reference.qdd - self.Lambda @ ed
        b = self.betas
        return float(
            b.beta1 * np.linalg.norm(qdd_r)
            + b.beta2 * np.linalg.norm(qd) * np.linalg.norm(qd_r)
            + b.beta3
        )

    def output(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """``u = -Q s - rho^2 / (rho ||s|| + eta) s`` [N m]."""
        try:
            e = q - reference.q
            s = qd - reference.qd + self.Lambda @ e
            rho = self.rho(q, qd, reference)
            u = -self.Q @ s - (rho * rho / (rho * np.linalg.norm(s) + self.eta)) * s
        except (ValueError, TypeError, IndexError, AttributeError) as exc:
            raise self.state_error(q, qd, reference) or exc from None
        shape = (self.dof,)  # a one-entry vector would broadcast: refuse it
        if not (
            np.shape(q) == np.shape(qd) == u.shape == shape
            and np.shape(reference.q) == np.shape(reference.qd) == np.shape(reference.qdd) == shape
        ):
            raise self.state_error(q, qd, reference) or InputError(
                f"q, qd and the reference must be {self.dof} numbers", field="q"
            )
        return u

    def __repr__(self) -> str:
        return (
            f"RAlphaController(r={self.r:g}, alpha={self.alpha:g}, eta={self.eta:g}, "
            f"betas=({self.betas.beta0:.4g}, {self.betas.beta1:.4g}, {self.betas.beta2:.4g}, "
            f"{self.betas.beta3:.4g}))"
        )


def gain_matrix(value: float | Sequence[float] | np.ndarray, dof: int, name: str) -> np.ndarray:
    """A symmetric positive definite ``dof x dof`` gain from a scalar (times I), a diagonal
    (length ``dof``) or a full matrix.

    Raises:
        InputError: wrong shape, non-finite, not symmetric or not positive definite.
    """
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        array = float(array) * np.eye(dof)
    elif array.shape == (dof,):
        array = np.diag(array)
    elif array.shape != (dof, dof):
        raise InputError(
            f"shape {array.shape} does not fit {dof} joints: give a scalar, {dof} diagonal "
            f"entries or a {dof}x{dof} matrix",
            field=name,
        )
    if not np.all(np.isfinite(array)) or not np.allclose(array, array.T):
        raise InputError(f"{name} must be finite and symmetric, got {array.tolist()}", field=name)
    if np.linalg.eigvalsh(array)[0] <= 0:
        raise InputError(f"{name} must be positive definite, got {array.tolist()}", field=name)
    return array


def synthesize_r_alpha(
    robot: Robot,
    box: ParameterBox,
    *,
    r: float = 1e-2,
    alpha: float = 1.0,
    Lambda: float | np.ndarray | None = None,
    Q: float | np.ndarray | None = None,
    eta: float | None = None,
    betas: Betas | None = None,
    n_samples: int = 100_000,
    seed: int = 0,
    disturbance_bound: float = 10.0,
    q_range: tuple[float | Sequence[float], float | Sequence[float]] = (0.0, 2 * np.pi),
    sample_period: float | None = None,
) -> RAlphaController:
    """Design an r-alpha controller for ``robot`` with parameters in ``box``.

    ``betas`` defaults to :func:`estimate_betas` (``n_samples``, ``seed``, ``q_range``,
    ``disturbance_bound`` [N m], the bound the designer assumes on ``d``). Gains left ``None`` are
    set to the least conservative values meeting the design conditions: ``Lambda = alpha I``,
    ``Q = alpha beta1 I``, ``eta = (alpha r)^2 lambda_min(Q) beta0 / beta1``. Given gains are kept
    as they are; check :meth:`RAlphaController.design_conditions`. ``sample_period`` [s] is the
    period the law runs at (``None``: continuous time).
    """
    if betas is None:
        betas = estimate_betas(robot, box, n_samples, seed, q_range, disturbance_bound)
    dof = box.nominal_robot(robot).dof
    if Lambda is None:
        Lambda = alpha
    if Q is None:
        Q = alpha * betas.beta1
    if eta is None:
        lambda_min_Q = float(np.linalg.eigvalsh(gain_matrix(Q, dof, "Q"))[0])
        eta = (alpha * r) ** 2 * lambda_min_Q * betas.beta0 / betas.beta1
    return RAlphaController(
        betas, dof, r=r, alpha=alpha, Lambda=Lambda, Q=Q, eta=eta, sample_period=sample_period
    )
