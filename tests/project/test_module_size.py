"""Short modules with one job: no module of src/gcu_async is longer than :data:`LIMIT` lines.

A module that grows past it is split by job (the frame tables and the frame classes generated
from them are two modules, for example), not squeezed: CONTRIBUTING.md, "House rules"."""

from __future__ import annotations

from pathlib import Path

SRC = Path(__file__).resolve().parent.parent.parent / "src" / "gcu_async"

LIMIT = 600
"""The most lines a module may have."""


def lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def too_long(root: Path = SRC) -> dict[str, int]:
    """Each module under ``root`` longer than :data:`LIMIT` lines, with its count."""
    counts = {p.relative_to(root).as_posix(): lines(p) for p in sorted(root.rglob("*.py"))}
    return {rel: n for rel, n in counts.items() if n > LIMIT}


def test_no_module_is_longer_than_the_limit() -> None:
    assert len(list(SRC.rglob("*.py"))) > 80  # the scan reads the package
    found = too_long()
    assert not found, f"modules over {LIMIT} lines (split them by job): {found}"


def test_the_scan_finds_a_long_module(tmp_path: Path) -> None:
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "short.py").write_text("x = 1\n" * LIMIT, encoding="utf-8")
    (tmp_path / "pkg" / "long.py").write_text("x = 1\n" * (LIMIT + 1), encoding="utf-8")
    assert too_long(tmp_path) == {"pkg/long.py": LIMIT + 1}
