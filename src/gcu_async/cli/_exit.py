"""Exit statuses shared by every sub-command (docs/cli.md, "Exit status"), the checks of
the usage rule they share (a missing extra, a number of seconds), running a coroutine so
that Ctrl-C and SIGTERM end it cleanly, and stopping quietly when the reader of stdout
leaves (``gcu-async monitor … | head``)."""

from __future__ import annotations

import asyncio
import contextlib
import math
import os
import signal
import sys
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


EXIT_MISSING_EXTRA = EXIT_USAGE
"""A sub-command (or an option of one) needs an extra that is not installed: like a usage
error, it is reported on one line before anything is opened, with the quoted install hint;
the same command line cannot work until the extra is installed."""
SECONDS_MAX = 3600.0
"""The longest wait an option of seconds may ask for (``--timeout``, ``--hold``): one hour."""


def install_hint(extra: str) -> str:
    """The command that installs ``extra``, quoted for every shell (zsh expands ``[…]``)."""
    return f"pip install 'gcu-async[{extra}]'"


def missing_extra(prog: str, extra: str, exc: ImportError) -> int:
    """Report a missing extra on one line of stderr; returns :data:`EXIT_MISSING_EXTRA`."""
    cause = exc.__cause__ if isinstance(exc.__cause__, ImportError) else exc
    module = f" ({cause.name} is not installed)" if cause.name else ""
    print(f"{prog}: needs the '{extra}' extra{module}: {install_hint(extra)}", file=sys.stderr)
    return EXIT_MISSING_EXTRA


def check_seconds(option: str, value: float, *, zero: bool = False,
                  high: float = SECONDS_MAX) -> float:  # fmt: skip
    """``value`` if it is a finite number of seconds in (0, ``high``] (``zero``: [0, high]);
    else ``ValueError`` naming the option, the range and the value (a usage error)."""
    low_ok = value >= 0 if zero else value > 0
    if not (math.isfinite(value) and low_ok and value <= high):
        low = "[0" if zero else "(0"
        raise ValueError(f"{option}: {value!r} is outside {low}, {high:g}] seconds")
    return value


def silence_stdout() -> None:
    """The reader of stdout has gone (``| head`` has all it wants, a closed pipe): point
    stdout at the null device, so that nothing more, not even the flush at exit, fails
    with ``BrokenPipeError``. The caller then ends quietly."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    finally:
        os.close(devnull)


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


__all__ = ["EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_MISSING_EXTRA", "EXIT_OK", "EXIT_USAGE",
           "SECONDS_MAX", "Interrupted", "check_seconds", "install_hint", "interruptible",
           "missing_extra", "silence_stdout"]
