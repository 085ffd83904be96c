"""Which points of a link box are rigid bodies, and what to say about the others.

A point of a physical box (mass ``m``, CoM ``c``, inertia ``I_C`` about the CoM) is a rigid body
when ``m > 0`` and ``Sigma_C = tr(I_C)/2 * 1 - I_C`` is positive semi-definite: then ``I_C`` is
too (its principal moments are sums of two eigenvalues of ``Sigma_C``) and its principal moments
obey the triangle inequality ``I1 + I2 >= I3``. A point of a barycentric box (``m``, ``h = m c``,
``I_O`` about the link origin) is one when the pseudo-inertia ``J = [[Sigma_O, h], [h^T, m]]``
(``Sigma_O = tr(I_O)/2 * 1 - I_O``) is positive semi-definite with ``m > 0``.

Both conditions are linear matrix inequalities in the box's coordinates, so the rigid bodies form
a convex set: a box lies inside it exactly when its corners do (a box is the convex hull of its
corners). :func:`corner_check` tests the corners of the inertia part of a box (at most 2^6
corners for a physical box, 2^10 for a barycentric one).

Three kinds of boxes are refused by :func:`urpc.model.uncertainty.resolve_link_box`: a negative
lower end where every rigid body is non-negative (:func:`negative_lower_end`), values so large
that the bound overflows (:func:`too_large`), and a nominal that is no rigid body (the nominal
lies in its box, so every accepted box has a rigid body in it). A box only part of which is
non-physical is accepted with a :class:`NonPhysicalBoxWarning` saying which part
(:func:`describe_non_physical_part`): the bound over the whole box, a superset of its rigid
bodies, stays sound.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .parameter_box import LinkBox

#: The largest magnitude of a standard parameter (``m`` [kg], ``m c`` [kg m], ``I_O`` [kg m^2])
#: over a box. The mismatch torque is ``Y_SL (pi - pi0)`` and the control law squares
#: ``rho``: with parameters up to 1e100, regressor entries (joint rates squared times lever arms)
#: up to 1e50 keep ``w``, the margins and ``||rho||^2`` below the largest double (1.8e308).
LARGEST_PARAMETER = 1e100

#: Coordinates that no rigid body makes negative: the mass and the diagonal of an inertia
#: (about the CoM, or about the link origin), by box kind.
NON_NEGATIVE = {
    "physical": ("mass", "ixx", "iyy", "izz"),
    "barycentric": ("m", "I_xx", "I_yy", "I_zz"),
}
_WHY_NON_NEGATIVE = {
    "mass": "a mass is > 0",
    "m": "a mass is > 0",
    "ixx": "a moment of inertia about an axis is >= 0",
    "iyy": "a moment of inertia about an axis is >= 0",
    "izz": "a moment of inertia about an axis is >= 0",
    "I_xx": "a moment of inertia about an axis is >= 0",
    "I_yy": "a moment of inertia about an axis is >= 0",
    "I_zz": "a moment of inertia about an axis is >= 0",
}
#: The inertia coordinates of each kind, by index into the box's 10 coordinates.
_INERTIA = {"physical": range(4, 10), "barycentric": range(0, 10)}
#: Relative tolerance of the corner test (rounding of the written intervals).
TOLERANCE = 1e-9


class NonPhysicalBoxWarning(UserWarning):
    """A box that is accepted although part of it describes no rigid body."""


def negative_lower_end(box: LinkBox) -> tuple[str, str] | None:
    """``(field, message)`` for the first coordinate whose lower end is negative although every
    rigid body has it non-negative, or ``None``."""
    for key in NON_NEGATIVE[box.kind]:
        k = box.fields.index(key)
        if box.lower[k] < 0:
            return key, (
                f"the lower end {box.lower[k]:.6g} of {key} is negative, which no rigid body has "
                f"({_WHY_NON_NEGATIVE[key]}); raise it to 0 or more"
            )
    return None


def too_large(box: LinkBox) -> str | None:
    """Why the box's values are too large for a finite bound (:data:`LARGEST_PARAMETER`), or
    ``None``."""
    magnitude = np.maximum(np.abs(box.lower), np.abs(box.upper))
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow here is the answer
        if box.kind == "physical":
            mass, lever = magnitude[0], np.sqrt(3.0) * magnitude[1:4].max()
            standard = [mass, mass * lever, magnitude[4:10].max() + mass * lever * lever]
        else:
            standard = list(magnitude)
        largest = float(np.max(standard))
    if not largest <= LARGEST_PARAMETER:
        return (
            f"its values are too large for a finite bound: a standard parameter (m, m c or the "
            f"inertia about the link origin) reaches {largest:.3g}, above {LARGEST_PARAMETER:.0e} "
            "(the mismatch torque and ||rho||^2 would overflow double precision); check the units"
        )
    return None


@dataclass(frozen=True)
class CornerCheck:
    """The corners of a box's inertia part that are no rigid body.

    Attributes:
        corners: Number of corners tested.
        bad: Coordinates (10 each, the box's kind) of the corners that are no rigid body, worst
            (most negative eigenvalue) first.
    """

    corners: int
    bad: tuple[np.ndarray, ...]

    @property
    def all_physical(self) -> bool:
        return not self.bad


def corner_check(box: LinkBox) -> CornerCheck:
    """Test every corner of the uncertain inertia coordinates (others at their nominal)."""
    free = [k for k in _INERTIA[box.kind] if box.upper[k] > box.lower[k]]
    corners = np.tile(box.nominal, (2 ** len(free), 1))
    for row, ends in enumerate(itertools.product((0, 1), repeat=len(free))):
        for k, end in zip(free, ends, strict=True):
            corners[row, k] = box.upper[k] if end else box.lower[k]
    least = _least_eigenvalues(box.kind, corners)
    bad = np.flatnonzero(least < -TOLERANCE * _scale(box))
    order = bad[np.argsort(least[bad])]
    return CornerCheck(len(corners), tuple(corners[k] for k in order))


def _scale(box: LinkBox) -> float:
    inertia = np.maximum(np.abs(box.lower), np.abs(box.upper))[list(_INERTIA[box.kind])]
    return max(float(inertia.max()), 1e-300)


def _least_eigenvalues(kind: str, points: np.ndarray) -> np.ndarray:
    """The smallest eigenvalue of ``Sigma_C`` (physical) or of ``J`` (barycentric) per point."""
    if kind == "physical":
        xx, xy, yy, xz, yz, zz = points[:, 4:10].T
        inertia = np.stack(
            [np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)],
            -2,
        )
        trace = np.trace(inertia, axis1=1, axis2=2)
        sigma = 0.5 * trace[:, None, None] * np.eye(3) - inertia
        return np.linalg.eigvalsh(sigma)[:, 0]
    m, hx, hy, hz, xx, xy, yy, xz, yz, zz = points.T
    inertia = np.stack(
        [np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)], -2
    )
    trace = np.trace(inertia, axis1=1, axis2=2)
    pseudo = np.zeros((len(points), 4, 4))
    pseudo[:, :3, :3] = 0.5 * trace[:, None, None] * np.eye(3) - inertia
    pseudo[:, :3, 3] = pseudo[:, 3, :3] = np.stack([hx, hy, hz], -1)
    pseudo[:, 3, 3] = m
    return np.linalg.eigvalsh(pseudo)[:, 0]


def describe_non_physical_part(box: LinkBox, check: CornerCheck) -> str:
    """Which part of the box is no rigid body, in the file's names."""
    if box.kind == "physical" and _diagonal_only(box):
        parts = []
        names = {"ixx": 4, "iyy": 6, "izz": 9}
        for key, (a, b) in {"ixx": ("iyy", "izz"), "iyy": ("ixx", "izz"),
                            "izz": ("ixx", "iyy")}.items():  # fmt: skip
            k, i, j = names[key], names[a], names[b]
            floor = box.lower[i] + box.lower[j]
            if box.upper[k] > floor * (1 + TOLERANCE):
                parts.append(
                    f"{key} > {a} + {b} ({key} reaches {box.upper[k]:.6g}, {a} + {b} goes down "
                    f"to {floor:.6g})"
                )
        if parts:
            return "the triangle inequality fails where " + ", or where ".join(parts)
    worst = check.bad[0]
    free = [k for k in _INERTIA[box.kind] if box.upper[k] > box.lower[k]]
    where = ", ".join(f"{box.fields[k]} = {worst[k]:.6g}" for k in free)
    what = (
        "the inertia about the CoM is not positive semi-definite or violates the triangle "
        "inequality"
        if box.kind == "physical"
        else "the pseudo-inertia is not positive semi-definite"
    )
    return f"{len(check.bad)} of its {check.corners} corners, e.g. {where}: {what} there"


def _diagonal_only(box: LinkBox) -> bool:
    """Physical box whose products of inertia are exactly zero over the box."""
    off = [5, 7, 8]  # ixy, ixz, iyz
    return bool(np.all(box.lower[off] == 0) and np.all(box.upper[off] == 0))
