"""CI smoke test of examples/harness: run the example project's own tests as a user would.

``pytest examples/harness`` in a fresh interpreter: the example's pyproject.toml is its
pytest configuration (as in a user's project), and the ``gcu_sim`` / ``gcu_client``
fixtures must come from the installed gcu-async's ``pytest11`` entry point — nothing here
loads the plugin explicitly.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HARNESS = ROOT / "examples" / "harness"


def test_harness_example_tests_pass() -> None:
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "pytest", str(HARNESS), "-p", "no:cacheprovider"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=90,
        check=False,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    # the example's own configuration was used, the plugin came from the entry point, and
    # every test ran and passed (a missing plugin or pytest-asyncio shows as errors or skips)
    assert f"rootdir: {HARNESS}" in output, output
    assert re.search(r"^plugins: .*\bgcu-async-", output, re.MULTILINE), output
    summary = [line for line in output.splitlines() if line.strip()][-1]
    match = re.fullmatch(r"=+ (\d+) passed in [\d.]+s(?: \([\d:]+\))? =+", summary.strip())
    assert match is not None, output
    assert int(match.group(1)) >= 6, output
