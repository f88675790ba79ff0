"""MkDocs hooks for the docs build: tables generated from the code, so they cannot drift.

Placeholders (HTML comments, invisible if the hook is not run):

- ``<!-- gen:pod-support -->``: the pod models of Appendix 7 with the Appendix 8 commands
  each supports, from :mod:`gcu_async.protocol.pods`.
- ``<!-- gen:commands -->``: the client's command table (docs/client.md), and
  ``<!-- gen:send-commands -->``: the ``gcu-async send`` table (docs/cli.md), from the command
  catalogue (:mod:`gcu_async.protocol.catalogue`, itself made from the command schema).
- ``<!-- gen:cli-help NAME -->``: ``gcu-async NAME --help`` (``NAME`` empty: the top level),
  from the real argparse parser.
"""

from __future__ import annotations

import argparse
import enum
import os
import re
from typing import Any

_CLI = re.compile(r"<!-- gen:cli-help ?(?P<name>[a-z-]*) -->")
_PODS = "<!-- gen:pod-support -->"
COMMANDS = "<!-- gen:commands -->"
SEND_COMMANDS = "<!-- gen:send-commands -->"


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


def _pod_support() -> str:
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


def _cli_help(name: str) -> str:
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


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    if _PODS in markdown:
        markdown = markdown.replace(_PODS, _pod_support())
    if COMMANDS in markdown:
        markdown = markdown.replace(COMMANDS, command_table())
    if SEND_COMMANDS in markdown:
        markdown = markdown.replace(SEND_COMMANDS, send_table())
    return _CLI.sub(lambda m: _cli_help(m["name"]), markdown)
