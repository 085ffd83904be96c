"""Output folders and files follow the umask, and a writer never leaves a hidden scratch folder
beside its output, not even when killed (issue 21.2)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from urpc.atomic import PARTIAL_SUFFIX, write_files


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def test_new_folders_and_files_follow_the_umask(tmp_path, umask_022):
    out = tmp_path / "deep" / "out"
    write_files(
        out, {"a.txt": lambda p: p.write_text("a"), "sub/b.txt": lambda p: p.write_text("b")}
    )
    for folder in (tmp_path / "deep", out, out / "sub"):
        assert folder.stat().st_mode & 0o777 == 0o755, folder
    for path in (out / "a.txt", out / "sub" / "b.txt"):
        assert path.stat().st_mode & 0o777 == 0o644, path
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deep"]


def test_a_failing_writer_removes_what_it_wrote(tmp_path):
    def broken(path):
        path.write_text("half")
        raise OSError("disk full")

    with pytest.raises(OSError):
        write_files(tmp_path / "new", {"a.txt": lambda p: p.write_text("a"), "b.txt": broken})
    assert list(tmp_path.iterdir()) == []


def test_a_killed_reproduce_paper_leaves_no_scratch_beside_its_output(tmp_path):
    out = tmp_path / "results" / "paper"
    process = subprocess.Popen(
        [sys.executable, "-m", "urpc", "reproduce-paper", "--out", str(out), "--duration", "0.3"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    time.sleep(4.0)  # inside the runs (the workers are up)
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=10)
    leftovers = [p for p in tmp_path.rglob("*") if p.name.startswith(".")]
    assert leftovers == []
    partial = [p for p in tmp_path.rglob(f"*{PARTIAL_SUFFIX}*")]
    assert all(out in p.parents for p in partial)  # if any, inside the output, visible
