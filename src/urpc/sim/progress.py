"""Progress reporting, one mechanism for every long task (a simulation, the runs of a demo, of a
campaign, of the paper's reproduction).

A task reports how much of its ``total`` is done; :class:`Progress` passes that to what the caller
asked for: nothing (``None``/``False``), a tqdm bar on stderr (``True``), a tqdm-like bar of the
caller's (anything with ``update``), or a callable. Each task keeps the callable signature it
documents (a fraction, ``(done, total)``, ``(done, total, label)``) through ``report``.

A bar opens at the first report (or :meth:`Progress.start`), never before the task has checked
its inputs, and a task that fails clears its bar, so that no bar is left on the line above the
``error:`` line. Whether to ask for a bar at all is the caller's choice: the CLI asks only when
stderr is a terminal (:func:`urpc.cli.common.show_progress`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from ..errors import InputError

#: How a task calls the caller's callable: ``report(callback, done, total, label)``.
Report = Callable[[Callable[..., Any], float, float, "str | None"], None]


def report_fraction(callback: Callable[[float], Any], done: float, total: float, label) -> None:
    """``callback(done / total)``: a fraction in [0, 1]."""
    callback(done / total)


def report_count(callback: Callable[[int, int], Any], done: float, total: float, label) -> None:
    """``callback(done, total)``: whole units (runs) finished."""
    callback(int(done), int(total))


def report_labelled(
    callback: Callable[[int, int, str], Any], done: float, total: float, label
) -> None:
    """``callback(done, total, label)``: whole units finished and the last one's name."""
    callback(int(done), int(total), label)


class Progress:
    """Progress of a task of ``total`` units (see the module docstring).

    Args:
        progress: ``None``/``False``, ``True``, a tqdm-like bar (``update``), or a callable.
        total: Size of the task, in ``unit`` [1].
        description: The bar's label.
        unit: The bar's unit (``"run"``, ``"%"``).
        report: How a callable is called (:func:`report_fraction` by default).
        leave: Keep the finished bar on screen (a failed task always clears it).
        bar_format: tqdm's ``bar_format``, or ``None`` for tqdm's default.
        accepts_bars: Whether a caller's tqdm-like bar is accepted as ``progress``.
        caller_bar_total: The total given to a caller's bar that has none (default ``total``).

    Raises:
        InputError: ``progress`` is none of the above.
    """

    def __init__(
        self,
        progress: Any,
        total: float,
        *,
        description: str,
        unit: str = "it",
        report: Report = report_fraction,
        leave: bool = True,
        bar_format: str | None = None,
        accepts_bars: bool = False,
        caller_bar_total: float | None = None,
    ):
        self.total, self.completed = total, 0.0
        self._owned, self._bar, self._callback = False, None, None
        self._tqdm = {"desc": description, "unit": unit, "leave": leave}
        if bar_format is not None:
            self._tqdm["bar_format"] = bar_format
        self._report = report
        self._wanted = progress is True
        if progress is None or progress is False or progress is True:
            pass
        elif accepts_bars and hasattr(progress, "update"):
            self._bar = progress
            if getattr(progress, "total", None) is None:
                progress.total = total if caller_bar_total is None else caller_bar_total
        elif callable(progress):
            self._callback = progress
        else:
            kinds = "True, a callable or a tqdm bar" if accepts_bars else "True or a callable"
            raise InputError(
                f"{progress!r} is not a progress reporter; give None, False, {kinds}",
                field="progress",
            )

    @property
    def active(self) -> bool:
        """Whether anything listens (a bar or a callable)."""
        return self._wanted or self._bar is not None or self._callback is not None

    def start(self) -> None:
        """Show the bar now (at 0), e.g. once the workers of a campaign are reachable."""
        if self._wanted and self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(total=self.total, file=sys.stderr, **self._tqdm)
            self._owned = True

    def update_to(self, done: float, label: str | None = None) -> None:
        """Report ``done`` units finished (clipped to ``[0, total]``; never goes back)."""
        done = min(max(done, 0.0), self.total)
        if done <= self.completed and label is None:
            return
        self.start()
        step, self.completed = max(done - self.completed, 0.0), max(done, self.completed)
        if self._bar is not None:
            if label is not None and hasattr(self._bar, "set_postfix_str"):
                self._bar.set_postfix_str(label, refresh=False)
            self._bar.update(self._bar_units(step))
        elif self._callback is not None:
            self._report(self._callback, self.completed, self.total, label)

    def advance(self, amount: float = 1.0, label: str | None = None) -> None:
        """Report ``amount`` more units finished."""
        self.update_to(self.completed + amount, label)

    def close(self, failed: bool = False) -> None:
        """Close the bar this object opened; a ``failed`` task clears it from the terminal."""
        if self._owned and self._bar is not None:
            if failed:
                self._bar.leave = False
            self._bar.close()
            self._bar, self._owned = None, False

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, kind, value, traceback) -> None:
        self.close(failed=kind is not None)

    def _bar_units(self, step: float) -> float:
        # A caller's bar may count in its own total (e.g. 100 for percent).
        total = getattr(self._bar, "total", None) or self.total
        return step * total / self.total


class SimulationProgress(Progress):
    """The progress of one simulation, as the fraction of the simulated time done: ``progress``
    is ``None``, ``True`` (a bar in percent, cleared when done), a callable receiving the fraction
    in [0, 1], or a tqdm-like bar of the caller's."""

    def __init__(self, progress: Any):
        super().__init__(
            progress,
            1.0,
            description="simulate",
            unit="%",
            leave=False,
            bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}",
            accepts_bars=True,
            caller_bar_total=100,
        )

    def update(self, fraction: float) -> None:
        """Report the fraction of the simulated time done."""
        self.update_to(fraction)
