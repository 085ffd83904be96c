"""``urpc reproduce-paper``: the twelve runs, then the report, the figures and the runs' files
written at once."""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...atomic import check_writable, write_files
from ...errors import InputError
from ...jsonsafe import jsonable
from .figures import figure_writers
from .report import document_of, results_markdown
from .runs import PAPER_CONTROLLERS, PAPER_RUNS, RunReporter, run_all

#: Default output directory of ``urpc reproduce-paper``.
DEFAULT_OUT_DIR = Path("urpc-results") / "paper"


def reproduce_paper(
    out_dir: str | Path = DEFAULT_OUT_DIR,
    *,
    progress: bool | Callable[[int, int, str], Any] | None = None,
    duration: float | None = None,
    workers: int = 2,
) -> dict[str, Any]:
    """Run the paper's six scenarios with both controllers and write the report into ``out_dir``.

    Args:
        out_dir: Output directory (created with its parents; files of an earlier reproduction
            are replaced, other files kept).
        progress: ``None``; ``True`` for a tqdm bar on stderr counting finished runs; or a
            callable ``(finished, total, label)`` called after each run.
        duration: Simulated time of every run [s]; ``None`` keeps the scenario files' 10 s.
        workers: Number of processes (``1``: run in this process, one run after the other).

    Returns:
        The content of ``results.json`` plus ``out_dir`` and ``files`` (paths relative to it).

    Raises:
        InputError: ``duration`` or ``workers`` out of range, or a scenario that fails to load.
        SimulationError: a run diverged.
    """
    if duration is not None and not (
        isinstance(duration, int | float) and math.isfinite(duration) and duration > 0
    ):
        raise InputError(f"{duration!r} must be a finite number > 0 [s]", field="duration")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"{workers!r} must be an integer >= 1", field="workers")
    out_dir = Path(out_dir)
    check_writable(out_dir)  # before any work: a file in the way, a read-only folder
    start = time.perf_counter()
    jobs = [(n, ic, c) for n, ic in PAPER_RUNS for c in PAPER_CONTROLLERS]
    # The 10 kHz runs take longest: start them first so that two workers finish together.
    order = sorted(jobs, key=lambda job: (job[0] != 2, job[0] != 3))
    runs = run_all(order, duration, workers, RunReporter(progress, len(jobs)))
    runs = {job: runs[job] for job in jobs}  # report order
    document = document_of(runs, duration, workers)
    writers = figure_writers(runs)
    for run in runs.values():
        for name, write in run["result"].writers(csv=False).items():
            writers[f"runs/{run['folder']}/{name}"] = write
    document["wall_time"] = time.perf_counter() - start
    writers["results.md"] = _text_writer(results_markdown(document))
    writers["results.json"] = _text_writer(json.dumps(jsonable(document), indent=2) + "\n")
    write_files(out_dir, writers)
    files = sorted(writers)
    return {**document, "out_dir": str(out_dir), "files": files}


def _text_writer(text: str) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_text(text)

    return write
