"""A type checker catches a misspelt or mistyped ``connect()`` option (``mypy --strict`` on a
user's script, as a new user runs it on their app): the options are typed, per kind."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.subprocess

SCRIPT = '''\
from gcu_async import connect
from gcu_async.session import Session

connect("udp://127.0.0.1", comand_timeout=3.0)
connect("udp://127.0.0.1", command_timeout="3")
connect("udp://127.0.0.1", local_port="2338")
Session(rate_hz="50")
connect("udp://127.0.0.1", command_timeout=3.0, local_port=0, discovery=True, rate_hz=30.0,
        open_timeout=None, max_attempts=None, baudrate=115200)
Session(rate_hz=50, reorder_guard=0.015, name="pod")
'''

@pytest.mark.skipif(importlib.util.find_spec("mypy") is None, reason="needs mypy (lint group)")
def test_mypy_flags_each_bad_option_and_nothing_else(tmp_path: Path) -> None:
    script = tmp_path / "app.py"
    script.write_text(SCRIPT, encoding="utf-8")
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-error-summary", "--cache-dir",
         str(tmp_path / "cache"), str(script)],
        capture_output=True, text=True, cwd=tmp_path, timeout=600,
    )  # fmt: skip
    errors = [line.split(": error: ", 1) for line in result.stdout.splitlines()
              if ": error: " in line]  # fmt: skip
    by_line = {int(where.split(":")[1]): what for where, what in errors}
    assert sorted(by_line) == [4, 5, 6, 7], result.stdout + result.stderr
    assert 'Unexpected keyword argument "comand_timeout"' in by_line[4]
    assert '"command_timeout"' in by_line[5] and '"str"' in by_line[5]
    assert '"local_port"' in by_line[6] and '"str"' in by_line[6]
    assert '"rate_hz"' in by_line[7] and '"str"' in by_line[7]
