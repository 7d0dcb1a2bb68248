"""Rewrite the shipped JSON Schemas with the plug-in names of the built-in registries.

Run after adding a constraint or an objective to its registry (tests/test_structure.py checks
the shipped files against the registries)::

    PYTHONPATH=src python scripts/write_schemas.py
"""

from __future__ import annotations

from pathlib import Path

from freefloat.plans.schema import SCHEMAS, schema_text

if __name__ == "__main__":
    folder = Path(__file__).resolve().parent.parent / "src" / "freefloat" / "schemas"
    for name in SCHEMAS:
        path = folder / f"{name}.schema.json"
        path.write_text(schema_text(name), encoding="utf-8")
        print(f"wrote {path}")
