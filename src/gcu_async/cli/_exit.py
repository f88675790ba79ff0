"""Exit statuses shared by every sub-command (docs/cli.md, "Exit status"), and running a
coroutine so that Ctrl-C and SIGTERM end it cleanly."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import Coroutine
from typing import Any, TypeVar

T = TypeVar("T")

EXIT_OK = 0
"""Done."""
EXIT_FAILED = 1
"""The operation failed: no link, a command failed or timed out, nothing decodable."""
EXIT_USAGE = 2
"""A usage error (bad option, URL or argument), reported before anything is opened."""
EXIT_INTERRUPTED = 130
"""Interrupted by Ctrl-C (SIGINT) or SIGTERM, after a clean shutdown."""


class Interrupted(Exception):
    """SIGINT or SIGTERM ended the work (exit status :data:`EXIT_INTERRUPTED`)."""


async def interruptible(work: Coroutine[Any, Any, T]) -> T:
    """Run ``work``; SIGINT and SIGTERM cancel it (its ``async with`` blocks close what they
    opened) and raise :class:`Interrupted`."""
    task = asyncio.ensure_future(work)
    loop = asyncio.get_running_loop()
    interrupted: list[int] = []

    def interrupt(sig: int) -> None:
        interrupted.append(sig)
        task.cancel()

    installed = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
            loop.add_signal_handler(sig, interrupt, sig)
            installed.append(sig)
    try:
        return await task
    except asyncio.CancelledError:
        if not interrupted:
            raise
        raise Interrupted(signal.Signals(interrupted[0]).name) from None
    finally:
        for sig in installed:
            loop.remove_signal_handler(sig)


__all__ = ["EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "Interrupted",
           "interruptible"]
