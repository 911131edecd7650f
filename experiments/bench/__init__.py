"""Benchmarks of the engine (`make bench`)."""
from __future__ import annotations

from pathlib import Path


def write_page(out, name: str, lines: list[str]) -> Path:
    """Write a benchmark page (markdown lines) as out/name, creating out, and say where."""
    page = Path(out) / name
    page.parent.mkdir(parents=True, exist_ok=True)
    page.write_text("\n".join(lines) + "\n")
    print(f"\nwrote {page}")
    return page
