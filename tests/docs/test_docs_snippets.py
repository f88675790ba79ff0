"""Every code block of README.md and docs/**/*.md runs, or says why not.

A fenced block's kind comes from its language and an optional marker, an HTML comment on
the line(s) right above the fence (invisible on the site):

- ```` ```python ```` without a marker: a complete program, run in a fresh interpreter.
- ``<!-- snippet: fragment -->``: a fragment; it runs as the body of an ``async def``
  whose arguments ``gcu`` (a client connected over loopback UDP) and ``sim`` (the built-in
  simulator behind it, pod D-90Pro(TA)) are all it is given — no imports.
- ``<!-- snippet: pytest -->``: test functions, run by pytest with the installed plugin.
- ``<!-- snippet: not-run (reason) -->``: needs hardware or a real network; it must still
  compile (top-level ``await`` allowed), and is counted.
- ```` ```console ```` / ```` ```sh ```` blocks: every ``gcu-async`` command in them is
  parsed by the real parser (and a ``send`` command by its command's parser); a block with
  any other command must be marked ``not-run (reason)``.
- Other languages (``text``, ``toml``, none): output and data, not run.

A block that has no marker and does not run fails its test. The inventory is printed.
"""

from __future__ import annotations

import ast
import re
import shlex
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FILES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
FENCE = re.compile(r"^(?P<indent> *)(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`\s]*)[^`]*$")
COMMENT = re.compile(r"^\s*<!--.*-->\s*$")
MARKER = re.compile(r"<!--\s*snippet:\s*(?P<kind>[a-z-]+)\s*(?:\((?P<reason>[^)]*)\))?\s*-->")
PYTHON = {"python", "py", "pycon"}
SHELL = {"console", "sh", "bash", "shell"}
KINDS = {"python": {None, "fragment", "pytest", "not-run"}, "shell": {None, "not-run"}}
TIMEOUT = 90.0
TEST_DEF = re.compile(r"^(?:async )?def test_", re.MULTILINE)


@dataclass(frozen=True)
class Block:
    path: Path
    line: int
    """1-based line of the opening fence."""
    lang: str
    text: str
    kind: str | None
    """The marker's kind (``None``: no marker)."""
    reason: str | None

    @property
    def family(self) -> str:
        return "python" if self.lang in PYTHON else "shell" if self.lang in SHELL else "other"

    @property
    def where(self) -> str:
        return f"{self.path.relative_to(ROOT) if self.path.is_relative_to(ROOT) else self.path}" \
               f":{self.line}"  # fmt: skip


def blocks_in(path: Path, text: str) -> list[Block]:
    """The fenced code blocks of a Markdown text, with the marker above each."""
    lines = text.splitlines()
    found: list[Block] = []
    i = 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        indent, fence = len(opening["indent"]), opening["fence"]
        end = i + 1
        while end < len(lines) and not re.match(
            rf"^ {{{indent}}}{re.escape(fence[0])}{{{len(fence)},}}\s*$", lines[end]
        ):
            end += 1
        body = "\n".join(line[indent:] for line in lines[i + 1 : end]) + "\n"
        markers = []
        above = i - 1
        while above >= 0 and COMMENT.match(lines[above]):
            markers += [m for m in MARKER.finditer(lines[above])]
            above -= 1
        if len(markers) > 1:
            raise AssertionError(f"{path}:{i + 1}: more than one snippet marker")
        kind = markers[0]["kind"] if markers else None
        reason = markers[0]["reason"] if markers else None
        found.append(Block(path, i + 1, opening["info"].lower(), body, kind, reason))
        i = end + 1
    return found


BLOCKS = [b for path in FILES for b in blocks_in(path, path.read_text(encoding="utf-8"))]
RUN = [b for b in BLOCKS if b.family == "python" and b.kind != "not-run"]
NOT_RUN = [b for b in BLOCKS if b.kind == "not-run"]
SHELL_BLOCKS = [b for b in BLOCKS if b.family == "shell"]


# -- running a python block -------------------------------------------------------------------
HARNESS = '''\
import asyncio as _asyncio

from gcu_async import connect as _connect
from gcu_async.sim import GcuSimulator as _GcuSimulator


async def _fragment(gcu, sim):
{body}

async def _main():
    sim = _GcuSimulator(pod="D-90Pro(TA)")
    async with sim.serve_udp("127.0.0.1", 0) as server, \\
            _connect(server.url, local_port=0) as gcu:
        await _fragment(gcu, sim)


_asyncio.run(_main())
'''


def program(block: Block) -> str:
    """The Python source that runs ``block`` (a program or a fragment in the harness)."""
    if block.kind == "fragment":
        return HARNESS.format(body=textwrap.indent(block.text, "    "))
    return block.text


def run_block(block: Block, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    """Run a python block as the docs' reader would, in a fresh interpreter in an empty
    directory; pytest blocks under pytest (with ``asyncio_mode=auto``, docs/pytest-plugin.md)."""
    script = tmp_path / ("test_snippet.py" if block.kind == "pytest" else "snippet.py")
    script.write_text(program(block), encoding="utf-8")
    if block.kind == "pytest":
        argv = ["-m", "pytest", "-q", "-p", "no:cacheprovider", "-o", "asyncio_mode=auto",
                str(script)]  # fmt: skip
    else:
        argv = [str(script)]
    return subprocess.run([sys.executable, *argv], capture_output=True, text=True,
                          timeout=TIMEOUT, cwd=tmp_path, check=False)  # fmt: skip


@pytest.mark.parametrize("block", RUN, ids=lambda b: b.where)
def test_python_block_runs(block: Block, tmp_path: Path) -> None:
    done = run_block(block, tmp_path)
    assert done.returncode == 0, f"{block.where} ({block.kind or 'program'}) failed:\n" \
                                 f"{done.stdout}\n{done.stderr}"  # fmt: skip
    if block.kind == "pytest":
        tests = len(TEST_DEF.findall(block.text))
        passed = re.search(r"(\d+) passed", done.stdout)
        assert tests and passed and int(passed[1]) >= tests, done.stdout
        assert not re.search(r"\d+ (failed|skipped|error)", done.stdout), done.stdout


@pytest.mark.parametrize("block", [b for b in NOT_RUN if b.family == "python"],
                         ids=lambda b: b.where)  # fmt: skip
def test_not_run_python_block_compiles(block: Block) -> None:
    compile(block.text, block.where, "exec", flags=ast.PyCF_ALLOW_TOP_LEVEL_AWAIT)


# -- shell blocks ---------------------------------------------------------------------------
def commands(block: Block) -> list[list[str]]:
    """The commands of a shell block: ``$ ``-prefixed lines of a console block (the rest is
    output), every line of a sh block; continuation lines joined, comments dropped, split at
    ``;``, ``&&``, ``||``, ``&`` and ``$( )``. A command reading a pipe (``| head -3``,
    ``| jq ...``) only shapes the output and is left out."""
    lines = block.text.splitlines()
    if block.lang == "console":
        lines = [line[2:] for line in _joined(lines) if line.startswith("$ ")]
    else:
        lines = _joined(lines)
    out = []
    for line in lines:
        lexer = shlex.shlex(line, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        lexer.commenters = "#"
        argv: list[str] = []
        piped = False
        for token in [*lexer, ";"]:
            if token in SEPARATORS:
                if argv and not piped:
                    out.append([a.removesuffix("$") for a in argv])
                argv, piped = [], token == "|"
            else:
                argv.append(token)
    return out


SEPARATORS = {"|", "||", "&&", ";", "&", "(", ")", "$("}


def _joined(lines: list[str]) -> list[str]:
    out: list[str] = []
    for line in lines:
        if out and out[-1].endswith("\\"):
            out[-1] = out[-1][:-1] + " " + line.strip()
        else:
            out.append(line)
    return out


def is_gcu_async(argv: list[str]) -> bool:
    return Path(argv[0]).name == "gcu-async"


def parse_command_line(argv: list[str]) -> None:
    """Parse ``gcu-async ARGS`` as the console script would, opening nothing; a usage error
    raises ``AssertionError`` with argparse's message."""
    from gcu_async.cli import build_parser
    from gcu_async.cli.send import resolve

    try:
        args = build_parser().parse_args(argv[1:])
        if args.command == "send":
            resolve(args)
    except SystemExit as exc:  # argparse: 0 after --help, 2 for a usage error
        if exc.code != 0:
            raise AssertionError(f"{shlex.join(argv)}: usage error (status {exc.code})") from None
    except ValueError as exc:
        raise AssertionError(f"{shlex.join(argv)}: {exc}") from None


@pytest.mark.parametrize("block", [b for b in SHELL_BLOCKS if any(map(is_gcu_async,
                                                                      commands(b)))],
                         ids=lambda b: b.where)  # fmt: skip
def test_gcu_async_commands_parse(block: Block, capsys: pytest.CaptureFixture[str]) -> None:
    for argv in commands(block):
        if is_gcu_async(argv):
            try:
                parse_command_line(argv)
            except AssertionError as exc:
                raise AssertionError(f"{block.where}: {exc}\n{capsys.readouterr().err}") from None


# -- the inventory --------------------------------------------------------------------------
def problems(blocks: list[Block]) -> list[str]:
    """Blocks that neither run nor carry a valid marker saying why."""
    found = []
    for b in blocks:
        allowed = KINDS.get(b.family, {None})
        if b.kind not in allowed:
            found.append(f"{b.where}: marker {b.kind!r} on a {b.lang or 'plain'} block "
                         f"(allowed: {sorted(k for k in allowed if k)})")  # fmt: skip
        elif b.kind == "not-run" and not (b.reason or "").strip():
            found.append(f"{b.where}: not-run without a reason")
        elif b.family == "python" and b.kind is None and TEST_DEF.search(b.text):
            found.append(f"{b.where}: defines tests, which a plain run never calls: mark it "
                         "<!-- snippet: pytest -->")  # fmt: skip
        elif b.family == "shell" and b.kind is None:
            others = [shlex.join(a) for a in commands(b) if not is_gcu_async(a)]
            if others:
                found.append(f"{b.where}: runs {others[0]!r}, which is not checked: mark it "
                             "<!-- snippet: not-run (reason) -->")  # fmt: skip
            elif not commands(b):
                found.append(f"{b.where}: a shell block without a command")
    return found


def test_every_block_runs_or_says_why_not(capsys: pytest.CaptureFixture[str]) -> None:
    assert problems(BLOCKS) == []
    kinds = {k: sum(1 for b in RUN if b.kind == k) for k in (None, "fragment", "pytest")}
    parsed = [a for b in SHELL_BLOCKS for a in commands(b) if is_gcu_async(a)]
    lines = [
        f"docs snippets: {len(BLOCKS)} code blocks in {len(FILES)} files",
        f"  python run:      {len(RUN)} ({kinds[None]} programs, {kinds['fragment']} "
        f"fragments against the simulator, {kinds['pytest']} under pytest)",
        f"  shell parsed:    {sum(1 for b in SHELL_BLOCKS if b.kind is None)} blocks of "
        f"gcu-async commands only; {len(parsed)} gcu-async commands in all parsed by the real "
        "parser",
        f"  marked not-run:  {len(NOT_RUN)} (the python ones compile; gcu-async commands in "
        "them parse)",
        *(f"    {b.where}: {b.reason}" for b in NOT_RUN),
        f"  output and data: {sum(1 for b in BLOCKS if b.family == 'other')} blocks "
        "(text, toml, ...), not code",
    ]
    with capsys.disabled():
        print("\n" + "\n".join(lines))
    # the collector sees the docs as they are (it would pass vacuously on nothing)
    assert len(RUN) >= 15 and len(parsed) >= 10


# -- the machinery can fail -------------------------------------------------------------------
FRAGMENT = """\
await gcu.zoom_to(2.0)
assert sim.model.executions[0x25] == 1
"""


def sample(text: str) -> list[Block]:
    return blocks_in(Path("sample.md"), text)


def test_markers_and_fences_are_read() -> None:
    text = ("intro\n\n<!-- --8<-- [start:x] -->\n<!-- snippet: not-run (a GCU at 10.0.0.1) -->\n"
            "```python\nawait x()\n```\n\n<!-- snippet: fragment -->\n\n```py\npass\n```\n"
            "    ```sh\n    gcu-async sim --listen pty\n    ```\n")  # fmt: skip
    first, second, third = sample(text)
    assert (first.line, first.lang, first.kind, first.reason) == (5, "python", "not-run",
                                                                  "a GCU at 10.0.0.1")
    assert first.text == "await x()\n"
    assert second.kind is None  # a blank line separates the marker from the fence
    assert (third.family, third.text, commands(third)) == (
        "shell", "gcu-async sim --listen pty\n", [["gcu-async", "sim", "--listen", "pty"]])


def test_an_unmarked_fragment_fails(tmp_path: Path) -> None:
    (block,) = sample(f"```python\n{FRAGMENT}```\n")
    done = run_block(block, tmp_path)
    assert done.returncode != 0 and "SyntaxError" in done.stderr  # top-level await
    (block,) = sample("```python\ngcu.release_control()\n```\n")
    done = run_block(block, tmp_path)
    assert done.returncode != 0 and "NameError: name 'gcu' is not defined" in done.stderr


def test_a_marked_fragment_runs_against_the_simulator(tmp_path: Path) -> None:
    (block,) = sample(f"<!-- snippet: fragment -->\n```python\n{FRAGMENT}```\n")
    done = run_block(block, tmp_path)
    assert done.returncode == 0, done.stderr
    (block,) = sample("<!-- snippet: fragment -->\n```python\nassert sim.model.executions[0x25]"
                      "\n```\n")  # fmt: skip
    assert run_block(block, tmp_path).returncode != 0  # the assertion is checked


def test_the_harness_gives_a_fragment_nothing_but_gcu_and_sim(tmp_path: Path) -> None:
    (block,) = sample("<!-- snippet: fragment -->\n```python\nawait asyncio.sleep(0)\n```\n")
    done = run_block(block, tmp_path)
    assert done.returncode != 0 and "NameError: name 'asyncio' is not defined" in done.stderr


def test_a_failing_pytest_block_fails(tmp_path: Path) -> None:
    (block,) = sample("<!-- snippet: pytest -->\n```python\ndef test_no() -> None:\n"
                      "    assert False\n```\n")  # fmt: skip
    done = run_block(block, tmp_path)
    assert done.returncode != 0 and "1 failed" in done.stdout


def test_unmarked_and_misused_blocks_are_problems() -> None:
    blocks = sample(
        "```sh\nmake test\n```\n"
        "<!-- snippet: not-run () -->\n```sh\nmake test\n```\n"
        "<!-- snippet: fragment -->\n```sh\ngcu-async sim\n```\n"
        "<!-- snippet: pytest -->\n```text\nout\n```\n"
        "<!-- snippet: not-run (installs packages) -->\n```sh\npip install x\n```\n"
        "```console\n$ gcu-async monitor udp://127.0.0.1:2337 --count 1\nout\n```\n"
        "```python\nasync def test_x() -> None:\n    pass\n```\n"
    )  # fmt: skip
    found = problems(blocks)
    assert len(found) == 5, found
    assert "runs 'make test', which is not checked" in found[0]
    assert "not-run without a reason" in found[1]
    assert "marker 'fragment' on a sh block" in found[2]
    assert "marker 'pytest' on a text block" in found[3]
    assert "defines tests, which a plain run never calls" in found[4]


def test_shell_lines_are_split_into_commands() -> None:
    (block,) = sample(
        "```console\n$ gcu-async decode --file x.pcapng | jq -c '[.a // .b]' | head -3\n[1]\n"
        "$ tshark -X lua_script:$(gcu-async wireshark --print-path) -r c.pcapng  # one run\n"
        "$ gcu-async sim && kill -HUP $!\n```\n"
    )
    assert commands(block) == [
        ["gcu-async", "decode", "--file", "x.pcapng"],
        ["tshark", "-X", "lua_script:"], ["gcu-async", "wireshark", "--print-path"],
        ["-r", "c.pcapng"], ["gcu-async", "sim"], ["kill", "-HUP", "$!"],
    ]


def test_a_bad_command_line_is_caught() -> None:
    (block,) = sample("```console\n$ gcu-async send udp://127.0.0.1:2337 zoom-to\n```\n")
    with pytest.raises(AssertionError, match="usage error"):
        parse_command_line(commands(block)[0])
    with pytest.raises(AssertionError, match="unknown command 'zoom'"):
        parse_command_line(["gcu-async", "send", "udp://127.0.0.1:2337", "zoom", "4"])
    with pytest.raises(AssertionError, match="usage error"):
        parse_command_line(["gcu-async", "monitor", "udp://x", "--count", "many"])
    parse_command_line(["gcu-async", "send", "udp://127.0.0.1:2337", "zoom-to", "4",
                        "--cameras", "1,2"])  # fmt: skip


# -- signatures as the API reference shows them -----------------------------------------------
def test_no_public_signature_defaults_to_a_private_name() -> None:
    """The API reference prints each default as written in the source: a private sentinel
    shows up as ``= _UNSET``. Defaults must read as what they mean (``KEEP``, ``None``…)."""
    offenders = []
    for path in sorted((ROOT / "src").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            args = node.args
            for default in [*args.defaults, *(d for d in args.kw_defaults if d is not None)]:
                for sub in ast.walk(default):
                    name = sub.id if isinstance(sub, ast.Name) else \
                        sub.attr if isinstance(sub, ast.Attribute) else ""  # fmt: skip
                    if name.startswith("_"):
                        offenders.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}"
                                         f"(... = {ast.unparse(default)})")  # fmt: skip
    assert offenders == []


def test_update_aircraft_defaults_read_keep() -> None:
    import inspect

    from gcu_async.client import KEEP, GcuClient

    params = inspect.signature(GcuClient.update_aircraft).parameters
    keeps = [p.name for p in params.values() if p.default is KEEP]
    assert keeps == ["attitude", "acceleration", "velocity", "position", "relative_altitude",
                     "satellites", "gnss_week", "gnss_ms"]  # fmt: skip
    assert repr(KEEP) == "KEEP"
    assert "= KEEP" in str(inspect.signature(GcuClient.update_aircraft))
