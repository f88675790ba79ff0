"""MkDocs hooks for the docs build: the generated blocks must be current.

The tables and help texts made from the code are committed into the Markdown between
``<!-- gen:KIND -->`` and ``<!-- /gen -->`` comments (docs/_ext/generated.py), so the raw
files and the site show the same text. The build renders them as committed and stops at a
block that no longer matches the code; the fix is ``python docs/_ext/generated.py``. (An
error, not a warning: ``mkdocs build --strict --quiet`` counts no warning, as ``--quiet``
drops them before the strict check sees them.)
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError

sys.path.insert(0, str(Path(__file__).resolve().parent))
import generated  # this folder, not a package


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    where = page.file.src_uri
    try:
        stale = [block.spec for block in generated.blocks(markdown) if not block.current]
    except ValueError as exc:
        raise PluginError(f"{where}: {exc}") from None
    if stale:
        raise PluginError(f"{where}: the generated blocks {', '.join(stale)} no longer match "
                          "the code: run `python docs/_ext/generated.py`")
    return markdown
