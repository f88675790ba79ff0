"""Griffe extension for the docs build: render the Sphinx-style markup of gcu_async's
docstrings in Markdown.

- Roles (``:class:`X```, ``:meth:`~a.b.C.m```, ``:func:``, ``:attr:``, ``:data:``, ``:mod:``,
  ``:exc:``) become code spans wrapped in *optional* autorefs: a link when the target is
  rendered somewhere in the docs, plain code otherwise (never a strict-mode warning).
  Names are resolved like Python would from the docstring's object (members, then the
  enclosing class and module, imports included).
- Simple reST tables (``=====  =====`` borders) become Markdown tables.
- Undocumented instance attributes (``self.x = x`` in ``__init__``) lose their value, so
  the reference lists them without echoing the assignment.

Only the copy of the docstrings that the docs build reads is changed; the sources are not.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:class|meth|func|attr|data|mod|exc|obj):`(?P<name>[^`]+)`")
_BORDER = re.compile(r"^(?P<indent>\s*)=+(?:\s+=+)+\s*$")


def _resolve(obj: griffe.Object, name: str) -> str | None:
    if name.startswith("gcu_async."):
        return name
    head, _, rest = name.partition(".")
    try:
        target = obj.resolve(head)
    except (griffe.NameResolutionError, AttributeError, KeyError):
        return None
    if not target.startswith("gcu_async"):
        return None
    return f"{target}.{rest}" if rest else target


def _roles(obj: griffe.Object, text: str) -> str:
    def replace(match: re.Match[str]) -> str:
        raw = match["name"].strip()
        short = raw.startswith("~")
        name = raw.lstrip("~").strip()
        title = name.rsplit(".", 1)[-1] if short else name
        identifier = _resolve(obj, name)
        code = f"<code>{title}</code>"
        if identifier is None:
            return code
        return f'<autoref identifier="{identifier}" optional>{code}</autoref>'

    return _ROLE.sub(replace, text)


def _columns(border: str) -> list[tuple[int, int]]:
    return [(m.start(), m.end()) for m in re.finditer(r"=+", border)]


def _cells(line: str, spans: list[tuple[int, int]]) -> list[str]:
    cells = []
    for i, (start, _) in enumerate(spans):
        end = spans[i + 1][0] if i + 1 < len(spans) else len(line)
        cells.append(line[start:end].strip())
    return cells


def _tables(text: str) -> str:
    lines = text.splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        m = _BORDER.match(lines[i])
        if not m:
            out.append(lines[i])
            i += 1
            continue
        # a simple table: border, header, border, rows, border
        spans = _columns(lines[i])
        j = i + 1
        block: list[list[str]] = []
        header: list[str] | None = None
        closed = False
        while j < len(lines):
            if _BORDER.match(lines[j]):
                if header is None:
                    header = [" ".join(c) for c in zip(*block, strict=True)] if block else []
                    block = []
                else:
                    closed = True
                    break
            elif lines[j].strip():
                cells = _cells(lines[j], spans)
                if block and not cells[0]:  # continuation line
                    block[-1] = [f"{a} {b}".strip() for a, b in zip(block[-1], cells, strict=True)]
                else:
                    block.append(cells)
            j += 1
        if not closed or not header:
            out.append(lines[i])
            i += 1
            continue
        indent = m["indent"]
        out.append("")
        out.append(indent + "| " + " | ".join(header) + " |")
        out.append(indent + "|" + "---|" * len(header))
        for row in block:
            cells = [c.replace("|", "\\|") for c in row]
            out.append(indent + "| " + " | ".join(cells) + " |")
        out.append("")
        i = j + 1
    return "\n".join(out)


class SphinxRoles(griffe.Extension):
    """Rewrite every docstring of the loaded package once it is complete."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        self._walk(pkg, set())

    def _walk(self, obj: griffe.Object, seen: set[str]) -> None:
        if obj.path in seen:
            return
        seen.add(obj.path)
        if obj.docstring is not None:
            text = _tables(obj.docstring.value)
            obj.docstring.value = _roles(obj, text)
        elif isinstance(obj, griffe.Attribute) and "instance-attribute" in obj.labels:
            obj.value = None  # `self.x = x` in __init__: the right-hand side says nothing
        for member in obj.members.values():
            if not member.is_alias:
                self._walk(member, seen)  # type: ignore[arg-type]
