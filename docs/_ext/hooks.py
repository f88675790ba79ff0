"""MkDocs hooks for the docs build: tables generated from the code, so they cannot drift.

Placeholders (HTML comments, invisible if the hook is not run):

- ``<!-- gen:pod-support -->``: the pod models of Appendix 7 with the Appendix 8 commands
  each supports, from :mod:`gcu_async.protocol.pods`.
- ``<!-- gen:cli-help NAME -->``: ``gcu-async NAME --help`` (``NAME`` empty: the top level),
  from the real argparse parser.
"""

from __future__ import annotations

import argparse
import os
import re
from typing import Any

_CLI = re.compile(r"<!-- gen:cli-help ?(?P<name>[a-z-]*) -->")
_PODS = "<!-- gen:pod-support -->"


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
    return _CLI.sub(lambda m: _cli_help(m["name"]), markdown)
