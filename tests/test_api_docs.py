"""docs/api.md lists every public name of urpc (its __all__), one line each, and nothing else."""

from __future__ import annotations

import re
from pathlib import Path

import urpc

API = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def test_every_public_name_has_one_line_in_docs_api():
    listed = re.findall(r"^- `([A-Za-z_][A-Za-z0-9_]*)` — \S", API.read_text(), flags=re.M)
    assert sorted(set(urpc.__all__) - set(listed)) == []  # a public name missing from the docs
    assert sorted(set(listed) - set(urpc.__all__)) == []  # a documented name that is not public
    assert len(listed) == len(set(listed))  # one line each


def test_every_public_name_resolves():
    for name in urpc.__all__:
        assert getattr(urpc, name) is not None, name
