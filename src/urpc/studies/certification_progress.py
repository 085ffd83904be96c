"""The progress of one certificate: a status line naming the stage that runs, then one line
saying how the certificate was obtained (:class:`urpc.sim.progress.Progress`)."""

from __future__ import annotations

import sys
from typing import Any

from ..sim.progress import Progress


def _report_message(callback, done: float, total: float, label) -> None:
    callback(label)


class CertificateProgress(Progress):
    """The stages of one certificate (``"enclosing 236 cells (||e|| <= 0.01, ||r|| <= 0.45)"``,
    ``"searching the largest sample period"``), for ``progress``: ``True`` for a status line on
    stderr with the time elapsed (cleared when done), a callable receiving each stage's line, or
    ``None``/``False``. :meth:`finish` then prints (or passes) one closing line such as
    ``certificate: cached (key 1a2b3c4d5e6f)``."""

    def __init__(self, progress: Any):
        super().__init__(
            progress,
            1.0,
            description="certifying",
            unit="stage",
            report=_report_message,
            leave=False,
            bar_format="{desc} [{elapsed}]",
        )

    def stage(self, message: str) -> None:
        """Show that the stage ``message`` has started."""
        if self._callback is not None:
            self._report(self._callback, 0.0, self.total, message)
            return
        self.start()
        if self._bar is not None:
            self._bar.set_description_str(f"certifying: {message}", refresh=True)

    def finish(self, message: str | None) -> None:
        """Clear the status line and leave ``message`` in its place (a callable receives it);
        ``None``: only clear it."""
        self.close()
        if message is None:
            return
        if self._wanted:
            print(message, file=sys.stderr)
        elif self._callback is not None:
            self._report(self._callback, self.total, self.total, message)
