"""The tree's shape: no import circles, and every package imports only the layers below it.

Imports are read from the source (module level and inside functions alike), so a lazy import that
runs back up is caught as surely as a top-level one. ``docs/architecture.md`` draws the same layers.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: The library's packages from the bottom up: each may import its own layer's modules and any layer
#: below it, never one above. The data flow is discover -> stack -> synthesise -> judge -> write -> report;
#: the steps that run first sit higher where they call later steps' code (the scan's triage judges pixels).
LAYERS = [
    {"errors", "findings", "memo", "pngchunks", "version", "naming", "fileio", "textures"},
    {"imaging"},
    {"metrics"},
    {"verdict"},
    {"synthesis"},
    {"discover"},
    {"authoring"},
    {"report"},
    {"pipeline"},
    {"api"},
    {"", "hooks"},  # the package itself (its lazy public names come from api) and the DCC hooks
]


def _modules(folder: Path, prefix: str) -> dict[str, Path]:
    out = {}
    for path in sorted(folder.rglob("*.py")):
        parts = list(path.relative_to(folder).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join([prefix, *parts] if prefix else parts)] = path
    return out


def _imports(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The known modules ``name`` imports: ``from a.b import c`` names ``a.b.c`` where that is a module."""
    here = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(here[: len(here) - node.level + 1] + ([node.module] if node.module else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for target in targets:
            parts = target.split(".")
            hit = next((".".join(parts[:k]) for k in range(len(parts), 0, -1) if ".".join(parts[:k]) in known), None)
            if hit is not None and hit != name:
                found.add(hit)
    return found


def _graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _layer(module: str) -> int:
    parts = module.split(".")
    package = parts[1] if len(parts) > 1 else ""
    return next(i for i, names in enumerate(LAYERS) if package in names)


def test_the_layers_name_every_package_of_the_library():
    packages = {p.stem if p.is_file() else p.name for p in (ROOT / "seamless_usd").iterdir()
                if (p.suffix == ".py" and p.stem != "__init__") or (p / "__init__.py").exists()}
    assert packages == set().union(*LAYERS) - {""}


@pytest.mark.parametrize("folder,prefix", [("seamless_usd", "seamless_usd"), ("cli", "seamless_usd_cli"),
                                           ("sample_assets", ""), ("benchmarks", "")])
def test_no_import_circles(folder, prefix):
    assert _circles(_graph(_modules(ROOT / folder, prefix))) == []


def test_no_import_runs_back_up_a_layer():
    graph = _graph(_modules(ROOT / "seamless_usd", "seamless_usd"))
    upward = sorted(f"{a} -> {b}" for a, targets in graph.items() for b in targets if _layer(b) > _layer(a))
    assert upward == []


def test_the_library_never_imports_the_cli():
    for path in (ROOT / "seamless_usd").rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
        names += [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
        assert not any(n.split(".")[0] in {"cli", "seamless_usd_cli"} for n in names), path


def test_a_circle_and_an_upward_import_are_found(tmp_path):
    """The checks above can fail: a planted circle and a verdict module importing the pipeline are seen."""
    pkg = tmp_path / "seamless_usd"
    (pkg / "verdict").mkdir(parents=True)
    (pkg / "pipeline").mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "verdict" / "__init__.py").write_text("")
    (pkg / "pipeline" / "__init__.py").write_text("")
    (pkg / "verdict" / "a.py").write_text("from . import b\n")
    (pkg / "verdict" / "b.py").write_text("def f():\n    from seamless_usd.verdict import a\n")
    (pkg / "verdict" / "c.py").write_text("from seamless_usd.pipeline import run\n")
    (pkg / "pipeline" / "run.py").write_text("")
    graph = _graph(_modules(pkg, "seamless_usd"))
    assert _circles(graph) == [["seamless_usd.verdict.a", "seamless_usd.verdict.b"]]
    assert _layer("seamless_usd.pipeline.run") > _layer("seamless_usd.verdict.c")
    assert "seamless_usd.pipeline.run" in graph["seamless_usd.verdict.c"]
