"""What the web example's tests need, checked in one place: a test module calls one of these
before importing the example, and skips with the install command when something is missing."""

from __future__ import annotations

import os
from types import ModuleType

import pytest

INSTALL = "pip install -e '.[web]' --group test"
NEEDED = (
    ("starlette", "the web example needs starlette"),
    ("uvicorn", "the web example needs uvicorn"),
    ("httpx", "the web example tests need httpx"),
    ("websockets.asyncio.client", "the web example tests need websockets>=13"),
)


def require_web() -> None:
    """Skip the calling module unless the web example and its test clients import."""
    for module, why in NEEDED:
        pytest.importorskip(module, reason=f"{why}: {INSTALL}")


def require_browser() -> ModuleType:
    """:func:`require_web`, Playwright and Debian's Chromium; returns
    ``playwright.async_api``."""
    require_web()
    async_api = pytest.importorskip(
        "playwright.async_api",
        reason="the browser tests need Playwright: pip install playwright (never `playwright "
        "install`: they drive Debian's chromium)",
    )
    from helpers.examples.web import CHROMIUM

    if not os.access(CHROMIUM, os.X_OK):
        pytest.skip(f"the browser tests need {CHROMIUM}: apt-get install chromium",
                    allow_module_level=True)  # fmt: skip
    return async_api
