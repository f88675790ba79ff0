"""The exception trees of the README and the client guide are the exception classes of
``gcu_async.errors``: every class once, under one of its bases, its other bases named
("also …"); nothing listed that does not exist."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import pytest

from gcu_async import errors

ROOT = Path(__file__).resolve().parents[2]
PAGES = ["README.md", "docs/client.md"]
_ROW = re.compile(r"^(?P<indent>(?:[│ ] {3})*)(?:[├└]── )?(?P<name>[A-Z]\w+)(?P<rest>.*)$")

CLASSES = {name: cls for name, cls in inspect.getmembers(errors, inspect.isclass)
           if issubclass(cls, errors.GcuError) and cls.__module__ == errors.__name__}


def tree(page: str) -> dict[str, tuple[str | None, str]]:
    """``name -> (parent, the rest of its row)`` of the first text block rooted at GcuError."""
    text = (ROOT / page).read_text(encoding="utf-8")
    block = text[text.index("```text\nGcuError"):]
    block = block[len("```text\n"):block.index("```", len("```text"))]
    rows: dict[str, tuple[str | None, str]] = {}
    stack: list[str] = []
    for line in block.splitlines():
        match = _ROW.match(line)
        assert match, f"{page}: cannot read {line!r}"
        depth = len(match["indent"]) // 4 + (0 if line.startswith("GcuError") else 1)
        del stack[depth:]
        rows[match["name"]] = (stack[-1] if stack else None, match["rest"])
        stack.append(match["name"])
    return rows


@pytest.mark.parametrize("page", PAGES)
def test_the_tree_lists_every_exception_once(page: str) -> None:
    assert sorted(tree(page)) == sorted(CLASSES)


@pytest.mark.parametrize("page", PAGES)
def test_each_class_sits_under_a_base_and_names_its_other_bases(page: str) -> None:
    for name, (parent, rest) in tree(page).items():
        bases = [b.__name__ for b in CLASSES[name].__bases__ if b is not Exception]
        if parent is None:
            assert name == "GcuError"
            continue
        assert parent in bases, (page, name, parent, bases)
        for other in bases:
            if other != parent:
                assert f"also {other}" in rest or f"also a {other}" in rest, (page, name, other)


def test_the_readmes_range_error_is_the_one_raised() -> None:
    """The README quotes, word for word, what its example call raises."""
    from gcu_async.client import GcuClient
    from gcu_async.transport.memory import MemoryTransport

    gcu = GcuClient(MemoryTransport.pair()[0])
    with pytest.raises(errors.FieldRangeError) as raised:
        gcu.set_angles(pitch=200)
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "`gcu.set_angles(pitch=200)` raises" in text
    assert f"`FieldRangeError: {raised.value}`" in text
