"""The dissector's tables are generated from the protocol package when it is written: the
packaged ``xfgcu.lua`` holds none of them (only the marker line where they go), the complete
dissector holds each once, every command of the protocol has its row, and the file that
``--print-path`` and ``--install`` write is the complete dissector, written atomically."""

from __future__ import annotations

import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from gcu_async.protocol import COMMAND_TYPES, Opcode
from gcu_async.protocol.fields import WIRE_RANGES
from gcu_async.wireshark import (
    MARKER,
    dissector_path,
    dissector_source,
    install,
    tables,
    template_path,
)

TOOL = Path(__file__).resolve().parents[2] / "tools" / "gen_wireshark_tables.py"
CLI = [sys.executable, "-m", "gcu_async"]
_LOCAL = re.compile(r"^local ([A-Z_]+) = ", re.M)


def generated_names() -> list[str]:
    return _LOCAL.findall(tables.render())


def test_the_packaged_dissector_holds_the_marker_and_no_table() -> None:
    template = template_path().read_text(encoding="utf-8")
    assert template.count(MARKER) == 1
    assert re.search(rf"^{re.escape(MARKER)}$", template, re.M)
    names = generated_names()
    assert {"OPCODE_NAMES", "COMMAND_ROWS", "PARAM_ENUMS", "MODE_NAMES"} <= set(names)
    for name in names:
        assert f"local {name} =" not in template, name
    assert not re.search(r"\[0x[0-9A-Fa-f]+\] = ", template)  # no code -> name table
    for row in tables.rows():  # no command's name or opcode written by hand
        assert not re.search(rf'(?<!= )"{row.command}"', template), row.command


def test_the_complete_dissector_holds_every_table_once() -> None:
    text = dissector_source()
    assert MARKER not in text
    for name in generated_names():
        assert text.count(f"local {name} =") == 1, name
    for row in tables.rows():
        assert f'[0x{row.opcode:02X}] = {{command = "{row.command}"' in text


def test_every_command_has_its_row_in_wire_order() -> None:
    rows = tables.rows()
    assert [r.opcode for r in rows] == sorted(COMMAND_TYPES)
    for row in rows:
        layout = COMMAND_TYPES[row.opcode].LAYOUT
        assert row.command == Opcode(row.opcode).name
        assert "<" + "".join(p.fmt for p in row.params) == layout.format, row.command
        for p in row.params:
            low, high = WIRE_RANGES[p.fmt]
            assert low <= (p.low if p.low is not None else low)
            assert (p.high if p.high is not None else high) <= high


def test_decode_reads_every_row_it_knows() -> None:
    """The generator learns from decode how each parameter reads: a row of a command decode
    knows must get there (a base of valid values), never fall back to the row alone."""
    for row in tables.rows():
        if row.params:
            assert tables._Probe(row).base is not None, row.command


def test_the_tool_writes_the_complete_dissector(tmp_path: Path) -> None:
    target = tmp_path / "sub" / "xfgcu.lua"
    done = subprocess.run([sys.executable, str(TOOL), "--write", str(target)],
                          capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert target.read_text(encoding="utf-8") == dissector_source()


def test_install_writes_the_complete_dissector(tmp_path: Path) -> None:
    target = install(tmp_path / "plugins")
    assert target == tmp_path / "plugins" / "xfgcu.lua"
    assert target.read_text(encoding="utf-8") == dissector_source()
    assert target.stat().st_mode & 0o644 == 0o644


def test_dissector_path_is_content_addressed_and_repaired(tmp_path: Path) -> None:
    path = dissector_path(tmp_path)
    assert path.parent == tmp_path and re.fullmatch(r"xfgcu-[0-9a-f]{16}\.lua", path.name)
    assert path.read_text(encoding="utf-8") == dissector_source()
    assert dissector_path(tmp_path) == path
    path.write_text("-- cut short", encoding="utf-8")  # a file someone damaged
    assert dissector_path(tmp_path) == path
    assert path.read_text(encoding="utf-8") == dissector_source()


def test_concurrent_writers_leave_one_complete_file(tmp_path: Path) -> None:
    """Test workers and shells call --print-path at once: each gets the same complete file,
    and no temporary file is left behind."""
    with ThreadPoolExecutor(8) as pool:
        paths = set(pool.map(lambda _: dissector_path(tmp_path), range(32)))
    procs = [subprocess.Popen([*CLI, "wireshark", "--print-path", "--cache-dir", str(tmp_path)],
                              stdout=subprocess.PIPE, text=True) for _ in range(4)]  # fmt: skip
    for proc in procs:
        out, _ = proc.communicate(timeout=120)
        assert proc.returncode == 0
        paths.add(Path(out.strip()))
    assert len(paths) == 1
    assert [p.name for p in tmp_path.iterdir()] == [paths.pop().name]


def test_an_unwritable_folder_is_an_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(NotADirectoryError):
        dissector_path(blocker / "cache")
    done = subprocess.run([*CLI, "wireshark", "--print-path", "--cache-dir", str(blocker / "c")],
                          capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.startswith("gcu-async wireshark: cannot write the dissector:")
    assert len(done.stderr.strip().splitlines()) == 1
    usage = subprocess.run([*CLI, "wireshark", "--install", "--cache-dir", str(tmp_path)],
                           capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
    assert usage.returncode == 2
    assert "--cache-dir: only with --print-path" in usage.stderr


def test_print_path_defaults_to_the_user_cache(tmp_path: Path) -> None:
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "XDG_CACHE_HOME": "",
           "PYTHONPATH": ":".join(sys.path)}  # fmt: skip
    done = subprocess.run([*CLI, "wireshark", "--print-path"], capture_output=True, text=True,
                          timeout=120, env=env, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    path = Path(done.stdout.strip())
    assert path.parent == tmp_path / ".cache" / "gcu_async"
    assert path.read_text(encoding="utf-8") == dissector_source()
