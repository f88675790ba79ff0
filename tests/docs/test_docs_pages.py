"""What the user pages say, as a reader meets them.

- The user pages (README.md and the docs pages other than the explanation ones) name no test
  file and tell no issue history: those live in the explanation pages (docs/testing.md,
  docs/session-contract.md, ...), CONTRIBUTING.md and CHANGELOG.md. (The examples' READMEs
  say how each example is tested: that is part of what they show.)
- The pytest plugin's install line is one text: the plugin's page and the harness example.
- Every docs page is on the site's navigation, and the navigation names only pages that exist.
- The package metadata names no placeholder address: the docs and the changelog ship in the
  source distribution, and the README says where they are.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_docs_links import prose_lines  # noqa: E402 - this folder's link reader

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")

EXPLANATION = {"architecture.md", "benchmarks.md", "session-contract.md", "protocol-notes.md",
               "testing.md"}  # fmt: skip
USER_PAGES = [ROOT / "README.md",
              *(p for p in sorted(DOCS.glob("*.md")) if p.name not in EXPLANATION)]
HISTORY = [
    (re.compile(r"\btests/[\w/*.-]*\.py\b|\btest_\w+\.py\b|\btests/\w+/\B"), "a test file"),
    (re.compile(r"\b[Ii]ssues? #?\d+"), "an issue"),
    (re.compile(r"\bon the old code\b|\bused to (?:be|read|exceed)\b|\(before\)"), "history"),
]


def history(path: Path) -> list[str]:
    """Lines of ``path``'s prose (outside code blocks and comments) that name a test file or
    tell history."""
    where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path.name
    found = []
    for number, line in prose_lines(path.read_text(encoding="utf-8")):
        for pattern, what in HISTORY:
            if (m := pattern.search(line)) is not None:
                found.append(f"{where}:{number}: {what}: {m[0]!r}")
    return found


@pytest.mark.parametrize("page", USER_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_user_pages_name_no_test_and_tell_no_history(page: Path) -> None:
    assert history(page) == []


def test_the_history_check_can_fail(tmp_path: Path) -> None:
    sample = tmp_path / "x.md"
    sample.write_text("A `tests/client/test_client_x.py` check; issue 17 on the old code.\n"
                      "<!-- tests/project/test_y.py in a comment -->\n"
                      "```python\nimport tests.test_z  # tests/z/test_z.py in code\n```\n",
                      encoding="utf-8")  # fmt: skip
    assert [line.split(": ", 2)[1] for line in history(sample)] == ["a test file", "an issue",
                                                                   "history"]


# -- the plugin's install line ---------------------------------------------------------------
def install_lines(path: Path) -> set[str]:
    """The ``pip install`` lines of ``path``'s shell blocks that install the ``pytest`` extra."""
    text = path.read_text(encoding="utf-8")
    blocks = re.findall(r"^ *```(?:sh|console|bash)\n(.*?)^ *```", text, re.M | re.S)
    return {line.strip().removeprefix("$ ") for block in blocks for line in block.splitlines()
            if "pip install" in line and "[pytest]" in line}  # fmt: skip


def test_the_plugin_install_line_is_one_text() -> None:
    page = install_lines(DOCS / "pytest-plugin.md")
    harness = install_lines(ROOT / "examples" / "harness" / "README.md")
    how_to = install_lines(DOCS / "test-your-app.md")
    assert len(page) == 1, page
    assert harness == page == how_to


# -- the site's navigation -------------------------------------------------------------------
def nav_pages() -> list[str]:
    text = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    nav = text[text.index("\nnav:"):]
    return re.findall(r"^\s+- (?:[^:\n]+: )?([\w/.-]+\.md)\s*$", nav, re.M)


def test_every_page_is_on_the_navigation() -> None:
    listed = nav_pages()
    assert len(listed) == len(set(listed)), "a page is listed twice"
    pages = {str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md")}
    assert set(listed) == pages


# -- where the docs are ------------------------------------------------------------------------
PLACEHOLDER = re.compile(r"\.(?:invalid|example|test|localhost)\b|//example\.(?:com|org|net)\b")


def test_no_placeholder_address_in_the_metadata() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    urls = project.get("urls", {})
    assert [u for u in urls.values() if PLACEHOLDER.search(u)] == []
    assert PLACEHOLDER.search("https://gcu-async.example.invalid/docs/")  # what it was


def test_the_readme_says_where_the_docs_are() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    pypi = readme.split("<!-- pypi-start", 1)[1].split("<!-- pypi-end -->", 1)[0]
    public = re.sub(r"<!-- checkout-only-start -->.*?<!-- checkout-only-end -->", "", pypi,
                    flags=re.S)  # fmt: skip
    assert "source distribution" in public and "docs/" in public
    assert "make docs" in readme
