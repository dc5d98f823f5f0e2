"""Where a benchmark leaves its figures: ``NAME.md`` (the tables, to read) beside ``NAME.json`` (every
figure, to compare or re-table), in one folder. Every script that writes such a pair writes it here.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> md, js = write_results(out / "new", "demo", "# Demo\\n", {"rows": [1, 2]})
    >>> md.name, js.name, md.read_text(), json.loads(js.read_text())
    ('demo.md', 'demo.json', '# Demo\\n', {'rows': [1, 2]})
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

__all__ = ["write_results"]


def write_results(out_dir: Path, name: str, markdown: str, data: Any, *, indent: int = 1,
                  end: str = "") -> tuple[Path, Path]:
    """Write ``out_dir/{name}.md`` (``markdown`` as given) and ``out_dir/{name}.json`` (``data`` as JSON
    indented by ``indent``, then ``end``), making the folder where it is missing. Returns the two paths,
    the page first."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    page, figures = out_dir / f"{name}.md", out_dir / f"{name}.json"
    figures.write_text(json.dumps(data, indent=indent) + end)
    page.write_text(markdown)
    return page, figures
