"""The two demos end to end: run, draw, and write the figure and the JSON summaries."""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ...atomic import replace_file
from ...errors import InputError
from ...jsonsafe import jsonable
from .configuration_run import run_configuration
from .figures import plot_reconfigure, plot_tool_change
from .progress import ProgressReporter
from .replay import reconfigure_parts, tool_change_parts
from .settings import (
    DEFAULT_CONFIGURATIONS,
    DISTURBANCE_BOUND,
    DURATION,
    EPSILON,
    SAMPLE_PERIOD,
    TIMING_REPEATS,
    TOOL_CHANGE,
    ConfigurationLike,
    configuration_folders,
)
from .tool_change import tool_change_run


def reconfigure_demo(
    out_dir: str | Path | None = None,
    *,
    configurations: Sequence[ConfigurationLike] | None = None,
    progress: bool | Callable[[float], Any] | None = None,
    duration: float = DURATION,
    epsilon: float = EPSILON,
    sample_period: float = SAMPLE_PERIOD,
    disturbance_bound: float = DISTURBANCE_BOUND,
    seed: int = 0,
    initial_offset: float | Sequence[float] | None = None,
    repeats: int = TIMING_REPEATS,
    replay: bool = False,
) -> dict[str, Any]:
    """Run a sequence of arm configurations, each synthesized on the fly with the same settings.

    Args:
        out_dir: Where to write ``reconfigure.png`` (the figure), ``reconfigure.json`` (the
            returned summary) and, per configuration, ``<name>/summary.json`` with the composed
            URDF and uncertainty file; ``None`` writes nothing.
        configurations: What to run, in order (see :func:`synthesize_configuration`); default
            :data:`DEFAULT_CONFIGURATIONS`.
        progress: ``True`` for a progress bar on stderr, a callable receiving the fraction done in
            ``[0, 1]``, or ``None``.
        duration: Simulated time per configuration [s].
        epsilon: Required precision [rad].
        sample_period: Control period [s].
        disturbance_bound: Radius of the disturbance ball [N m] (unknown to the controllers).
        seed: Seed of the true plants and of the disturbance draws.
        initial_offset: Initial position error [rad] (a number: the same on every joint);
            ``None`` starts on the reference.
        repeats: Timed repeats of each synthesis (the median is reported).
        replay: Also write ``replay.html``, a 3D replay of every configuration in turn
            (:mod:`urpc.sim.replay`).

    Returns:
        ``{"configurations": [{"name", "modules", "dof", "synthesis_time", "met", ...metrics}],
        "settings": {...}, "figure": path or None, "replay": path or None}``.
    """
    configurations = list(DEFAULT_CONFIGURATIONS if configurations is None else configurations)
    if not configurations:
        raise InputError("give at least one configuration", field="configurations")
    out = None if out_dir is None else Path(out_dir)
    folders = configuration_folders(out, configurations)
    runs = []
    with ProgressReporter(progress, "reconfigure", len(configurations)) as report:
        for i, (configuration, folder) in enumerate(zip(configurations, folders, strict=True)):
            runs.append(
                run_configuration(
                    configuration,
                    epsilon=epsilon,
                    sample_period=sample_period,
                    disturbance_bound=disturbance_bound,
                    duration=duration,
                    seed=seed,
                    initial_offset=initial_offset,
                    out_dir=folder,
                    repeats=repeats,
                    progress=report.part(i, len(configurations)),
                )
            )
    summary: dict[str, Any] = {
        "configurations": [run.summary() for run in runs],
        "settings": {
            "epsilon": epsilon,
            "sample_period": sample_period,
            "disturbance_bound": disturbance_bound,
            "disturbance_known": False,
            "duration": duration,
            "seed": seed,
            "initial_offset": initial_offset,
            "timing_repeats": repeats,
            "controller": "interval, default gains (synthesize(robot, box, epsilon, sample_period))",
        },
        "figure": None,
        "replay": None,
    }
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        if replay:
            summary["replay"] = str(_write_replay(out, reconfigure_parts(runs), "reconfigure"))
        figure_path = out / "reconfigure.png"
        plot_reconfigure(runs, epsilon=epsilon).savefig(figure_path, dpi=110)
        summary["figure"] = str(figure_path)
        for folder, entry in zip(folders, summary["configurations"], strict=True):
            write_json(folder / "summary.json", entry)
        write_json(out / "reconfigure.json", summary)
    return summary


def tool_change_demo(
    out_dir: str | Path | None = None,
    *,
    progress: bool | Callable[[float], Any] | None = None,
    before: ConfigurationLike = TOOL_CHANGE[0],
    after: ConfigurationLike = TOOL_CHANGE[1],
    t_change: float = 4.0,
    switch_delay: float = 0.0,
    duration: float = DURATION,
    seed: int = 0,
    initial_offset: float | Sequence[float] | None = None,
    replay: bool = False,
) -> dict[str, Any]:
    """Run :func:`tool_change_run` with the demo's settings; write ``tool_change.png`` and
    ``tool_change.json`` into ``out_dir`` (nothing when ``None``), and with ``replay`` a 3D replay
    ``replay.html``; return the summary."""
    run = tool_change_run(
        before,
        after,
        t_change=t_change,
        switch_delay=switch_delay,
        duration=duration,
        seed=seed,
        initial_offset=initial_offset,
        out_dir=out_dir,
        progress=progress,
    )
    summary = run.summary()
    summary["figure"] = summary["replay"] = None
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        if replay:
            summary["replay"] = str(_write_replay(out, tool_change_parts(run), "tool change"))
        figure_path = out / "tool_change.png"
        plot_tool_change(run).savefig(figure_path, dpi=110)
        summary["figure"] = str(figure_path)
        write_json(out / "tool_change.json", summary)
    return summary


def _write_replay(out: Path, parts, title: str) -> Path | None:
    from ...sim.replay import REPLAY_NAME, write_replay

    if not parts:  # every configuration diverged: nothing moves
        return None
    return write_replay(out / REPLAY_NAME, parts, title=title)


def write_json(path: Path, payload: Mapping[str, Any]) -> None:
    """``payload`` as JSON (non-finite numbers as ``null``) in ``path``, atomically."""
    text = json.dumps(jsonable(dict(payload)), indent=2, allow_nan=False) + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    replace_file(path, lambda partial: partial.write_text(text))
