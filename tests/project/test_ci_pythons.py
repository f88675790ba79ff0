"""``make test``'s interpreter matrix (.ci/pythons.py): which CPythons it finds, what it
reports as missing, and that a run's size and result reach the summary and the exit status."""

from __future__ import annotations

import importlib.util
import os
import re
import stat
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / ".ci" / "pythons.py"


def load() -> ModuleType:
    spec = importlib.util.spec_from_file_location("ci_pythons", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve annotations through sys.modules
    spec.loader.exec_module(module)
    return module


def fake_python(path: Path, reports: str | None) -> Path:
    """An executable that answers the version probe like CPython ``reports`` (or fails,
    like a pyenv shim for a version that is not installed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    body = f"echo {reports}" if reports else "echo 'pyenv: version not installed' >&2; exit 127"
    path.write_text(f"#!/bin/sh\n{body}\n", encoding="ascii")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


@pytest.mark.skipif(sys.platform == "win32", reason="make test runs on POSIX shells")
def test_finds_the_newest_working_patch_release(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ci = load()
    root = tmp_path / "pyenv"
    fake_python(root / "versions" / "3.12.1" / "bin" / "python3.12", "3.12.1")
    newest = fake_python(root / "versions" / "3.12.10" / "bin" / "python3.12", "3.12.10")
    fake_python(root / "versions" / "3.12.9" / "bin" / "python3.12", "3.12.9")
    fake_python(root / "versions" / "3.13.0" / "bin" / "python3.13", None)  # broken
    fake_python(root / "versions" / "3.130.1" / "bin" / "python3.130", "3.130.1")
    bindir = tmp_path / "bin"
    on_path = fake_python(bindir / "python3.13", "3.13.2")
    fake_python(bindir / "python3.11", "3.10.4")  # misnamed: reports another version
    monkeypatch.setenv("PATH", str(bindir))
    assert ci.find_python("3.12", [root]) == newest  # 10 > 9 > 1, numerically
    assert ci.find_python("3.13", [root]) == on_path  # the pyenv one does not run
    assert ci.find_python("3.11", [root]) is None
    assert ci.find_python("3.10", [root]) is None
    monkeypatch.setenv("PYENV_ROOT", str(root))
    assert root in ci.pyenv_roots()


def _run(tmp_path: Path, test_body: str, versions: str) -> subprocess.CompletedProcess[str]:
    test_file = tmp_path / "test_probe.py"
    test_file.write_text(test_body, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_", "GCU_TEST"))}
    env["PATH"] = str(tmp_path / "empty-bin")  # no python3.X to be found here
    env["PYENV_ROOT"] = str(tmp_path / "no-pyenv")
    env["HOME"] = str(tmp_path)
    main_venv = Path(sys.prefix)
    return subprocess.run(
        [sys.executable, str(SCRIPT), "--main-venv", str(main_venv), "--versions", versions,
         "--jobs", "1", "--", "-q", "-p", "no:cacheprovider", str(test_file)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip


def test_reports_what_ran_at_which_size_and_what_was_missing(tmp_path: Path) -> None:
    if sys.prefix == sys.base_prefix:
        pytest.skip("the suite is not running in a venv: no main venv to hand the script")
    mine = f"{sys.version_info[0]}.{sys.version_info[1]}"
    proc = _run(
        tmp_path,
        "import os\n\ndef test_size():\n    assert os.environ['GCU_TEST_SIZE'] == 'full'\n",
        f"{mine} 3.98 3.99",
    )
    out = proc.stdout
    assert proc.returncode == 0, out + proc.stderr
    venv = Path(sys.prefix).name
    for phase in ("full tier", "fast tier", "alone"):
        assert f"=== Python {mine} ({venv}, full size): {phase} ===" in out, out
    assert "1 passed" in out, out  # the probe has no kind marker: the full tier runs it
    assert "1 deselected" in out, out  # the others had nothing: exit 5 is not a failure
    assert re.search(r"full size, every tier: passed \(full tier \dm\d\ds, fast tier \dm\d\ds, "
                     r"alone \dm\d\ds\)", out), out  # fmt: skip
    assert f"ran: {mine}; missing: 3.98, 3.99" in out, out
    assert "3.99   missing: no CPython 3.99 in " in out, out


def test_a_failing_run_fails_the_whole(tmp_path: Path) -> None:
    if sys.prefix == sys.base_prefix:
        pytest.skip("the suite is not running in a venv: no main venv to hand the script")
    proc = _run(tmp_path, "def test_fails():\n    assert False\n", "")
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "full size, every tier: FAILED (full tier: pytest exit 1)" in proc.stdout, proc.stdout
    assert "missing: none" in proc.stdout, proc.stdout


def test_bad_versions_are_a_usage_error(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--main-venv", sys.prefix, "--versions", "3.x"],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 2
    assert "--versions: '3.x' is not a list like '3.10 3.11'" in proc.stderr


def test_the_main_run_is_everything_once_and_the_others_the_fast_tier() -> None:
    ci = load()
    main = ci.Run("3.11", tier="every", size="full")
    other = ci.Run("3.12", tier="fast", size="reduced")
    serial = ["-p", "no:xdist"]

    def shown(run: object, jobs: int) -> list[tuple[str, list[str], str]]:
        return [(p.name, p.args, p.lane) for p in ci.phases(run, jobs)]

    assert shown(main, 4) == [
        ("full tier", ["-n", "4", "-m", "(not fast or heavy) and not alone"], "background"),
        ("fast tier", [*serial, "-m", "fast and not heavy"], "foreground"),
        ("alone", [*serial, "-m", "alone"], "last"),
    ]  # each test once: heavy ones are fast, never alone
    assert shown(other, 4) == [("fast tier", [*serial, "-m", "fast"], "foreground")]
    assert shown(main, 1)[0][1] == [*serial, "-m", "(not fast or heavy) and not alone"]


def test_jobs_below_one_is_a_usage_error() -> None:
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--main-venv", sys.prefix, "--jobs", "0"],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 2
    assert "--jobs: 0 is not a number of workers >= 1" in proc.stderr
