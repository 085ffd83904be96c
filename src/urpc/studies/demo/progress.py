"""One progress bar over the several simulations of a demo."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from ...errors import InputError


class ProgressReporter:
    """One progress bar over several simulations: :meth:`part` gives the ``i``-th of ``n``
    simulations a callable for ``simulate(progress=...)``."""

    def __init__(self, progress: Any, description: str):
        self._bar = None
        self._callback = None
        self._done = 0.0
        if progress is True:
            from tqdm import tqdm

            self._bar = tqdm(
                total=100,
                file=sys.stderr,
                leave=False,
                desc=description,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}",
            )
        elif callable(progress):
            self._callback = progress
        elif progress not in (None, False):
            raise InputError(
                f"{progress!r} is not a progress reporter; give True, False, None or a callable",
                field="progress",
            )

    def __enter__(self) -> ProgressReporter:
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._bar is not None:
            self._bar.close()

    def part(self, index: int, count: int) -> Callable[[float], None] | None:
        if self._bar is None and self._callback is None:
            return None
        return lambda fraction: self._update((index + fraction) / count)

    def _update(self, fraction: float) -> None:
        fraction = min(max(fraction, 0.0), 1.0)
        if fraction <= self._done:
            return
        if self._bar is not None:
            self._bar.update(100.0 * (fraction - self._done))
        if self._callback is not None:
            self._callback(fraction)
        self._done = fraction
