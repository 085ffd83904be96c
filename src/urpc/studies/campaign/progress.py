"""Progress of a campaign: a tqdm bar, a callable ``(done, total)``, or nothing."""

from __future__ import annotations

import sys
from typing import Any

from ...errors import InputError


class CampaignProgress:
    """Progress of a campaign: a tqdm bar on stderr (``True``), a callable ``(done, total)``, or
    nothing. The bar appears at :meth:`start`, once the workers are reachable."""

    def __init__(self, progress: Any, total: int):
        if not (progress is None or isinstance(progress, bool) or callable(progress)):
            raise InputError(
                f"{progress!r} is not a progress reporter; give True or a callable (done, total)",
                field="progress",
            )
        self._progress, self._total, self._done, self._bar = progress, total, 0, None

    def start(self) -> None:
        if self._progress is True and self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(total=self._total, file=sys.stderr, unit="run", desc="campaign")

    def advance(self) -> None:
        self._done += 1
        if self._bar is not None:
            self._bar.update(1)
        elif callable(self._progress):
            self._progress(self._done, self._total)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
