"""The test tiers (tests/helpers/tiers.py): every test file has a declared kind, no test runs
nowhere, and ``make test``'s phases select every collected test exactly once."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from helpers.tiers import ALONE, DEFAULT, FAST, HEAVY, KINDS, MARKERS, SLOW_KINDS, TIERS, kinds_of

TESTS = Path(__file__).resolve().parent.parent
LAYERS = ("protocol", "session", "transport", "client", "sim", "cli", "bridge", "capture",
          "wireshark", "examples", "netns", "sitl", "docs", "project")  # fmt: skip
"""The folders of tests/, one per layer of the architecture (CONTRIBUTING.md, "Where a test
goes"); beside them only conftest.py, data/ and the helpers package."""
TOP = {"conftest.py", "data", "helpers"}
"""What tests/ holds besides the layer folders (CONTRIBUTING.md, "Helpers")."""


def _by_name(tests: Path) -> tuple[dict[str, Path], list[str]]:
    """Every test file under ``tests`` by name, and the names used more than once: TIERS (and
    conftest's lookup) key files by name, and pytest imports them by name."""
    paths = sorted(tests.rglob("test_*.py"))
    names = [p.name for p in paths]
    return {p.name: p for p in paths}, sorted({n for n in names if names.count(n) > 1})


def _misplaced(tests: Path) -> list[str]:
    """Test files under ``tests`` that are not directly in a layer's folder."""
    return sorted(p.relative_to(tests).as_posix() for p in tests.rglob("test_*.py")
                  if p.parent.parent != tests or p.parent.name not in LAYERS)  # fmt: skip


def test_each_test_file_name_is_used_once() -> None:
    assert _by_name(TESTS)[1] == [], "test file names used in more than one folder"


def test_the_top_of_tests_holds_only_the_layers_and_the_helpers() -> None:
    top = {p.name for p in TESTS.iterdir() if p.name != "__pycache__" and p.name[0] != "."}
    assert top - set(LAYERS) == TOP, "shared modules go in tests/helpers (CONTRIBUTING.md)"


def test_every_test_file_is_in_its_layer_folder() -> None:
    assert _misplaced(TESTS) == [], "move each into its layer's folder (CONTRIBUTING.md)"
    guide = (TESTS.parent / "CONTRIBUTING.md").read_text(encoding="utf-8")
    rows = [line for line in guide.splitlines() if line.startswith("| `tests/")]
    named = {folder for row in rows for folder in re.findall(r"`tests/(\w+)/`", row)}
    assert named == set(LAYERS), "CONTRIBUTING.md's table of folders"


def test_the_layout_checks_catch_a_repeated_name_and_a_stray_file(tmp_path: Path) -> None:
    for rel in ("protocol/test_a.py", "sim/test_a.py", "test_b.py", "misc/test_c.py",
                "sim/deeper/test_d.py", "sim/test_e.py"):  # fmt: skip
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("")
    assert _by_name(tmp_path)[1] == ["test_a.py"]
    assert _misplaced(tmp_path) == ["misc/test_c.py", "sim/deeper/test_d.py", "test_b.py"]


def test_every_test_file_has_a_tier_and_every_entry_a_file() -> None:
    paths, _ = _by_name(TESTS)
    files = set(paths)
    declared = {name for name in files if name in TIERS or _module_marks_a_kind(paths[name])}
    assert files - declared == set(), (
        "test files without a tier: add each to TIERS in tests/helpers/tiers.py (or give it a "
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
        assert set(kinds) <= {*KINDS, ALONE, HEAVY}, (name, entry)
        assert not (FAST in kinds and ALONE in kinds), name
        assert HEAVY not in kinds or FAST in kinds, name
    assert DEFAULT in SLOW_KINDS  # an undeclared test runs in the full tier, not nowhere
    assert set(MARKERS) == {*KINDS, ALONE, HEAVY}


REPORTER = """
def pytest_collection_finish(session):
    for item in session.items:
        names = sorted({m.name for m in item.iter_markers()})
        print("MARKS", item.name, ",".join(names))
"""


def _markers(project: Path) -> dict[str, set[str]]:
    """Each test's markers after this suite's conftest has assigned the tiers (one pytest
    collection in a fresh interpreter: a conftest is per directory)."""
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist",
         "-p", "reporter", "--collect-only", "-q", "-c", str(project / "pytest.ini"),
         str(project)],
        cwd=project, env={**os.environ, "PYTHONPATH": os.pathsep.join(
            [str(project), str(TESTS), os.environ.get("PYTHONPATH", "")])},
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    lines = [line.split(" ") for line in proc.stdout.splitlines() if line.startswith("MARKS ")]
    return {name: set(marks.split(",")) for _, name, marks in lines}


@pytest.fixture
def project(tmp_path: Path) -> Path:
    """A test directory with this suite's conftest, a listed fast file, an unlisted file and
    a fast file with a test of another kind."""
    (tmp_path / "pytest.ini").write_text("[pytest]\naddopts = --strict-markers\n")
    (tmp_path / "reporter.py").write_text(REPORTER)
    (tmp_path / "conftest.py").write_text((TESTS / "conftest.py").read_text(encoding="utf-8"))
    (tmp_path / "test_protocol_crc.py").write_text(  # a name TIERS lists as fast
        "import pytest\n\ndef test_listed():\n    pass\n\n"
        "@pytest.mark.subprocess\ndef test_own_kind():\n    pass\n\n"
        "@pytest.mark.realtime\n@pytest.mark.alone\ndef test_alone():\n    pass\n\n"
        "@pytest.mark.heavy\ndef test_heavy():\n    pass\n"
    )
    (tmp_path / "test_brand_new.py").write_text("def test_unlisted():\n    pass\n")
    return tmp_path


@pytest.mark.subprocess
def test_each_test_gets_one_kind_and_an_unlisted_file_the_full_tier(project: Path) -> None:
    assert TIERS["test_protocol_crc.py"] == FAST
    marks = _markers(project)
    assert marks == {
        "test_listed": {FAST},
        "test_own_kind": {"subprocess"},  # its own marker takes it out of the fast tier
        "test_alone": {"realtime", ALONE},
        "test_heavy": {FAST, HEAVY},
        "test_unlisted": {DEFAULT},  # not in TIERS: still runs, in the full tier
    }
    # each test has one kind, so make test's main run ("(not fast or heavy) and not alone",
    # "fast and not heavy", "alone") selects every test exactly once
    assert all(len(m & set(KINDS)) == 1 for m in marks.values())


@pytest.mark.subprocess
def test_two_kinds_on_one_test_is_a_usage_error(project: Path) -> None:
    (project / "test_brand_new.py").write_text(
        "import pytest\n\n@pytest.mark.realtime\n@pytest.mark.netns\ndef test_both():\n"
        "    pass\n"
    )
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist",
         "--collect-only", "-q", "-c", str(project / "pytest.ini"), str(project)],
        cwd=project, env={**os.environ, "PYTHONPATH": os.pathsep.join(
            [str(TESTS), os.environ.get("PYTHONPATH", "")])},
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 4, proc.stdout + proc.stderr
    assert "more than one test kind marker: ['netns', 'realtime']" in proc.stdout + proc.stderr
