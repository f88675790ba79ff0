"""Restoring the host's mode and zoom after a GCU restart: ``GcuClient(restore=True)``
(docs/client.md, "GCU restarts").

The session reports a restart with what the host had before the loss
(:class:`~gcu_async.session.Restarted`): the mode command the GCU had confirmed last (when
the mode changed and the GCU was in that mode) with its control values, and camera 1's zoom
(when it changed). Both are submitted at once, as ordinary commands (so the session
contract holds: each executes at most once), before the application hears of the restart:
a command it sends on hearing of it comes after them and wins. A command that fails (the GCU
refuses it, no feedback in time, the link lost again, an INS-dependent mode without valid
aircraft data) is not retried: a WARNING log line and an ``ERROR`` link event say which and
why, and the application decides.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Protocol

from gcu_async.errors import GcuError
from gcu_async.protocol.builder import Context, Submission, build
from gcu_async.protocol.enums import opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.session import Restarted
from gcu_async.transport.base import LinkEvent, LinkEventKind

log = logging.getLogger("gcu_async.client")


class Restorer(Protocol):
    """What :func:`restore` needs of the client's driver (which calls it)."""

    @property
    def url(self) -> str: ...

    def context(self) -> Context: ...

    def enqueue(self, submission: Submission) -> tuple[object, asyncio.Future[Feedback | None]]:
        ...

    def emit(self, event: LinkEvent) -> None: ...


def restored(event: Restarted) -> list[str]:
    """What :func:`restore` re-applies for ``event``, as words (``"mode EULER_CONTROL"``,
    ``"zoom 5x"``)."""
    what = []
    if event.mode is not None:
        what.append(f"mode {opcode_name(event.mode.OPCODE)}")
    if event.zoom is not None:
        what.append(f"zoom {event.zoom:g}x")
    return what


def _submissions(driver: Restorer, event: Restarted) -> list[tuple[str, Submission]]:
    runs = []
    if event.mode is not None:
        runs.append((f"mode {opcode_name(event.mode.OPCODE)}",
                     Submission(event.mode, control=event.control)))  # fmt: skip
    if event.zoom is not None:
        runs.append((f"zoom {event.zoom:g}x",
                     build("zoom_to", driver.context(), ratio=event.zoom)))  # fmt: skip
    return runs


async def restore(driver: Restorer, event: Restarted) -> None:
    """Re-apply the mode and zoom ``event`` names; report each that fails."""
    url = driver.url
    pending: list[tuple[str, asyncio.Future[Feedback | None]]] = []

    def failed(what: str, exc: BaseException) -> None:
        detail = f"restoring {what} after the GCU restarted failed: {exc}"
        log.warning("%s: %s", url, detail)
        driver.emit(LinkEvent(LinkEventKind.ERROR, detail))

    for what, submission in _submissions(driver, event):
        try:
            _, future = driver.enqueue(submission)
        except GcuError as exc:
            failed(what, exc)
        else:
            pending.append((what, future))
    try:
        for what, future in pending:
            try:
                await asyncio.shield(future)
            except GcuError as exc:
                failed(what, exc)
            else:
                log.info("%s: restored %s after the GCU restarted", url, what)
    except asyncio.CancelledError:  # the client closes: the session ends the commands
        for _, future in pending:
            if not future.done():
                future.cancel()
        raise
