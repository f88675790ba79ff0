"""Without pytest-asyncio the plugin's async fixtures skip, and a test module that overrides
or parametrizes one of their fixtures (``gcu_sim_pod``) still collects and skips (a real
pytest run in a subprocess with pytest-asyncio made unimportable)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

TEST_MODULE = textwrap.dedent('''
    import pytest

    @pytest.fixture
    def gcu_sim_transport():
        return "memory"

    @pytest.mark.parametrize("gcu_sim_pod", ["Z-6A", "D-90Pro(TA)"])
    async def test_parametrized(gcu_client):
        raise AssertionError("runs only with pytest-asyncio")

    async def test_plain(gcu_sim):
        raise AssertionError("runs only with pytest-asyncio")

    def test_sync():
        pass
''')

RUNNER = textwrap.dedent('''
    import sys

    class NoPytestAsyncio:  # as if pytest-asyncio were not installed
        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] == "pytest_asyncio":
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None

    sys.meta_path.insert(0, NoPytestAsyncio())
    import pytest
    sys.exit(pytest.main(sys.argv[1:]))
''')


def test_async_fixtures_skip_with_parametrized_overrides(tmp_path: Path) -> None:
    (tmp_path / "test_user.py").write_text(TEST_MODULE)
    result = subprocess.run(
        # --assert=plain: pytest's rewriting importer would find pytest_asyncio first
        [sys.executable, "-c", RUNNER, "-p", "no:asyncio", "-p", "no:anyio", "-p",
         "no:cacheprovider", "--assert=plain", "-rs", "-q", str(tmp_path)],
        capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path,
    )  # fmt: skip
    out = result.stdout + result.stderr
    assert result.returncode == 0, out
    assert "1 passed, 3 skipped" in out, out
    assert "needs pytest-asyncio" in out and "pip install 'gcu-async[pytest]'" in out, out
