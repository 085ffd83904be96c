"""Guaranteed parameter intervals from recorded data (``urpc identify``).

One concept per module:

* :mod:`~urpc.identify.data` — data files (CSV/NPZ), derivatives estimated with error bounds;
* :mod:`~urpc.identify.problem` — the unknowns, the prior and the data as a polytope;
* :mod:`~urpc.identify.lp` — its enclosing box by linear programs (HiGHS);
* :mod:`~urpc.identify.core` — :func:`identify`, the file's fields bounded soundly;
* :mod:`~urpc.identify.writer` — the identified box as an uncertainty file;
* :mod:`~urpc.identify.excitation` — exciting Fourier trajectories, identifiable combinations;
* :mod:`~urpc.identify.simulated` — simulated recordings for verification.

``urpc.identify(robot, prior, data, torque_noise)`` calls :func:`identify`: this module is
callable, so the name works whether ``urpc.identify`` resolves to the function or to this
subpackage. Method and figures: ``docs/identification.md``.
"""

from __future__ import annotations

import sys
import types

from .core import FieldBound, Identification, identify
from .data import DerivativeBounds, Samples, load_samples
from .excitation import Excitation, FourierTrajectory, excite
from .lp import InfeasibleData
from .simulated import record

__all__ = [
    "DerivativeBounds",
    "Excitation",
    "FieldBound",
    "FourierTrajectory",
    "Identification",
    "InfeasibleData",
    "Samples",
    "excite",
    "identify",
    "load_samples",
    "record",
]


class _CallableModule(types.ModuleType):
    """``urpc.identify(...)`` is :func:`identify` even once this subpackage is imported."""

    def __call__(self, *args, **kwargs):
        return identify(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
