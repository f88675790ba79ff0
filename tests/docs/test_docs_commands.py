"""The docs' command tables are the command catalogue's, and match the client.

The command table of docs/client.md and the ``send`` table of docs/cli.md are generated from
the catalogue (:mod:`gcu_async.protocol.catalogue`) and committed between ``gen`` comments
(docs/_ext/generated.py; tests/docs/test_docs_generated.py checks they are current). Here the
committed client table is parsed and every row checked against ``GcuClient``: the method
exists and is awaitable, the backticked lower-case names of the parameters column are exactly
the method's parameters, and calling the method sends the command with the opcode of the row.
Every command method of the client must have a row, so the table cannot silently drift.
"""

from __future__ import annotations

import inspect
import re
import sys
from pathlib import Path
from typing import Any, NamedTuple

import pytest

from gcu_async import GcuClient
from gcu_async.protocol import command_code
from gcu_async.protocol.builder import build
from gcu_async.protocol.catalogue import CATALOGUE
from helpers.client import methods as client_methods
from helpers.protocol.catalogue_samples import sample

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import generated  # noqa: E402 - the docs' generator, from its folder

CLIENT_DOC = ROOT / "docs" / "client.md"
CLI_DOC = ROOT / "docs" / "cli.md"
PARAM_NAME = re.compile(r"`([a-z_][a-z0-9_]*)`")


def committed(path: Path, spec: str) -> str:
    """The body of the generated block ``spec`` of ``path``, as committed."""
    (body,) = [b.body for b in generated.blocks(path.read_text(encoding="utf-8"))
               if b.spec == spec]  # fmt: skip
    return body


class Row(NamedTuple):
    method: str
    opcode: int
    params: frozenset[str]


def table_rows(text: str) -> list[Row]:
    """The rows of the command table ``text``."""
    rows = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or not cells[0].startswith("`"):
            continue  # header, separator, markers
        method = cells[0].strip("`")
        params = frozenset(PARAM_NAME.findall(cells[2]))
        rows.append(Row(method, int(cells[1], 16), params))
    return rows


ROWS = table_rows(committed(CLIENT_DOC, "commands"))


def command_methods() -> set[str]:
    return client_methods.command_methods()


def test_table_was_found() -> None:
    assert len(ROWS) >= 30
    assert len({r.method for r in ROWS}) == len(ROWS), "a method is listed twice"


def test_every_command_method_has_a_row() -> None:
    listed = {r.method for r in ROWS}
    assert command_methods() - listed == set(), "command methods missing from the table"
    assert listed - command_methods() == set(), "table rows without a command method"


@pytest.mark.parametrize("row", ROWS, ids=lambda r: r.method)
def test_row_matches_the_client(row: Row) -> None:
    method = getattr(GcuClient, row.method, None)
    assert method is not None, f"GcuClient has no method {row.method}"
    assert inspect.iscoroutinefunction(method), f"{row.method} is not awaitable"
    params = [p for p in inspect.signature(method).parameters.values() if p.name != "self"]
    assert {p.name for p in params} == row.params, f"{row.method}: parameters differ"


@pytest.mark.parametrize("row", ROWS, ids=lambda r: r.method)
async def test_row_sends_its_opcode(row: Row) -> None:
    signature = inspect.signature(getattr(GcuClient, row.method))
    entry = next(e for e in CATALOGUE if e.method == row.method)
    kwargs = {
        p.name: sample(entry.parameter(p.name))
        for p in signature.parameters.values()
        if p.name != "self" and p.default is inspect.Parameter.empty
    }
    assert command_code(build(row.method, **kwargs).command) == row.opcode


def test_parser_rejects_a_drifted_table() -> None:
    """The checks above can fail: a wrong opcode or parameter shows up in the parsed row."""
    text = "| Method | Opcode | Parameters | Notes |\n|---|---|---|---|\n" \
           "| `zoom_to` | 0x26 | `ratio`, `speed` | |"
    (row,) = table_rows(text)
    assert row == Row("zoom_to", 0x26, frozenset({"ratio", "speed"}))
    signature = inspect.signature(GcuClient.zoom_to)
    assert set(signature.parameters) - {"self"} != row.params


# -- the `gcu-async send` table of docs/cli.md ------------------------------------------
class CliRow(NamedTuple):
    command: str
    params: tuple[str, ...]
    method: str


def cli_rows(text: str) -> list[CliRow]:
    rows = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or not cells[0].startswith("`"):
            continue
        params = tuple(PARAM_NAME.findall(cells[1]))
        rows.append(CliRow(cells[0].strip("`"), params, cells[2].strip("`")))
    return rows


class Spy:
    """Records which client method a CLI command calls."""

    def __init__(self) -> None:
        self.called: list[str] = []

    def __getattr__(self, name: str) -> Any:
        def method(*args: Any, **kwargs: Any) -> None:
            self.called.append(name)

        return method


def test_cli_send_table_matches_the_cli() -> None:
    from gcu_async.cli.send_commands import COMMANDS

    rows = cli_rows(committed(CLI_DOC, "send-commands"))
    assert [r.command for r in rows] == list(COMMANDS)
    for row in rows:
        spec = COMMANDS[row.command]
        assert row.params == tuple(p.name for p in spec.params), row.command
        spy = Spy()
        spec.call(spy, [0.5] * len(spec.params))
        assert spy.called == [row.method] == [spec.method], row.command
        assert hasattr(GcuClient, row.method)


def test_generated_table_parses_back() -> None:
    """The parser above reads the generated table: one row per entry, its parameters."""
    rows = table_rows(generated.command_table())
    assert [(r.method, r.opcode) for r in rows] == [(e.method, e.opcode) for e in CATALOGUE]
    for row, entry in zip(rows, CATALOGUE, strict=True):
        assert row.params == {p.name for p in entry.parameters}, entry.method
