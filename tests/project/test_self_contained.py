"""The repository is self-contained: no tracked file refers to a path outside it, and the
citations of the protocol notes point at sections that exist.

What counts as a reference outside the repository:

- an absolute path under a machine's or user's own directories (``/home``, ``/root``,
  ``/Users``, ``/work``, ``/mnt``, ``/media``, ``/srv``, ``/opt``, ``/tmp``), a home-relative
  path (``~/``, ``$HOME/``) or a Windows user path (``C:\\Users``). System paths a program
  legitimately names (``/dev/ttyUSB0``, ``/proc/cpuinfo``, ``/usr/bin/chromium``) and URL
  paths (``/api/state``) are fine;
- a relative path that climbs out of the repository: in Markdown and HTML relative to the
  file (``../cli.md`` from ``docs/reference`` is fine), everywhere else relative to the
  repository root, where every tool runs (so any ``../`` leads out);
- ``Path(__file__)`` climbing above the root (``parents[k]`` or ``.parent`` chains);
- the protocol's reading notes kept outside the repository (``NOTES §…``, ``NOTES.md``): the
  shipped docs/protocol-notes.md replaces them.

This file names those patterns itself, so it is the one file the scan skips; the detector is
tested on samples instead.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import unicodedata
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

import pytest

ROOT = Path(__file__).resolve().parents[2]
THIS = PurePosixPath(Path(__file__).resolve().relative_to(ROOT).as_posix())
NOTES_PAGE = ROOT / "docs" / "protocol-notes.md"

_PRIVATE_ROOTS = ("home", "root", "Users", "work", "mnt", "media", "srv", "opt", "tmp")
_ABSOLUTE = re.compile(
    r"(?<![\w.~$/:-])/(?:" + "|".join(_PRIVATE_ROOTS) + r")(?=/|\b)(?:/[\w.+-]*)*"
)
_HOME = re.compile(r"(?<![\w/])(?:~|\$HOME|\$\{HOME\}|\$\(HOME\))/[\w.-]+")
_WINDOWS_USER = re.compile(r"\b[A-Za-z]:[\\/]+(?:Users|Documents and Settings)\b", re.IGNORECASE)
_CLIMB = re.compile(r"(?<![\w.])((?:\.\./)+)([\w.-]*)")
_PARENTS = re.compile(r"Path\(__file__\)(?:\.resolve\(\))?\.parents\[(\d+)\]")
_PARENT_CHAIN = re.compile(r"Path\(__file__\)(?:\.resolve\(\))?((?:\.parent)+)\b")
# Places on a user's machine that the project documents as destinations (Wireshark's personal
# Lua plugin folders, where `gcu-async wireshark --install` copies the dissector): named, not
# read from, so they are not references to files outside the repository.
_USER_DESTINATIONS = ("~/.local/lib/wireshark/plugins", "~/.config/wireshark/plugins")
_OUTSIDE_NOTES = re.compile(r"\bNOTES(?:\.md\b| ?§)")
_FILE_RELATIVE = {".md", ".html", ".htm"}


@dataclass(frozen=True)
class Finding:
    path: str
    line: int
    text: str
    why: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.text!r} ({self.why})"


def outside_references(rel_path: str, text: str) -> list[Finding]:
    """Every reference in ``text`` (the file ``rel_path``, relative to the root) to a path
    outside the repository."""
    path = PurePosixPath(rel_path)
    depth = len(path.parts) - 1  # directories between the root and the file
    file_relative = path.suffix.lower() in _FILE_RELATIVE
    found: list[Finding] = []
    for number, line in enumerate(text.splitlines(), start=1):

        def add(match: re.Match[str], why: str, n: int = number) -> None:
            found.append(Finding(rel_path, n, match.group(0), why))

        for m in _ABSOLUTE.finditer(line):
            add(m, "absolute path on a particular machine")
        for m in _HOME.finditer(line):
            if not line.startswith(_USER_DESTINATIONS, m.start()):
                add(m, "path in a home directory")
        for m in _WINDOWS_USER.finditer(line):
            add(m, "Windows user directory")
        for m in _CLIMB.finditer(line):
            ups = m.group(1).count("../")
            if not file_relative or ups > depth:
                add(m, "relative path leading out of the repository")
        for m in _PARENTS.finditer(line):
            if int(m.group(1)) > depth:
                add(m, "Path(__file__).parents above the repository root")
        for m in _PARENT_CHAIN.finditer(line):
            if m.group(1).count(".parent") - 1 > depth:
                add(m, "Path(__file__).parent chain above the repository root")
        for m in _OUTSIDE_NOTES.finditer(line):
            add(m, "reading notes outside the repository: cite docs/protocol-notes.md")
    return found


def tracked_files() -> list[str]:
    git = shutil.which("git")
    if git is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout (or no git): the tracked files are unknown")
    out = subprocess.run(
        [git, "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True, timeout=30
    ).stdout
    return [name for name in out.decode("utf-8").split("\0") if name]


OPTIONAL_PEERS = re.compile(r"^sitl=\.\./shared/tools/ardupilot-sitl/arducopter$")
"""The one reference allowed out of the tree: .ci/run handing CI's optional third-party test
peer (ArduPilot SITL) to the tests through an environment variable."""


def is_optional_test_peer(finding: Finding, text: str) -> bool:
    line = text.splitlines()[finding.line - 1].strip()
    return finding.path == ".ci/run" and bool(OPTIONAL_PEERS.match(line))


def test_only_ci_may_name_the_optional_test_peer() -> None:
    up = ".." + "/shared"  # (spelt in two pieces: no tracked file names it outright)
    text = f"sitl={up}/tools/ardupilot-sitl/arducopter\n"
    (finding,) = outside_references(".ci/run", text)
    assert is_optional_test_peer(finding, text)
    (finding,) = outside_references("Makefile", text)
    assert not is_optional_test_peer(finding, text)
    other = f"cp {up}/spec/x.hex tests/data\n"
    (finding,) = outside_references(".ci/run", other)
    assert not is_optional_test_peer(finding, other)


def test_no_tracked_file_refers_outside_the_repository() -> None:
    files = tracked_files()
    # the scan really covers the tree
    assert "tests/helpers/protocol/vectors.py" in files and len(files) > 50
    findings: list[Finding] = []
    scanned = 0
    for name in files:
        if PurePosixPath(name) == THIS:
            continue
        try:
            text = (ROOT / name).read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue  # binary (images): no paths to follow
        except FileNotFoundError:
            continue  # deleted in the work tree, not yet committed
        scanned += 1
        findings += [f for f in outside_references(name, text)
                     if not is_optional_test_peer(f, text)]  # fmt: skip
    assert scanned > 50
    assert not findings, "\n".join(map(str, findings))


@pytest.mark.parametrize(
    ("path", "text"),
    [
        ("tests/helpers/protocol/vectors.py",
         'SPEC = Path(__file__).resolve().parents[4] / "elsewhere" / "spec"'),
        ("tests/helpers/protocol/vectors.py",
         "SPEC = Path(__file__).parent.parent.parent.parent.parent / 'elsewhere'"),
        ("src/gcu_async/x.py", "open('../elsewhere/spec/gcu-example.hex')"),
        ("Makefile", "\tcp ../elsewhere/spec/*.hex tests/data"),
        ("docs/index.md", "[the spec](../../elsewhere/spec/doc.md)"),
        ("docs/reference/cli.md", "see [notes](../../NOTES.md)"),
        ("README.md", "Clone next to `/work/elsewhere` first."),
        ("README.md", "python at /home/alice/venv/bin/python"),
        ("docs/x.md", "see /root/.pyenv/versions"),
        ("docs/x.md", "`mkdocs build -d /tmp/site`"),
        ("docs/x.md", "data in ~/gcu/spec"),
        ("docs/x.md", "copy it to ~/.local/lib/python3.11/site-packages"),
        ("Makefile", "PY := $(HOME)/.local/bin/python"),
        ("docs/x.md", r"C:\Users\me\gcu"),
        ("src/gcu_async/a.py", "(NOTES §5)"),
        ("src/gcu_async/a.py", "see NOTES.md"),
        ("src/gcu_async/a.py", "/Users/me/spec.md"),
    ],
)
def test_detector_flags_references_outside(path: str, text: str) -> None:
    assert outside_references(path, text), text


@pytest.mark.parametrize(
    ("path", "text"),
    [
        ("docs/transports.md", "`serial:///dev/ttyUSB0?baudrate=115200`"),
        ("benchmarks/_machine.py", 'open("/proc/cpuinfo")'),
        ("tests/examples/test_example_web.py", 'CHROMIUM = "/usr/bin/chromium"'),
        ("examples/web/app.py", "GET /api/state and /static/app.js"),
        ("docs/reference/cli.md", "the [Command line](../cli.md) page"),
        ("tests/docs/test_docs_commands.py", 'Path(__file__).resolve().parents[2] / "README.md"'),
        ("tests/conftest.py", "Path(__file__).parent.parent / 'docs'"),
        ("docs/cli.md", "`udp://192.168.144.108:2337`, `tcp://[::1]:2332`"),
        ("docs/x.md", "the folder src/gcu_async/tmp/ and https://example.org/home/x"),
        ("src/gcu_async/a.py", 'docs/protocol-notes.md §12 "Transports"'),
        ("docs/x.md", "serial://COM3 on Windows; ~ is home"),
        ("docs/wireshark.md", "Wireshark's default, `~/.local/lib/wireshark/plugins`"),
    ],
)
def test_detector_accepts_legitimate_paths(path: str, text: str) -> None:
    assert outside_references(path, text) == []


# -- citations of docs/protocol-notes.md ----------------------------------------------------

_CITATION = re.compile(r'protocol-notes\.md\s+§(\d+)(?:\s+"([^"]+)")?')
_ANCHOR = re.compile(r"protocol-notes\.md#([\w-]+)")


def _slug(title: str) -> str:
    """The anchor Python-Markdown's toc extension gives a heading (its default slugify)."""
    text = unicodedata.normalize("NFKD", title).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def notes_sections() -> dict[int, str]:
    """Numbered sections (``### N. Title``) of docs/protocol-notes.md."""
    text = NOTES_PAGE.read_text(encoding="utf-8")
    return {int(n): t.strip() for n, t in re.findall(r"^### (\d+)\. (.+)$", text, re.M)}


def notes_anchors() -> set[str]:
    text = NOTES_PAGE.read_text(encoding="utf-8")
    return {_slug(t) for t in re.findall(r"^#{1,6} (.+)$", text, re.M)}


SAMPLES = {ROOT / "tests" / "docs" / "test_docs_links.py"}
"""Files whose stale citations are samples, on purpose (the citation checker's own tests)."""


def _citing_files() -> list[Path]:
    files = sorted(
        p
        for top in ("src", "docs", "tests", "examples", "benchmarks")
        for p in (ROOT / top).rglob("*")
        if p.suffix in (".py", ".md") and p.is_file() and p not in SAMPLES
    )
    files.append(ROOT / "README.md")
    return files


def test_notes_sections_are_numbered_in_order() -> None:
    sections = notes_sections()
    assert len(sections) >= 13
    assert list(sections) == list(range(1, len(sections) + 1))


def test_every_citation_of_the_protocol_notes_names_an_existing_section() -> None:
    sections = notes_sections()
    anchors = notes_anchors()
    citations = 0
    bad: list[str] = []
    for path in _citing_files():
        # docstrings and comments wrap: join lines so a citation split across two still reads
        text = re.sub(r"\s*\n\s*(?:#\s*)?", " ", path.read_text(encoding="utf-8"))
        where = path.relative_to(ROOT)
        for m in _CITATION.finditer(text):
            citations += 1
            number, title = int(m.group(1)), m.group(2)
            if number not in sections:
                bad.append(f"{where}: §{number} does not exist")
            elif title is not None and title != sections[number]:
                bad.append(f"{where}: §{number} is {sections[number]!r}, cited as {title!r}")
        for m in _ANCHOR.finditer(text):
            citations += 1
            if m.group(1) not in anchors:
                bad.append(f"{where}: #{m.group(1)} is no heading of protocol-notes.md")
    assert citations >= 30  # the source cites the notes throughout
    assert not bad, "\n".join(bad)


def test_slug_matches_the_docs_own_links() -> None:
    # docs/cli.md links this heading by hand; the slug rule above must agree with it
    assert _slug("Errata in the document's example packets") == (
        "errata-in-the-documents-example-packets"
    )
    assert _slug("12. Transports") == "12-transports"
