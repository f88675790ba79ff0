"""The README's runnable examples run: the quickstart and the pytest-plugin test.

Each code block is taken from README.md (the same text the docs site includes) and run in
a fresh interpreter, as a reader would run it: the quickstart against the built-in simulator
on a loopback ephemeral port, the plugin example under pytest with the installed plugin.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")


def code_block(after: str) -> str:
    """The first ```python block after the marker text ``after``."""
    start = README.index(after)
    match = re.compile(r"```python\n(.*?)```", re.DOTALL).search(README, start)
    assert match is not None, f"no python block after {after!r}"
    return match.group(1)


def test_quickstart_runs(tmp_path: Path) -> None:
    script = tmp_path / "quickstart.py"
    script.write_text(code_block("[start:quickstart]"), encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=30, check=False
    )
    assert done.returncode == 0, done.stderr
    pod, mode, attitude = done.stdout.strip().split(" ", 2)
    assert (pod, mode) == ("D-90Pro(TA)", "EULER_CONTROL")
    assert attitude.startswith("Attitude(roll=")


def test_plugin_example_passes(tmp_path: Path) -> None:
    test_file = tmp_path / "test_readme_plugin.py"
    test_file.write_text(code_block("## pytest plugin"), encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-o",
         "asyncio_mode=auto", str(test_file)],
        capture_output=True, text=True, timeout=60, check=False, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 passed" in done.stdout
