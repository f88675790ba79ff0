"""The ``--report FILE`` option every sub-command that watches a link shares: one flag name,
the conformance report of the *other* side (``sim``: the host's; ``monitor``, ``decode``:
the GCU's), each file rewritten whole (docs/conformance.md)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

HOST_REPORT_HELP = ("write the host conformance report (how the host's packets deviate from "
                    "V2.0.6, text) to FILE")  # fmt: skip
GCU_REPORT_HELP = ("write the GCU conformance report (how the GCU's replies deviate from "
                   "V2.0.6, text) to FILE")  # fmt: skip


def add_report_option(parser: Any, help_text: str) -> None:
    """``--report FILE`` with ``help_text`` (one of the two above, completed by the caller)."""
    parser.add_argument("--report", type=Path, metavar="FILE", help=help_text)


def write_report(path: Path, content: str) -> None:
    """Write ``content`` to ``path`` through a temporary file and a rename, so a reader never
    sees half a report. Raises ``OSError``."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(content, encoding="utf-8")
    os.replace(tmp, path)
