"""The docs' generated blocks: text made from the code, committed into the Markdown.

A block sits between two HTML comments (invisible on GitHub and on the site)::

    <!-- gen:KIND [ARGUMENTS] -->
    ... generated text ...
    <!-- /gen -->

so the raw files show what the site shows. Kinds:

- ``commands``: the client's command table (docs/client.md), from the command catalogue
  (:mod:`gcu_async.protocol.catalogue`, itself made from the command schema);
- ``send-commands``: the ``gcu-async send`` table (docs/cli.md), from the same catalogue;
- ``pod-support``: the pod models of Appendix 7 with the Appendix 8 commands each supports
  (docs/protocol-notes.md), from :mod:`gcu_async.protocol.pods`;
- ``cli-help [NAME]``: ``gcu-async NAME --help`` (no NAME: the top level), from the real
  argparse parser at 80 columns;
- ``include PATH SECTION``: the lines between ``[start:SECTION]`` and ``[end:SECTION]``
  comments of another file (PATH from the repository root), e.g. the README's quickstart.

Run ``python docs/_ext/generated.py`` (from the repository root, with the package
installed) to rewrite every stale block, ``--check`` to list them and exit 1.
tests/docs/test_docs_generated.py fails while a block is stale, and so does the strict docs
build (docs/_ext/hooks.py). Whitespace does not count: argparse lays its columns out a little
differently from one Python version to the next, the words are the same.
"""

from __future__ import annotations

import argparse
import enum
import os
import re
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
BLOCK = re.compile(r"^<!-- gen:(?P<spec>[^>]*?) -->\n(?P<body>.*?)^<!-- /gen -->$",
                   re.MULTILINE | re.DOTALL)  # fmt: skip
ANY_MARKER = re.compile(r"^<!-- */?gen\b", re.MULTILINE)


def pages() -> list[Path]:
    """Every Markdown file that may hold a block: the README, docs/, the examples' READMEs."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")),
            *sorted(ROOT.glob("examples/*/README.md"))]  # fmt: skip


# -- the generators ------------------------------------------------------------------------
def _value(value: object) -> str:
    if isinstance(value, enum.Enum):
        return value.name
    return f"{value:g}" if isinstance(value, float) else str(value)


def _param_cell(p: Any) -> str:
    """``name``: range unit (default), the doc."""
    from gcu_async.protocol.catalogue import REQUIRED, Kind

    text = f"`{p.name}`"
    bounds = " ".join(part for part in (p.range_text(), p.unit) if part)
    if p.choices is not None:
        bounds = f"`{p.choices.__name__}` {p.range_text()}"
    detail = "; ".join(part for part in (bounds, p.doc) if part)
    if p.default is None:
        detail += " (default: the current one)"
    elif p.default is not REQUIRED:
        detail += f" (default {_value(p.default)})"
    return f"{text}: {detail}" if p.kind is not Kind.CAMERAS else f"{text} ({_value(p.default)})"


def command_table() -> str:
    """The client's command table, one row per catalogue entry."""
    from gcu_async.protocol.catalogue import CATALOGUE

    lines = ["| Method | Opcode | Parameters: range unit; what (default) | Notes |",
             "|---|---|---|---|"]  # fmt: skip
    for e in CATALOGUE:
        params = "<br>".join(_param_cell(p) for p in e.parameters) or "—"
        rule = e.status.value
        notes = f"{e.doc} Status: {rule}." if e.status.name != "STANDARD" else e.doc
        lines.append(f"| `{e.method}` | 0x{e.opcode:02X} | {params} | {notes} |")
    return "\n".join(lines)


def send_table() -> str:
    """The ``gcu-async send`` table, one row per subcommand (made from the catalogue)."""
    from gcu_async.cli.send_commands import COMMANDS as SEND

    lines = ["| Command | Arguments | Client method |", "|---|---|---|"]
    for name, spec in SEND.items():
        args = " ".join(f"[`{p.name}`]" if p.optional else f"`{p.name}`" for p in spec.params)
        lines.append(f"| `{name}` | {args or '—'} | `{spec.method}` |")
    return "\n".join(lines)


def pod_support() -> str:
    """Appendix 7's models with their Appendix 8 support (● supported, ○ not)."""
    from gcu_async.protocol.pods import (
        MATRIX_COMMANDS,
        POD_NAMES,
        is_radiometric,
        is_thermal,
        supports,
    )

    header = ["Model", "Code", "Thermal", "Radiometric", *(op.name for op in MATRIX_COMMANDS)]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for model, name in POD_NAMES.items():
        cells = [
            name,
            str(int(model)),
            "yes" if is_thermal(model) else "",
            "yes" if is_radiometric(model) else "",
            *("●" if supports(model, op) else "○" for op in MATRIX_COMMANDS),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def cli_help(name: str = "") -> str:
    """``gcu-async NAME --help`` as a text block, at 80 columns."""
    from gcu_async.cli import build_parser

    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "80"
    try:
        parser = build_parser()
        if name:
            (commands,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
            parser = commands.choices[name]
        text = parser.format_help()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    return f"```text\n$ gcu-async {name + ' ' if name else ''}--help\n{text.rstrip()}\n```"


def include(path: str, section: str) -> str:
    """The lines of ``path`` between its ``[start:SECTION]`` and ``[end:SECTION]`` comments."""
    text = (ROOT / path).read_text(encoding="utf-8")
    name = re.escape(section)
    found = re.search(rf"^[^\n]*\[start:{name}\][^\n]*\n(.*?)^[^\n]*\[end:{name}\]", text,
                      re.MULTILINE | re.DOTALL)
    if found is None:
        raise ValueError(f"{path} has no section {section!r} ([start:{section}] … [end:…])")
    return found[1].rstrip("\n")


GENERATORS: dict[str, Callable[..., str]] = {
    "commands": command_table,
    "send-commands": send_table,
    "pod-support": pod_support,
    "cli-help": cli_help,
    "include": include,
}


# -- the blocks of a page ------------------------------------------------------------------
@dataclass(frozen=True)
class Block:
    spec: str
    """What follows ``gen:`` in the opening comment: the kind and its arguments."""
    body: str
    """The committed text between the comments, without its last newline."""
    start: int
    end: int
    """Character offsets of the body in the page."""

    def generate(self) -> str:
        kind, *args = self.spec.split()
        if kind not in GENERATORS:
            raise ValueError(f"unknown generated block {kind!r} (known: {sorted(GENERATORS)})")
        return GENERATORS[kind](*args)

    @property
    def current(self) -> bool:
        return _words(self.body) == _words(self.generate())


def _words(text: str) -> str:
    return " ".join(text.split())


def blocks(text: str) -> list[Block]:
    """The generated blocks of a page; an opening comment without its end is an error."""
    found = [Block(m["spec"].strip(), m["body"].removesuffix("\n"), m.start("body"),
                   m.end("body")) for m in BLOCK.finditer(text)]  # fmt: skip
    markers = len(ANY_MARKER.findall(text))
    if markers != 2 * len(found):
        raise ValueError(f"{markers} gen comments for {len(found)} complete blocks: an opening "
                         "<!-- gen:KIND --> needs its <!-- /gen --> on a line of its own")
    return found


def regenerate(text: str) -> str:
    """``text`` with every block's body made anew (blocks current but for whitespace kept)."""
    out, last = [], 0
    for block in blocks(text):
        new = block.body if block.current else block.generate()
        out += [text[last:block.start], new, "\n"]
        last = block.end
    return "".join([*out, text[last:]])


def stale(paths: list[Path] | None = None) -> Iterator[tuple[Path, Block]]:
    for path in paths if paths is not None else pages():
        for block in blocks(path.read_text(encoding="utf-8")):
            if not block.current:
                yield path, block


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="list stale blocks, exit 1 if any")
    args = parser.parse_args(argv)
    found = list(stale())
    for path, block in found:
        print(f"{path.relative_to(ROOT)}: gen:{block.spec} is "
              f"{'stale' if args.check else 'rewritten'}")
    if not args.check:
        for path in sorted({path for path, _ in found}):
            path.write_text(regenerate(path.read_text(encoding="utf-8")), encoding="utf-8")
    return 1 if args.check and found else 0


if __name__ == "__main__":
    sys.exit(main())
