"""Physical consistency of a rigid body's rotational inertia."""

from __future__ import annotations

import numpy as np


def inertia_problem(
    inertia_at_com: np.ndarray, tolerance: float = 1e-12, triangle: bool = True
) -> str | None:
    """Why a rotational inertia about the center of mass [kg m^2] is not physical, or ``None``.

    Physical means symmetric positive semi-definite with principal moments satisfying the triangle
    inequality (``I1 + I2 >= I3`` and permutations).
    """
    tensor = np.asarray(inertia_at_com, dtype=float)
    if not np.all(np.isfinite(tensor)):
        return "it has non-finite entries"
    if not np.allclose(tensor, tensor.T, atol=tolerance):
        return "it is not symmetric"
    moments = np.linalg.eigvalsh(tensor)
    scale = max(1.0, float(np.abs(moments).max())) * 1e-9
    if moments[0] < -scale:
        return (
            f"it is not positive semi-definite (principal moments {np.round(moments, 6).tolist()})"
        )
    if triangle and moments[0] + moments[1] < moments[2] - scale:
        return (
            "its principal moments violate the triangle inequality I1 + I2 >= I3 "
            f"({np.round(moments, 6).tolist()})"
        )
    return None
