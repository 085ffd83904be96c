"""A local process pool that stops at once: Ctrl-C reaches only the parent, which terminates the
workers; a worker whose parent has died exits by itself.

``concurrent.futures.ProcessPoolExecutor`` alone does neither: SIGINT goes to the whole process
group, each worker turns it into a ``KeyboardInterrupt`` result and takes the next task, and
``shutdown`` waits for the running ones; after a SIGKILL of the parent its workers block forever
on their task queue. Here the workers ignore SIGINT, the parent terminates them when it is
interrupted (or fails), and a watchdog thread in each worker exits when its parent is gone.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import signal
import threading
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

#: How often a worker checks that its parent is alive [s].
PARENT_POLL = 0.5


def _worker_start(parent: int) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides; it terminates us
    # The parent builds the same scenario first and reports its warnings once, in one line each;
    # a worker's copies would arrive in Python's multi-line format, once per worker.
    warnings.simplefilter("ignore")
    if hasattr(signal, "pthread_sigmask"):  # blocked by submit_all while this process started
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

    def watch() -> None:
        while True:
            time.sleep(PARENT_POLL)
            if os.getppid() != parent:  # re-parented: the campaign was killed
                os._exit(1)

    threading.Thread(target=watch, name="urpc-parent-watch", daemon=True).start()


@contextmanager
def worker_pool(
    workers: int, *, start_method: str | None = None
) -> Iterator[concurrent.futures.ProcessPoolExecutor]:
    """A process pool of ``workers`` processes (``start_method``: ``"spawn"``, ``"fork"`` or
    ``None`` for the platform's default) whose workers ignore SIGINT and die with their parent.
    Leaving the block normally waits for the pool; leaving it by an exception (``Ctrl-C``
    included) cancels what has not started and terminates the workers at once."""
    context = multiprocessing.get_context(start_method)
    pool = concurrent.futures.ProcessPoolExecutor(
        workers, mp_context=context, initializer=_worker_start, initargs=(os.getpid(),)
    )
    try:
        yield pool
    except BaseException:
        terminate(pool)
        raise
    pool.shutdown(wait=True)


def submit_all(pool: concurrent.futures.ProcessPoolExecutor, function, items) -> list:
    """``[pool.submit(function, item) for item in items]`` with SIGINT blocked meanwhile: the
    workers start during the submissions and inherit the mask, so a Ctrl-C cannot hit one while
    it imports (before it ignores SIGINT) and print its traceback; a Ctrl-C pressed meanwhile
    reaches the parent when the mask is lifted."""
    block = (
        hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread()
    )
    if block:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        return [pool.submit(function, item) for item in items]
    finally:
        if block:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def terminate(pool: concurrent.futures.ProcessPoolExecutor) -> None:
    """Cancel the pending tasks of ``pool`` and terminate its workers without waiting for the
    running tasks (Python 3.14's ``kill_workers``, or the same by hand before it)."""
    stop = getattr(pool, "kill_workers", None)
    if stop is not None:
        stop()
        return
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:  # SIGKILL: a worker holds nothing to clean up (the parent records)
        if process.is_alive():
            process.kill()
    for process in processes:
        process.join(timeout=1.0)
