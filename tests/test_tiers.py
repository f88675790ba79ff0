"""The test tiers (tests/_tiers.py): every test file has a declared kind, no test runs nowhere,
and ``make test``'s phases select every collected test exactly once."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from _tiers import ALONE, DEFAULT, FAST, KINDS, MARKERS, SLOW_KINDS, TIERS, kinds_of

TESTS = Path(__file__).resolve().parent


def test_every_test_file_has_a_tier_and_every_entry_a_file() -> None:
    files = {p.name for p in TESTS.glob("test_*.py")}
    declared = {name for name in files if name in TIERS or _module_marks_a_kind(TESTS / name)}
    assert files - declared == set(), (
        "test files without a tier: add each to TIERS in tests/_tiers.py (or give it a "
        "module-level pytestmark with one of " + ", ".join(KINDS) + ")"
    )
    assert set(TIERS) - files == set(), "TIERS names files that do not exist"


def _module_marks_a_kind(path: Path) -> bool:
    source = path.read_text(encoding="utf-8")
    return any(re.search(rf"^pytestmark\b.*\bmark\.{kind}\b", source, re.MULTILINE)
               for kind in KINDS)  # fmt: skip


def test_entries_name_one_kind_and_alone_only_for_full_tier_files() -> None:
    for name, entry in TIERS.items():
        kinds = kinds_of(entry)
        assert len([k for k in kinds if k in KINDS]) == 1, (name, entry)
        assert set(kinds) <= {*KINDS, ALONE}, (name, entry)
        assert not (FAST in kinds and ALONE in kinds), name
    assert DEFAULT in SLOW_KINDS  # an undeclared test runs in the full tier, not nowhere
    assert set(MARKERS) == {*KINDS, ALONE}


def _collect(tmp_path: Path, *args: str) -> set[str]:
    """Node ids pytest collects in ``tmp_path`` with this conftest and ``args``."""
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist",
         "--collect-only", "-q", "--rootdir", str(tmp_path), "--confcutdir", str(tmp_path),
         "-c", str(tmp_path / "pytest.ini"), *args, str(tmp_path)],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": os.pathsep.join(
            [str(TESTS), os.environ.get("PYTHONPATH", "")])},
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode in (0, 5), proc.stdout + proc.stderr
    return {line.split("::", 1)[1] for line in proc.stdout.splitlines() if "::" in line}


@pytest.fixture
def project(tmp_path: Path) -> Path:
    """A test directory with this suite's conftest, a listed fast file, an unlisted file and
    a fast file with a test of another kind."""
    (tmp_path / "pytest.ini").write_text("[pytest]\naddopts = --strict-markers\n")
    (tmp_path / "conftest.py").write_text((TESTS / "conftest.py").read_text(encoding="utf-8"))
    (tmp_path / "test_protocol_crc.py").write_text(  # a name TIERS lists as fast
        "import pytest\n\ndef test_listed():\n    pass\n\n"
        "@pytest.mark.subprocess\ndef test_own_kind():\n    pass\n"
    )
    (tmp_path / "test_brand_new.py").write_text("def test_unlisted():\n    pass\n")
    return tmp_path


@pytest.mark.subprocess
def test_phases_select_every_test_once_and_an_unlisted_file_runs_in_the_full_tier(
    project: Path,
) -> None:
    assert TIERS["test_protocol_crc.py"] == FAST
    everything = _collect(project)
    fast = _collect(project, "-m", FAST)
    parallel, alone = _collect(project, "-m", f"not {ALONE}"), _collect(project, "-m", ALONE)
    assert everything == {"test_listed", "test_own_kind", "test_unlisted"}
    assert fast == {"test_listed"}  # its own marker takes test_own_kind out of the fast tier
    assert parallel | alone == everything and not parallel & alone  # the full run: each once
    assert _collect(project, "-m", DEFAULT) == {"test_unlisted"}


@pytest.mark.subprocess
def test_two_kinds_on_one_test_is_a_usage_error(project: Path) -> None:
    (project / "test_brand_new.py").write_text(
        "import pytest\n\n@pytest.mark.realtime\n@pytest.mark.netns\ndef test_both():\n"
        "    pass\n"
    )
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist",
         "--collect-only", "-q", "-c", str(project / "pytest.ini"), str(project)],
        cwd=project, env={**os.environ, "PYTHONPATH": str(TESTS)},
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 4, proc.stdout + proc.stderr
    assert "more than one test kind marker: ['netns', 'realtime']" in proc.stdout + proc.stderr
