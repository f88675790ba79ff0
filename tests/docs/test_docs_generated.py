"""The generated blocks committed into the Markdown are what the code makes now.

Tables and help texts made from the code (the client's commands, ``gcu-async send``'s
table, the pod support matrix, every sub-command's ``--help``) and copies of README
sections live between ``<!-- gen:KIND -->`` and ``<!-- /gen -->`` comments
(docs/_ext/generated.py), so a reader of the raw files sees what the site shows. Each block
must match its generator (whitespace aside), every place that needs one has one, and the
machinery can fail: a stale or unclosed block is found, rewritten, and fails the build.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import generated  # noqa: E402 - the docs' generator, from its folder

BLOCKS = [(path, block) for path in generated.pages()
          for block in generated.blocks(path.read_text(encoding="utf-8"))]  # fmt: skip


def _id(item: tuple[Path, generated.Block]) -> str:
    return f"{item[0].relative_to(ROOT)}:{item[1].spec}"


@pytest.mark.parametrize("item", BLOCKS, ids=_id)
def test_every_generated_block_is_current(item: tuple[Path, generated.Block]) -> None:
    _, block = item
    assert block.body.strip(), f"{_id(item)} is empty"
    assert block.current, f"{_id(item)} is stale: run `python docs/_ext/generated.py`"


def _subcommands() -> list[str]:
    from gcu_async.cli import build_parser

    (commands,) = (a for a in build_parser()._actions
                   if isinstance(a, argparse._SubParsersAction))  # fmt: skip
    return list(commands.choices)


def test_the_blocks_stand_where_the_docs_need_them() -> None:
    specs = {(str(path.relative_to(ROOT)), block.spec) for path, block in BLOCKS}
    wanted = {("docs/client.md", "commands"), ("docs/cli.md", "send-commands"),
              ("docs/protocol-notes.md", "pod-support"), ("docs/cli.md", "cli-help"),
              *(("docs/cli.md", f"cli-help {name}") for name in _subcommands())}  # fmt: skip
    assert wanted - specs == set()
    assert len(_subcommands()) >= 7


def test_no_page_keeps_an_unfilled_placeholder() -> None:
    """The markers of old (filled in only by the docs build) are gone from every page."""
    for path in generated.pages():
        text = path.read_text(encoding="utf-8")
        generated.blocks(text)  # every opening comment has its end
        assert "<!-- gen:commands -->\n<!--" not in text


# -- the machinery can fail ------------------------------------------------------------------
TABLE = "<!-- gen:send-commands -->\n{}\n<!-- /gen -->\n"


def test_a_stale_block_is_found_and_rewritten() -> None:
    current = TABLE.format(generated.send_table())
    (block,) = generated.blocks(current)
    assert block.current and generated.regenerate(current) == current
    reflowed = TABLE.format(generated.send_table().replace(" | ", "  |  "))
    assert generated.blocks(reflowed)[0].current  # whitespace does not count
    stale = TABLE.format(generated.send_table().replace("`take-photo`", "`take-picture`"))
    (block,) = generated.blocks(stale)
    assert not block.current
    assert generated.regenerate(stale) == current
    assert list(generated.stale([])) == []


def test_an_unclosed_or_unknown_block_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=re.escape("needs its <!-- /gen -->")):
        generated.blocks("<!-- gen:commands -->\n| a |\n")
    (block,) = generated.blocks("<!-- gen:frobnicate -->\nx\n<!-- /gen -->\n")
    with pytest.raises(ValueError, match="unknown generated block 'frobnicate'"):
        block.generate()
    with pytest.raises(ValueError, match="has no section 'nowhere'"):
        generated.include("README.md", "nowhere")
    # a mention in running text or in a code span is not a marker
    assert generated.blocks("Blocks open with `<!-- gen:KIND -->`.\n") == []


def test_an_include_is_the_section_of_its_file() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    quickstart = generated.include("README.md", "quickstart")
    assert quickstart.startswith("```python\nimport asyncio") and quickstart in readme
    assert "[start:quickstart]" not in quickstart and "[end:quickstart]" not in quickstart


def test_the_command_checks_the_repository() -> None:
    assert generated.main(["--check"]) == 0


def test_the_build_stops_at_a_stale_block() -> None:
    pytest.importorskip("mkdocs", reason="the docs build's tools (the docs dependency group)")
    import hooks  # the docs build's hook, from docs/_ext
    from mkdocs.exceptions import PluginError

    page = SimpleNamespace(file=SimpleNamespace(src_uri="cli.md"))
    current = TABLE.format(generated.send_table())
    assert hooks.on_page_markdown(current, page=page) == current  # rendered as committed
    stale = TABLE.format("| Command | Arguments | Client method |\n|---|---|---|")
    with pytest.raises(PluginError, match=r"cli\.md: the generated blocks send-commands no"):
        hooks.on_page_markdown(stale, page=page)
    with pytest.raises(PluginError, match=re.escape("needs its <!-- /gen -->")):
        hooks.on_page_markdown("<!-- gen:commands -->\n", page=page)
