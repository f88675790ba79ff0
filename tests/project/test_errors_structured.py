"""Structured errors: a remote protocol error carries its reason as data,
nobody tells errors apart by their message, errors.py imports nothing of the package, and the
transports convert OS errors into LinkLost in one place."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from gcu_async.errors import LinkLost, ProtocolErrorReason
from gcu_async.sim import ManualClock, SimulatorModel
from gcu_async.transport._common import link_lost

SRC = Path(__file__).resolve().parents[2] / "src" / "gcu_async"


def _imports(tree: ast.AST) -> list[str]:
    names: list[str] = []
    for node in ast.walk(tree):  # function-level imports included
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names.append("." * node.level + (node.module or ""))
    return names


def test_errors_module_imports_nothing_of_the_package() -> None:
    imported = _imports(ast.parse((SRC / "errors.py").read_text()))
    assert not [n for n in imported if n.startswith(("gcu_async", "."))], imported


def _is_str_of_a_name(node: ast.AST) -> bool:
    return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
            and node.func.id == "str" and len(node.args) == 1
            and isinstance(node.args[0], ast.Name))  # fmt: skip


def test_no_module_tells_errors_apart_by_their_message() -> None:
    """No ``"..." in str(exc)`` anywhere in src/: the reason is data."""
    offenders = []
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Compare)
                    and any(isinstance(op, (ast.In, ast.NotIn)) for op in node.ops)
                    and any(_is_str_of_a_name(c) for c in node.comparators)):  # fmt: skip
                offenders.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not offenders


def test_the_simulator_counts_envelope_errors_by_reason() -> None:
    """``handle_bytes`` sorts what it cannot decode by ``exc.reason``."""
    from helpers.sim.support import host_bytes

    model = SimulatorModel(clock=ManualClock())
    good = host_bytes()
    bad_crc = bytearray(good)
    bad_crc[-1] ^= 1
    bad_length = bytearray(good)
    bad_length[2] += 1
    assert model.handle_bytes(bytes(bad_crc)) is None
    assert model.handle_bytes(bytes(bad_length)) is None
    assert model.handle_bytes(good[:40]) is None
    assert model.handle_bytes(b"\x00\x00" + good[2:]) is None
    stats = model.stats
    assert (stats.crc_errors, stats.length_errors, stats.malformed) == (1, 1, 2)
    assert model.handle_bytes(good) is not None
    assert [r.value for r in ProtocolErrorReason] == ["short", "header", "length", "crc"]


def test_transports_convert_os_errors_in_one_place() -> None:
    """Every ``except OSError`` / timeout handler in transport/ that raises LinkLost does so
    through :func:`link_lost`."""
    offenders = []
    for path in (SRC / "transport").glob("*.py"):
        tree = ast.parse(path.read_text())
        for handler in ast.walk(tree):
            if not isinstance(handler, ast.ExceptHandler) or handler.type is None:
                continue
            caught = ast.unparse(handler.type)
            if "OSError" not in caught and "TimeoutError" not in caught:
                continue
            for node in ast.walk(handler):
                if (isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call)
                        and ast.unparse(node.exc.func) == "LinkLost"):  # fmt: skip
                    offenders.append(f"{path.name}:{node.lineno}")
    assert not offenders


@pytest.mark.parametrize(("exc", "text"), [
    (OSError(111, "Connection refused"),
     "udp://h:1: cannot connect: [Errno 111] Connection refused"),
    (TimeoutError(), "udp://h:1: cannot connect"),
])  # fmt: skip
def test_link_lost_words_the_conversion(exc: BaseException, text: str) -> None:
    err = link_lost("udp://h:1", "cannot connect", exc)
    assert isinstance(err, LinkLost) and isinstance(err, ConnectionError)
    assert str(err) == text
