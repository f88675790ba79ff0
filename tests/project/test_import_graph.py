"""The import graph of src/gcu_async keeps the layering of docs/architecture.md.

Every ``import``/``from ... import`` of the package in src/ (module level, inside functions
and under ``TYPE_CHECKING`` alike: a cycle hidden from the interpreter is still a cycle for
the reader) is parsed with :mod:`ast`, reduced to an edge between the package's units (a
subpackage or a top-level module), and checked against :data:`ALLOWED`, the table the docs
page repeats (a test checks the two agree). Then: no cycle between units, and none between
modules (:data:`PENDING` lists the edges whose removal is under way).
"""

from __future__ import annotations

import ast
import functools
import re
from collections.abc import Iterable, Mapping
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
SRC = ROOT / "src"
PACKAGE = "gcu_async"
DOC = ROOT / "docs" / "architecture.md"

FOUNDATION = frozenset({"errors", "_checks", "_lifecycle", "_lograte"})
"""The bottom layer every unit may import: the exceptions, the argument checks, the
open/close lifecycle and rate-limited logging. ``errors`` imports nothing of the package;
``_checks`` only ``errors``; ``_lifecycle`` and ``_lograte`` nothing."""

ALLOWED: Mapping[str, frozenset[str]] = {
    "errors": frozenset(),
    "_lifecycle": frozenset(),
    "_lograte": frozenset(),
    "_checks": frozenset({"errors"}),
    "protocol": FOUNDATION,
    "session": FOUNDATION | {"protocol"},
    "capture": FOUNDATION | {"protocol"},
    "transport": FOUNDATION | {"protocol", "capture"},
    "mavlink": FOUNDATION | {"protocol"},
    "wireshark": FOUNDATION | {"protocol"},
    "conformance": FOUNDATION | {"protocol"},
    "client": FOUNDATION | {"protocol", "session", "transport", "capture", "conformance"},
    "sim": FOUNDATION | {"protocol", "transport", "capture", "conformance"},
    "pytest_plugin": FOUNDATION | {"protocol", "transport", "client", "sim"},
    "bridge": FOUNDATION | {"protocol", "session", "transport", "capture", "client", "mavlink"},
    "gcu_async": FOUNDATION | {"protocol", "session", "transport", "client"},
    "cli": FOUNDATION | {
        "protocol", "session", "transport", "capture", "client", "sim", "mavlink", "wireshark",
        "bridge", "gcu_async", "conformance",
    },
    "__main__": frozenset({"cli"}),
}  # fmt: skip
"""unit → the units it may import (``gcu_async``: the package's own ``__init__``)."""


def module_name(path: Path, root: Path = SRC) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(path: Path, root: Path = SRC) -> Iterable[str]:
    """Every module ``path`` imports (absolute names; relative imports resolved), wherever
    the import statement stands: at module level, inside a function, under
    ``TYPE_CHECKING``."""
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            names = False  # `from gcu_async import protocol` imports a module, not a name
            for alias in node.names:
                if _is_module(f"{base}.{alias.name}", root):
                    yield f"{base}.{alias.name}"
                else:
                    names = True
            if names:
                yield base


def _is_module(name: str, root: Path) -> bool:
    path = root / name.replace(".", "/")
    return path.is_dir() or path.with_suffix(".py").exists()


def unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else PACKAGE


def module_graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for path in sorted((SRC / PACKAGE).rglob("*.py")):
        graph[module_name(path)] = {
            m for m in imported_modules(path) if m == PACKAGE or m.startswith(PACKAGE + ".")
        }
    return graph


def unit_graph(modules: Mapping[str, set[str]]) -> dict[str, set[str]]:
    units: dict[str, set[str]] = {}
    for module, targets in modules.items():
        edges = units.setdefault(unit(module), set())
        edges.update(unit(t) for t in targets if unit(t) != unit(module))
    return units


def find_cycle(graph: Mapping[str, Iterable[str]]) -> list[str] | None:
    """A cycle of ``graph`` as a list of nodes (first == last), or None."""
    state: dict[str, int] = {}  # 1: on the stack, 2: done
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == 1:
                return [*stack[stack.index(target) :], target]
            if target not in state:
                found = visit(target)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


@functools.cache
def _graphs() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """The module graph and the unit graph, parsed once per process and only when a test
    asks (parsing every module at collection would cost each pytest-xdist worker)."""
    modules = module_graph()
    return modules, unit_graph(modules)


def modules_() -> dict[str, set[str]]:
    return _graphs()[0]


def units_() -> dict[str, set[str]]:
    return _graphs()[1]


def test_the_graph_is_read() -> None:
    """The parser finds the imports (a graph read wrongly would pass every rule)."""
    assert len(modules_()) > 80
    assert "gcu_async.protocol.packets" in modules_()["gcu_async.client.client"] or any(
        m.startswith("gcu_async.protocol") for m in modules_()["gcu_async.client.client"]
    )
    assert {"protocol", "session", "transport"} <= units_()["client"]
    assert "cli" in units_()["__main__"]


def test_every_unit_is_in_the_table() -> None:
    missing = sorted(set(units_()) - set(ALLOWED))
    assert not missing, f"add {missing} to ALLOWED here and to docs/architecture.md"


def test_every_import_is_allowed() -> None:
    wrong = [
        f"{source} -> {target}"
        for source, targets in sorted(units_().items())
        for target in sorted(targets)
        if target not in ALLOWED.get(source, frozenset())
    ]
    assert not wrong, "imports the layering forbids (docs/architecture.md): " + ", ".join(wrong)


def test_the_named_rules() -> None:
    """The rules of issue 10, spelled out (the table must not loosen them)."""
    above_protocol = set(ALLOWED) - FOUNDATION - {"protocol"}
    assert not ALLOWED["protocol"] & above_protocol
    assert ALLOWED["errors"] == frozenset()
    assert ALLOWED["session"] <= FOUNDATION | {"protocol"}
    assert not ALLOWED["transport"] & {"session", "client", "sim", "cli"}
    assert not ALLOWED["sim"] & {"client", "cli"}


def test_no_cycle_between_units() -> None:
    assert find_cycle(units_()) is None, find_cycle(units_())
    assert find_cycle(ALLOWED) is None, "the table itself has a cycle"


PENDING: Mapping[tuple[str, str], str] = {}
"""Module edges that close a cycle, each with the work that removes it (none should be added:
a new cycle is fixed, not listed)."""


def test_no_cycle_between_modules() -> None:
    """No module imports, however lazily, a module that imports it back (a cycle inside a
    unit is still a cycle for the reader)."""
    graph = {m: targets - {t for s, t in PENDING if s == m} for m, targets in modules_().items()}
    assert find_cycle(graph) is None, " -> ".join(find_cycle(graph) or [])


def test_every_pending_edge_still_closes_a_cycle() -> None:
    """A pending edge whose import is gone is dropped, not kept."""
    for source, target in PENDING:
        assert target in modules_()[source], f"{source} -> {target} is gone: drop it from PENDING"
        assert _reaches(modules_(), target, source), f"{source} -> {target} closes no cycle"


def _reaches(graph: Mapping[str, Iterable[str]], start: str, goal: str) -> bool:
    seen, todo = set(), [start]
    while todo:
        node = todo.pop()
        if node == goal:
            return True
        if node not in seen:
            seen.add(node)
            todo.extend(graph.get(node, ()))
    return False


def test_the_module_graph_reads_lazy_and_type_checking_imports(tmp_path: Path) -> None:
    """An import inside a function or under ``TYPE_CHECKING`` is an edge, and
    ``from package import module`` is an edge to the module, not to the package."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from pkg import a\n", encoding="utf-8")
    (pkg / "a.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.b import B\n",
        encoding="utf-8")  # fmt: skip
    (pkg / "b.py").write_text("def f():\n    from pkg import a\n", encoding="utf-8")
    found = {path.stem: set(imported_modules(path, root=tmp_path)) for path in pkg.glob("*.py")}
    assert found == {"__init__": {"pkg.a"}, "a": {"typing", "pkg.b"}, "b": {"pkg.a"}}
    graph = {f"pkg.{name}": {t for t in targets if t.startswith("pkg.")}
             for name, targets in found.items()}  # fmt: skip
    assert find_cycle(graph) == ["pkg.a", "pkg.b", "pkg.a"]


def test_no_cycle_between_the_simulators_modules() -> None:
    sim = {
        m: {t for t in targets if t.startswith("gcu_async.sim.")}
        for m, targets in modules_().items()
        if m.startswith("gcu_async.sim.")
    }
    assert find_cycle(sim) is None, " -> ".join(find_cycle(sim) or [])


def test_the_cycle_finder_finds_cycles() -> None:
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None
    assert find_cycle({"a": {"a"}}) == ["a", "a"]


def _doc_table() -> dict[str, frozenset[str]]:
    text = DOC.read_text(encoding="utf-8")
    start = text.index("<!-- allowed-imports -->")
    rows: dict[str, frozenset[str]] = {}
    for line in text[start:].splitlines()[1:]:
        if not line.startswith("|"):
            if rows:
                break
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0].startswith("-") or cells[0] == "Unit":
            continue
        names = re.findall(r"`([\w.]+)`", cells[1])
        unit_name = re.findall(r"`([\w.]+)`", cells[0])[0]
        rows[unit_name.removeprefix("gcu_async.")] = frozenset(
            n.removeprefix("gcu_async.") for n in names
        )
    return rows


def test_the_docs_table_is_this_table() -> None:
    assert _doc_table() == dict(ALLOWED)
