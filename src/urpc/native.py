"""Output of native libraries: urdfdom, Pinocchio's C++ parsers and MuJoCo print their own
messages straight to file descriptor 2, around urpc's one ``error:`` line. :func:`captured_stderr`
diverts that descriptor into a temporary file while a native call runs, so that urpc can report
the problem in its own words (and quote the library's first line when it helps)."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator


class Captured:
    """What a native library wrote on stderr inside :func:`captured_stderr` (after the block)."""

    text: str = ""

    @property
    def first_line(self) -> str:
        """The first non-empty line, without the library's ``Error:``/``Warning:`` prefix."""
        for line in self.text.splitlines():
            line = line.strip()
            for prefix in ("Error:", "Warning:", "error:", "warning:"):
                line = line.removeprefix(prefix).strip()
            if line:
                return line
        return ""


@contextlib.contextmanager
def captured_stderr() -> Iterator[Captured]:
    """Divert file descriptor 2 (C/C++ ``stderr``, ``std::cerr``) into a temporary file for the
    block; the text is then in the yielded :class:`Captured`. Python's own ``sys.stderr`` is
    flushed before and after, so nothing of urpc's output is lost or reordered. Where fd 2
    cannot be duplicated (no such descriptor), the block runs unchanged."""
    captured = Captured()
    try:
        saved = os.dup(2)
    except OSError:
        yield captured
        return
    with tempfile.TemporaryFile(mode="w+b") as sink:
        _flush()
        os.dup2(sink.fileno(), 2)
        try:
            yield captured
        finally:
            _flush()
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            captured.text = sink.read(1 << 16).decode("utf-8", "replace")


def _flush() -> None:
    for stream in (sys.stderr, sys.__stderr__):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass
