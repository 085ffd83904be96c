"""One progress bar over the several simulations of a demo
(:class:`urpc.sim.progress.Progress`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ...sim.progress import Progress


class ProgressReporter(Progress):
    """One progress bar over ``count`` simulations: :meth:`part` gives the ``i``-th simulation a
    callable for ``simulate(progress=...)``; a callable ``progress`` receives the fraction of the
    whole demo done, in [0, 1]."""

    def __init__(self, progress: Any, description: str, count: int = 1):
        super().__init__(
            progress,
            float(count),
            description=description,
            unit="run",
            leave=False,
            bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}",
        )

    def part(self, index: int, count: int | None = None) -> Callable[[float], None] | None:
        """The progress callable of simulation ``index`` (its fraction done, in [0, 1])."""
        if not self.active:
            return None
        scale = self.total / (count or self.total)
        return lambda fraction: self.update_to(scale * (index + min(max(fraction, 0.0), 1.0)))
