"""Thread-CPU timing of several functions side by side, in interleaved batches."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def time_calls(
    functions: dict[str, Callable[[], object]], repeats: int = 51, batch_seconds: float = 2e-3
) -> dict[str, float]:
    """Median over ``repeats`` timed batches of the time of one call of each function [s].

    Time is the CPU time of the calling thread (``time.thread_time``), so that other processes
    sharing the machine do not count; batches of the functions alternate (round robin), so that
    what remains of their load (shared caches) hits all of them alike. The batch size of each
    function makes a batch last about ``batch_seconds``."""
    calls = {}
    for name, function in functions.items():
        function()  # warm up caches and lazy allocations
        start = time.thread_time()
        function()
        calls[name] = max(1, int(batch_seconds / max(time.thread_time() - start, 1e-7)))
    samples: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(repeats):
        for name, function in functions.items():
            n = calls[name]
            start = time.thread_time()
            for _ in range(n):
                function()
            samples[name].append((time.thread_time() - start) / n)
    return {name: statistics.median(values) for name, values in samples.items()}
