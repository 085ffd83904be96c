"""Small helpers for the words of reports (no dependencies, imported by the CLI at start-up)."""

from __future__ import annotations


def count(number: int, noun: str, plural: str | None = None) -> str:
    """``"1 link"``, ``"2 links"``, ``"0 links"`` (``plural`` for irregular nouns)."""
    return f"{number} {noun if number == 1 else plural or noun + 's'}"
