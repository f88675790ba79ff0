"""Every relative link of the README and the docs resolves in the raw Markdown.

A reader of the repository (on GitHub, in a checkout, in the source distribution) follows
the links as they are written: each relative link of README.md, docs/**/*.md and the
examples' READMEs must point to a file that exists and, with a ``#fragment``, to a heading of
that file under GitHub's slug rule. Links between docs pages must also hit the heading under
the docs site's rule (Python-Markdown's ``toc``), so a fragment works in both places; the
strict docs build checks the site's side too (``validation`` in mkdocs.yml).

Citations of a docs section in prose (``docs/client.md, "Lifecycle"``, or a numbered one,
``docs/protocol-notes.md §4 "The same-opcode rule"``) must name a heading that exists, in the
docs and wherever a reader meets them: the docstrings, comments and messages of ``src/``
(a log message sends a user there), the tests, the examples and CONTRIBUTING.md.
``python tests/docs/test_docs_links.py`` lists the stale citations of the whole repository
(benchmarks and tools included), for whoever moves a section.
"""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md", *sorted(DOCS.rglob("*.md")),
         *sorted(ROOT.glob("examples/*/README.md"))]  # fmt: skip
FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
HEADING = re.compile(r"^ {0,3}(#{1,6})[ \t]+(.+?)[ \t#]*$")
# an inline link or image, not a reference link ([text][id], mkdocs' autorefs)
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]"
                  r"\((?P<target><[^>]*>|[^()\s]*(?:\([^()\s]*\)[^()\s]*)*)"
                  r"(?:\s+\"[^\"]*\")?\)")  # fmt: skip
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1")
COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)


# -- headings and their anchors --------------------------------------------------------------
def heading_text(raw: str) -> str:
    """A heading as rendered text: links to their text, code spans and emphasis unwrapped."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", raw)
    text = re.sub(r"\[([^\]]*)\]\[[^\]]*\]", r"\1", text)
    text = re.sub(r"(`+)(.+?)\1", r"\2", text)
    text = re.sub(r"(\*{1,3}|(?<!\w)_{1,3})(\S(?:.*?\S)?)\1", r"\2", text)
    text = re.sub(r"\s*\{#?[\w .-]*\}$", "", text)  # attr_list
    return text.strip()


def github_slug(text: str) -> str:
    """GitHub's anchor for a heading (github-slugger): lower case, every character dropped
    but letters, digits, marks, ``-``, ``_`` and spaces, then each space a ``-``."""
    kept = "".join(ch for ch in text.lower()
                   if ch in "-_ " or unicodedata.category(ch)[0] in "LNM")  # fmt: skip
    return kept.replace(" ", "-")


def site_slug(text: str) -> str:
    """The docs site's anchor (Python-Markdown's ``toc``, its default ``slugify``)."""
    value = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    value = re.sub(r"[^\w\s-]", "", value).strip().lower()
    return re.sub(r"[-\s]+", "-", value)


def prose_lines(text: str) -> list[tuple[int, str]]:
    """``(line number, line)`` outside fenced code blocks, HTML comments blanked."""
    text = COMMENT.sub(lambda m: "\n" * m[0].count("\n"), text)
    out, fence = [], ""
    for number, line in enumerate(text.splitlines(), 1):
        opening = FENCE.match(line)
        if fence:
            if opening and opening[1][0] == fence[0] and len(opening[1]) >= len(fence) \
                    and not line.strip()[len(opening[1]):].strip():  # fmt: skip
                fence = ""
            continue
        if opening:
            fence = opening[1]
            continue
        out.append((number, line))
    return out


def headings(path: Path) -> list[str]:
    return [heading_text(m[2]) for _, line in prose_lines(path.read_text(encoding="utf-8"))
            if (m := HEADING.match(line))]  # fmt: skip


def anchors(path: Path, slug: type[str] | object = github_slug) -> set[str]:
    """The anchors of a page's headings, repeated ones numbered as GitHub numbers them."""
    seen: dict[str, int] = {}
    out = set()
    for title in headings(path):
        base = slug(title)  # type: ignore[operator]
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


# -- links -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Link:
    page: Path
    line: int
    target: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def links(path: Path) -> list[Link]:
    found = []
    for number, line in prose_lines(path.read_text(encoding="utf-8")):
        line = CODE_SPAN.sub(lambda m: " " * len(m[0]), line)
        for m in LINK.finditer(line):
            found.append(Link(path, number, m["target"].strip("<>")))
    return found


def is_relative(target: str) -> bool:
    return not re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I) and not target.startswith("//")


def problem(link: Link) -> str | None:
    """What is wrong with a relative link, or None."""
    path_part, _, fragment = link.target.partition("#")
    target = (link.page.parent / path_part).resolve() if path_part else link.page
    if not target.exists():
        return f"{link.where}: {link.target}: no such file"
    if not target.is_relative_to(ROOT):
        return f"{link.where}: {link.target}: outside the repository"
    if not fragment:
        return None
    if target.suffix != ".md":
        return f"{link.where}: {link.target}: a fragment of a file that is not Markdown"
    if fragment not in anchors(target):
        return f"{link.where}: {link.target}: no heading of {target.name} has GitHub's anchor " \
               f"#{fragment}"  # fmt: skip
    both_on_site = link.page.is_relative_to(DOCS) and target.is_relative_to(DOCS)
    if both_on_site and fragment not in anchors(target, site_slug):
        return f"{link.where}: {link.target}: the docs site spells that heading's anchor " \
               "otherwise: reword the heading"  # fmt: skip
    return None


LINKS = [link for page in PAGES for link in links(page) if is_relative(link.target)]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(page: Path) -> None:
    found = [p for link in LINKS if link.page == page and (p := problem(link))]
    assert found == []


def test_the_links_were_found() -> None:
    readme = [link for link in LINKS if link.page.name == "README.md" and link.page.parent == ROOT]
    assert len(readme) >= 10 and any("#" in link.target for link in readme)
    assert len(LINKS) >= 150


# -- citations in prose ----------------------------------------------------------------------
CITATION = re.compile(r"docs/(?P<page>[\w/-]+\.md)(?:\s+§(?P<number>\d+))?(?:,\s*|\s+\(?)"
                      r"\"(?P<title>[^\"]+)\"")


def citations(path: Path) -> list[tuple[str, str, str]]:
    """``(where, page, title)`` of each ``docs/PAGE.md, "Heading"`` in ``path`` (of
    ``docs/PAGE.md §N "Heading"``: the title ``N. Heading``)."""
    # a line break, with the comment marker (Python, Lua) or list bullet that follows it
    text = re.sub(r"\s*\n\s*(?:#\s*|--\s*|\*\s*)?", " ", path.read_text(encoding="utf-8"))
    text = text.replace('\\"', '"')
    where = str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else path.name
    return [(where, m["page"], f"{m['number']}. {m['title']}" if m["number"] else m["title"])
            for m in CITATION.finditer(text)]  # fmt: skip


def stale_citations(paths: list[Path]) -> list[str]:
    bad = []
    for path in paths:
        for where, page, title in citations(path):
            target = DOCS / page
            if not target.exists():
                bad.append(f"{where}: docs/{page} does not exist (cited for {title!r})")
                continue
            titles = headings(target)
            # a title may be cut short at a word ("Errata", "Waiting for …"), or name a
            # numbered section without its number (with one, the number must match)
            short = title.removesuffix("…").rstrip()
            numbered = "" if re.match(r"\d+\. ", short) else r"(?:\d+\. )?"
            if not any(re.match(rf"{numbered}{re.escape(short)}(?!\w)", t) for t in titles):
                bad.append(f"{where}: docs/{page} has no heading {title!r}")
    return bad


def test_citations_in_the_docs_name_existing_sections() -> None:
    assert stale_citations(PAGES) == []


CITING = sorted(p for top in ("src", "tests", "examples") for p in (ROOT / top).rglob("*")
                if p.suffix in (".py", ".md", ".lua") and p.resolve() != Path(__file__).resolve()
                and "node_modules" not in p.parts)  # fmt: skip
"""The files outside docs/ whose citations readers follow (this file's samples are stale on
purpose and left out)."""


def test_citations_in_the_code_name_existing_sections() -> None:
    """A moved section leaves no stale citation in a docstring, comment or message."""
    assert len(CITING) >= 300 and any(citations(p) for p in CITING)
    assert stale_citations([*CITING, ROOT / "CONTRIBUTING.md"]) == []


# -- the machinery can fail ------------------------------------------------------------------
def test_slugs_follow_github_and_the_site() -> None:
    assert github_slug("Frames as JSON: as_dict()") == "frames-as-json-as_dict"
    assert github_slug("12. Transports") == site_slug("12. Transports") == "12-transports"
    # where the two rules part, a link cannot work in both places
    assert github_slug("Target distance ≤ 0") == "target-distance--0"
    assert site_slug("Target distance ≤ 0") == "target-distance-0"
    assert github_slug("decode --file") == "decode---file" != site_slug("decode --file")
    assert heading_text("Frames as JSON: `as_dict()`") == "Frames as JSON: as_dict()"
    assert heading_text("The [bridge](x.md) **contract**") == "The bridge contract"


def test_a_broken_link_is_found(tmp_path: Path) -> None:
    page = DOCS / "client.md"
    assert problem(Link(page, 1, "cli.md#exit-status")) is None
    assert "no such file" in str(problem(Link(page, 1, "clients.md")))
    assert "GitHub's anchor #exit" in str(problem(Link(page, 1, "cli.md#exit")))
    assert problem(Link(ROOT / "README.md", 1, "docs/client.md#commands")) is None
    text = "See [a](b.md) and `[c](d.md)` and [e][f]; ![g](h.png \"t\")\n```\n[i](j.md)\n```\n"
    sample = tmp_path / "x.md"
    sample.write_text(text, encoding="utf-8")
    assert [link.target for link in links(sample)] == ["b.md", "h.png"]


def test_repeated_headings_are_numbered(tmp_path: Path) -> None:
    sample = tmp_path / "x.md"
    sample.write_text("# A\n## Rules\n```\n# not a heading\n```\n### Rules\n", encoding="utf-8")
    assert anchors(sample) == {"a", "rules", "rules-1"}


def test_a_stale_citation_is_found(tmp_path: Path) -> None:
    sample = tmp_path / "x.py"
    sample.write_text('"""As docs/client.md, "Lifecycle", and docs/cli.md, "No such\n'
                      '    heading", say; docs/nowhere.md "X"; docs/client.md ("Waiting for …");\n'
                      '    docs/client.md, "Life"; docs/protocol-notes.md §4 "The same-opcode\n'
                      '    rule"; docs/protocol-notes.md §5 "The same-opcode rule"."""\n'
                      'log.info("see docs/client.md, \\"The session contract\\"")\n',
                      encoding="utf-8")  # fmt: skip
    found = [line.split(": ", 1)[1] for line in stale_citations([sample])]
    assert found == ["docs/cli.md has no heading 'No such heading'",
                     "docs/nowhere.md does not exist (cited for 'X')",
                     "docs/client.md has no heading 'Life'",
                     "docs/protocol-notes.md has no heading '5. The same-opcode rule'",
                     "docs/client.md has no heading 'The session contract'"]  # fmt: skip


if __name__ == "__main__":
    everything = sorted(p for top in ("src", "tests", "examples", "benchmarks", "tools", "docs")
                        for p in (ROOT / top).rglob("*") if p.suffix in (".py", ".md"))
    everything += [ROOT / "README.md", ROOT / "CONTRIBUTING.md"]
    everything.remove(Path(__file__).resolve())  # its samples are stale on purpose
    print("\n".join(stale_citations(everything)) or "no stale citation")
