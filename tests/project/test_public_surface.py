"""The top-level package's public surface is pinned and documented.

``gcu_async.__all__`` is the list below (a change to it is a change to this test: deliberate),
the package has no star import and leaks no other public name, and every exported name has a
row in docs/reference/top-level.md whose link names the object where it is documented (the
strict docs build checks the link resolves; this test checks it is the same object)."""

from __future__ import annotations

import ast
import importlib
import re
import types
from pathlib import Path

import gcu_async

ROOT = Path(__file__).resolve().parent.parent.parent
INIT = ROOT / "src" / "gcu_async" / "__init__.py"
PAGE = ROOT / "docs" / "reference" / "top-level.md"

PINNED = [
    # the client and what it reports
    "GcuClient", "connect", "ClientState", "TelemetrySample", "LinkHealth", "LinkEvent",
    "LinkEventKind",
    # the exceptions
    "GcuError", "CommandError", "CommandFailed", "CommandLinkLost", "CommandTimeout",
    "FieldRangeError", "LinkLost", "LocalProtocolError", "Outcome", "LikelyCause",
    "ClientStateError",
    "ProtocolErrorReason", "RemoteProtocolError", "UnsupportedCommandError", "WaitTimeout",
    # the values the client takes and returns
    "AircraftState", "Attitude", "CameraMask", "Feedback", "GcuMainFrame", "GcuSubFrame",
    "GeoPosition", "Mode", "NorthEastUp", "Opcode", "PodModel", "pod_name",
    "__version__",
]  # fmt: skip


def test_all_is_pinned() -> None:
    assert sorted(gcu_async.__all__) == sorted(PINNED)
    assert len(set(gcu_async.__all__)) == len(gcu_async.__all__)


def test_no_star_import_and_nothing_else_leaks() -> None:
    tree = ast.parse(INIT.read_text(encoding="utf-8"))
    stars = [n.module for n in ast.walk(tree)
             if isinstance(n, ast.ImportFrom) and any(a.name == "*" for a in n.names)]  # fmt: skip
    assert stars == []
    public = {
        name for name, value in vars(gcu_async).items()
        if not name.startswith("_") and not isinstance(value, types.ModuleType)
    }  # fmt: skip
    assert public == set(gcu_async.__all__) - {"__version__"}


def test_star_import_gives_exactly_all() -> None:
    namespace: dict[str, object] = {}
    exec("from gcu_async import *", namespace)
    assert set(namespace) - {"__builtins__"} == set(gcu_async.__all__)


def _documented() -> dict[str, str]:
    text = PAGE.read_text(encoding="utf-8")
    table = text[text.index("<!-- top-level-exports -->") :]
    rows = re.findall(r"^\| `(\w+)` \| \w+ \| \[`([\w.]+)`\]\[([\w.]+)\] \|$", table, re.M)
    documented = {}
    for name, shown, identifier in rows:
        assert shown == identifier, name
        assert name not in documented, f"{name} has two rows"
        documented[name] = identifier
    return documented


def test_every_export_is_documented_where_it_is_defined() -> None:
    documented = _documented()
    assert set(documented) == set(gcu_async.__all__) - {"__version__"}
    for name, identifier in documented.items():
        module_name, _, attribute = identifier.rpartition(".")
        module = importlib.import_module(module_name)
        assert getattr(module, attribute) is getattr(gcu_async, name), identifier
        assert identifier.rpartition(".")[2] == name


def test_version_is_documented_on_the_page() -> None:
    text = PAGE.read_text(encoding="utf-8")
    assert re.search(r"::: gcu_async\n(\s+.*\n)*?\s+- __version__\n", text)


def test_the_rest_is_importable_from_its_subpackage() -> None:
    """What the top level no longer exports is still where the docs say it is."""
    import gcu_async.protocol as protocol

    for name in protocol.__all__:
        assert getattr(protocol, name) is not None
    assert not hasattr(gcu_async, "HostPacket")  # the protocol core: gcu_async.protocol
    assert protocol.HostPacket is not None
