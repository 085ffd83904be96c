"""Progress of a campaign: a tqdm bar, a callable ``(done, total)``, or nothing
(:class:`urpc.sim.progress.Progress`)."""

from __future__ import annotations

from typing import Any

from ...sim.progress import Progress, report_count


class CampaignProgress(Progress):
    """Progress over the runs of a campaign: a tqdm bar on stderr (``True``), a callable
    ``(done, total)``, or nothing. The bar appears at :meth:`start`, once the workers are
    reachable; :meth:`advance` counts one finished run."""

    def __init__(self, progress: Any, total: int):
        super().__init__(progress, total, description="campaign", unit="run", report=report_count)
