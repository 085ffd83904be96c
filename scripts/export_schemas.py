"""Write the JSON Schema of every file format to docs/schemas/<format>.schema.json.

The schemas are generated from the pydantic models of ``urpc.formats``; a test checks that the
committed files equal what this script writes. Run it after changing a format:

    python scripts/export_schemas.py
"""

from __future__ import annotations

from pathlib import Path

from urpc.formats import FORMATS, json_schema_text

FOLDER = Path(__file__).resolve().parents[1] / "docs" / "schemas"


def main() -> None:
    FOLDER.mkdir(parents=True, exist_ok=True)
    for name in FORMATS:
        path = FOLDER / f"{name}.schema.json"
        path.write_text(json_schema_text(name))
        print(path)


if __name__ == "__main__":
    main()
