"""The progress of one simulation: nothing, a tqdm bar, a callable of the fraction done, or a
tqdm-like bar of the caller's."""

from __future__ import annotations

import sys
from typing import Any

from ..errors import InputError


class SimulationProgress:
    """Adapts ``progress`` (None, True, a callable of the fraction, a tqdm-like bar)."""

    def __init__(self, progress: Any):
        self._owned = False
        self._done = 0.0
        self._bar = None
        self._callback = None
        if progress is True:
            from tqdm import tqdm

            self._bar = tqdm(total=100, file=sys.stderr, unit="%", leave=False, desc="simulate")
            self._owned = True
        elif progress is None or progress is False:
            pass
        elif hasattr(progress, "update"):
            self._bar = progress
            if getattr(progress, "total", None) is None:
                progress.total = 100
        elif callable(progress):
            self._callback = progress
        else:
            raise InputError(
                f"{progress!r} is not a progress reporter; give True, a callable or a tqdm bar",
                field="progress",
            )

    def update(self, fraction: float) -> None:
        fraction = min(max(fraction, 0.0), 1.0)
        if fraction <= self._done:
            return
        if self._bar is not None:
            self._bar.update((fraction - self._done) * self._bar.total)
        elif self._callback is not None:
            self._callback(fraction)
        self._done = fraction

    def close(self) -> None:
        if self._owned and self._bar is not None:
            self._bar.close()
