"""Atomic writes: a failure leaves the previous files, and no partial file, behind."""

from __future__ import annotations

import pytest

from urpc.atomic import check_writable, replace_file, write_files
from urpc.errors import InputError


def test_write_files_replaces_what_it_writes_and_keeps_the_rest(tmp_path):
    target = tmp_path / "out"
    write_files(
        target, {"a.txt": lambda p: p.write_text("1"), "sub/b.txt": lambda p: p.write_text("2")}
    )
    (target / "mine.txt").write_text("keep")

    def broken(path):
        path.write_text("half")
        raise OSError("disk full")

    with pytest.raises(OSError):
        write_files(target, {"a.txt": lambda p: p.write_text("new"), "c.txt": broken})
    assert (target / "a.txt").read_text() == "1" and not (target / "c.txt").exists()
    write_files(target, {"sub/b.txt": lambda p: p.write_text("3")})
    assert (target / "sub" / "b.txt").read_text() == "3" and (target / "mine.txt").is_file()
    assert sorted(p.name for p in target.iterdir()) == ["a.txt", "mine.txt", "sub"]


def test_replace_file_keeps_the_old_content_when_the_write_fails(tmp_path):
    path = tmp_path / "a.json"
    replace_file(path, lambda p: p.write_text("old"))

    def broken(partial):
        partial.write_text("half")
        raise OSError("disk full")

    with pytest.raises(InputError, match="disk full"):
        replace_file(path, broken)
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]  # no partial file left
    replace_file(path, lambda p: p.write_text("new"))
    assert path.read_text() == "new"


def test_check_writable_names_the_file_in_the_way(tmp_path):
    (tmp_path / "file").write_text("x")
    assert check_writable(tmp_path / "new" / "deeper") == tmp_path / "new" / "deeper"
    with pytest.raises(InputError, match="not a folder"):
        check_writable(tmp_path / "file")
    with pytest.raises(InputError, match="not a writable folder"):
        check_writable(tmp_path / "file" / "below")
