"""The name tables of the Lua dissector are generated from the protocol package
(tools/gen_wireshark_tables.py): they must be up to date, and the check must catch a stale
table."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[2] / "tools" / "gen_wireshark_tables.py"
sys.path.insert(0, str(TOOL.parent))

import gen_wireshark_tables as gen  # noqa: E402


def test_generated_tables_are_up_to_date() -> None:
    done = subprocess.run([sys.executable, str(TOOL), "--check"], capture_output=True,
                          text=True, timeout=60, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr


def test_a_stale_table_is_caught() -> None:
    text = gen.LUA_PATH.read_text(encoding="utf-8")
    assert gen.replace_block(text, gen.render()) == text
    stale = text.replace('[0x29] = "D_90AI"', '[0x29] = "D_91AI"')
    assert stale != text
    assert gen.replace_block(stale, gen.render()) == text
    assert '[0x29] = "D-90AI"' in gen.render() and '[0x81] = "RANGING"' in gen.render()
