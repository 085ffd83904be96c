"""Spatial algebra on Arb balls (Pinocchio's conventions: ``(linear, angular)``, body frames):
frame changes of motions and forces, spatial inertia times a motion, and the symmetrized
Newton-Euler force of a body."""

from __future__ import annotations

from collections.abc import Sequence

from flint import arb

from .balls import (
    HALF,
    Mat,
    Motion,
    Vec,
    add,
    cross,
    rotate,
    rotate_back,
    scale,
    sub,
    sym_times,
)


def act_inverse(R: Mat, t: Vec, motion: Motion) -> Motion:
    """A motion of the parent frame seen in the child frame: ``(R^T (v - t x w), R^T w)``."""
    linear, angular = motion
    return rotate_back(R, sub(linear, cross(t, angular))), rotate_back(R, angular)


def act_force(R: Mat, t: Vec, force: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    """A force of the child frame seen in the parent frame: ``(R f, R n + t x R f)``."""
    linear = rotate(R, force[0])
    return linear, add(rotate(R, force[1]), cross(t, linear))


def add_force(a: tuple[Vec, Vec], b: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    return add(a[0], b[0]), add(a[1], b[1])


def subtract_force(a: tuple[Vec, Vec], b: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    return sub(a[0], b[0]), sub(a[1], b[1])


def inertia_times(parameters: Sequence[arb], physical: bool, motion: Motion) -> tuple[Vec, Vec]:
    """Spatial inertia times a motion ``(x, alpha)``.

    physical ``(m, c, I_C)``: ``(m (x - c x alpha), I_C alpha + c x f_lin)``;
    barycentric ``(m, h, I_O)``: ``(m x - h x alpha, I_O alpha + h x x)``.
    """
    linear, angular = motion
    m, first, tensor = parameters[0], parameters[1:4], parameters[4:10]
    if physical:
        f_lin = scale(m, sub(linear, cross(first, angular)))
        return f_lin, add(sym_times(tensor, angular), cross(first, f_lin))
    return (
        sub(scale(m, linear), cross(first, angular)),
        add(sym_times(tensor, angular), cross(first, linear)),
    )


def cross_force(motion: Motion, force: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    """``(v, omega) x* (f, n) = (omega x f, omega x n + v x f)``."""
    v, omega = motion
    return cross(omega, force[0]), add(cross(omega, force[1]), cross(v, force[0]))


def body_force(
    parameters: Sequence[arb], physical: bool, V: Motion, W: Motion, A: Motion
) -> tuple[Vec, Vec]:
    """``I A + (V x* I W + W x* I V) / 2`` (the symmetrized Newton-Euler force)."""
    inertial = inertia_times(parameters, physical, A)
    bias = add_force(
        cross_force(V, inertia_times(parameters, physical, W)),
        cross_force(W, inertia_times(parameters, physical, V)),
    )
    return add(inertial[0], scale(HALF, bias[0])), add(inertial[1], scale(HALF, bias[1]))
