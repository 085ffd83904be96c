"""A 3D replay of a simulation: one self-contained HTML file that opens offline in a browser.

The arm (its URDF visuals, or a skeleton drawn from its kinematics) moves with the recorded joint
trajectory; the desired end-effector path is drawn as a line; meshcat's panel has play, pause,
reset and a time slider (Animations > default). Several parts play in turn (the configurations of
the reconfiguration demo). See ``docs/replay.md``.

Modules: ``shapes`` (what is drawn of a robot), ``scene`` (the meshcat commands and the
animation), ``page`` (the HTML file).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from ...errors import InputError
from .page import page_commands, page_info, render_page
from .scene import ReplayPart, frame_indices, placements, scene_commands
from .shapes import ReplayGeometryWarning, Shape, end_effector_frame, robot_shapes

#: File name written next to the other results (``urpc simulate --replay``).
REPLAY_NAME = "replay.html"
#: Key frames per second of simulated time, and at most this many key frames per replay.
FPS, MAX_FRAMES = 30.0, 3000


def replay_html(
    parts: ReplayPart | Sequence[ReplayPart],
    *,
    title: str = "urpc replay",
    fps: float = FPS,
    max_frames: int = MAX_FRAMES,
) -> str:
    """The replay page of ``parts`` (played in turn) as HTML text.

    Args:
        parts: What moves (:class:`ReplayPart`).
        title: Page title, shown in the corner with the current part's label and time.
        fps: Key frames per second of simulated time (lowered so that a long run keeps at most
            ``max_frames``); the browser interpolates between them.
        max_frames: Cap on the key frames of the whole replay (the file's size grows with them).
    """
    parts = [parts] if isinstance(parts, ReplayPart) else list(parts)
    if not parts:
        raise InputError("a replay needs at least one part", field="parts")
    if not (math.isfinite(fps) and fps > 0) or max_frames < 1:
        raise InputError("fps must be > 0 and max_frames >= 1", field="fps")
    span = max(float(p.t[-1]) for p in parts) - min(float(p.t[0]) for p in parts)
    if span > 0:
        fps = min(fps, max_frames / span)
    commands, info = scene_commands(parts, fps)
    return render_page(title, commands, {**info, "fps": fps})


def write_replay(path: str | Path, parts: ReplayPart | Sequence[ReplayPart], **options) -> Path:
    """Write :func:`replay_html` to ``path`` (a file; an existing folder gets ``replay.html``);
    returns the file's path. ``options`` as :func:`replay_html`."""
    path = Path(path)
    if path.is_dir():
        path = path / REPLAY_NAME
    text = replay_html(parts, **options)
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InputError(f"cannot write the replay ({exc.strerror or exc})", source=path) from None
    return path


__all__ = [
    "FPS",
    "MAX_FRAMES",
    "REPLAY_NAME",
    "ReplayGeometryWarning",
    "ReplayPart",
    "Shape",
    "end_effector_frame",
    "frame_indices",
    "page_commands",
    "page_info",
    "placements",
    "replay_html",
    "robot_shapes",
    "write_replay",
]
