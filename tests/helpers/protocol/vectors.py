"""Facts from the protocol document that the tests check against, kept in ``tests/data``.

- ``host-example.hex`` / ``gcu-example.hex``: the document's example packets (Appendix 1 and
  2) with the errata of docs/protocol-notes.md ("Errata in the document's example packets")
  corrected: whitespace-separated hex, ``#`` starts a comment line.
- ``pod-models.csv``: Appendix 7, pod model code → vendor name.
- ``pod-support.csv``: Appendix 8, one row per command (opcode name), one column per model
  (vendor name, in the document's order), ``yes`` (●) or ``no`` (○).

The tables are transcribed independently of ``gcu_async.protocol.pods``, so comparing the two
catches a typo in either. The data lives inside the repository (located relative to this
file, never to the working directory).
"""

from __future__ import annotations

import csv
from pathlib import Path

DATA_DIR = Path(__file__).resolve().parents[2] / "data"


def load_hex(name: str) -> bytes:
    """Bytes of ``DATA_DIR / name``: whitespace-separated hex; lines starting with ``#`` are
    comments."""
    lines = (DATA_DIR / name).read_text(encoding="ascii").splitlines()
    return bytes.fromhex(" ".join(ln for ln in lines if not ln.lstrip().startswith("#")))


def _rows(name: str) -> list[list[str]]:
    with (DATA_DIR / name).open(encoding="utf-8", newline="") as f:
        return [row for row in csv.reader(f) if row]


def pod_models() -> dict[int, str]:
    """Appendix 7: pod model code → vendor name, in the document's order."""
    header, *rows = _rows("pod-models.csv")
    if header != ["code", "model"]:
        raise ValueError(f"pod-models.csv: header {header!r} is not ['code', 'model']")
    table: dict[int, str] = {}
    for code, model in rows:
        if int(code) in table:
            raise ValueError(f"pod-models.csv: code {code} is listed twice")
        table[int(code)] = model
    return table


def pod_support() -> tuple[list[str], dict[tuple[str, str], bool]]:
    """Appendix 8: (the command names in the document's order, {(model name, command name):
    supported})."""
    header, *rows = _rows("pod-support.csv")
    if header[0] != "command":
        raise ValueError(f"pod-support.csv: first column {header[0]!r} is not 'command'")
    models = header[1:]
    commands: list[str] = []
    table: dict[tuple[str, str], bool] = {}
    for command, *marks in rows:
        if len(marks) != len(models):
            raise ValueError(f"pod-support.csv: row {command} has {len(marks)} cells, "
                             f"expected {len(models)}")  # fmt: skip
        commands.append(command)
        for model, mark in zip(models, marks, strict=True):
            if mark not in ("yes", "no"):
                raise ValueError(f"pod-support.csv: {command}/{model}: {mark!r} is not yes/no")
            table[(model, command)] = mark == "yes"
    return commands, table


HOST_EXAMPLE = load_hex("host-example.hex")
"""Appendix 1, corrected: host → GCU, 72 bytes, null command."""
GCU_EXAMPLE = load_hex("gcu-example.hex")
"""Appendix 2, corrected: GCU → host, 73 bytes, take-photo success."""
