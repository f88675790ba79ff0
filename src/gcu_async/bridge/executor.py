"""The bridge's command executor: what waits for the GCU, run on the client one at a time.

Commands and pointing control messages the bridge took wait in an
:class:`~gcu_async.bridge.admission.Queue` (the shares taking turns, a newer command of a
kind replacing the one waiting); :class:`CommandExecutor` runs them one at a time, each once
the GCU is ready (:func:`~gcu_async.bridge.gcu_link.ready`), and answers each command once:
IN_PROGRESS after ``in_progress_after`` seconds, then its result; what waited past
:data:`~gcu_async.bridge.admission.COMMAND_WAIT` is answered TEMPORARILY_REJECTED and never
sent (docs/mavlink-bridge.md, "The bridge contract"). It also keeps what the bridge set on
the GCU (mode, tracking, photos taken), which the bridge's view reports.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import time
from dataclasses import replace
from typing import Any, Protocol

from gcu_async.bridge import admission, camera, dispatch, gcu_link
from gcu_async.bridge.camera import CameraConfig
from gcu_async.bridge.commands import (
    ACCEPTED,
    CANCELLED,
    FAILED,
    IN_PROGRESS,
    NO_STATUS,
    TEMPORARILY_REJECTED,
    CommandIn,
    GcuCall,
    Plan,
    command_name,
    result_for,
)
from gcu_async.bridge.lograte import LogLimiter
from gcu_async.bridge.view import GcuView
from gcu_async.client.client import GcuClient
from gcu_async.protocol.enums import Mode


class Host(Protocol):
    """What the executor uses of the bridge (:class:`~gcu_async.bridge.MavlinkBridge`)."""

    client: GcuClient
    camera: CameraConfig
    stats: dict[str, int]

    def view(self) -> GcuView: ...

    def send(self, component: int, message: Any, link: Any = None) -> None: ...

    def _ack(self, component: int, cmd: CommandIn, origin: Any, result: int,
             param2: int = 0, progress: int = 0) -> None: ...  # fmt: skip

    def _log_answer(self, entry: admission.Entry, result: int, reason: str) -> None: ...

    def _answer_plan(self, entry: admission.Entry, plan: Plan) -> None: ...


class CommandExecutor:
    """The bridge's waiting commands and how they run (see the module)."""

    def __init__(self, host: Host, logs: LogLimiter, in_progress_after: float) -> None:
        self._host = host
        self._logs = logs
        self.in_progress_after = in_progress_after
        self.queue = admission.Queue()
        self._wake = asyncio.Event()
        self.bridge_mode: Mode | None = None
        """The mode the bridge's last mode command set (None: not known)."""
        self.pending_mode: Mode | None = None
        """The mode of the mode command running now."""
        self.tracking_mode = 0
        self.tracking_box: tuple[float, float, float, float] | None = None
        self.images = 0
        """Photos taken through the bridge."""

    def forget_mode(self) -> None:
        """The GCU restarted: it is in its power-on mode, not tracking (the next request
        sends its mode command again)."""
        self.bridge_mode = None
        self.tracking_mode = 0
        self.tracking_box = None

    # -- admission and answers ------------------------------------------------------------
    def admit(self, entry: admission.Entry) -> None:
        """Queue ``entry``: it replaces what waits in its share's slot (answered CANCELLED),
        or is refused (TEMPORARILY_REJECTED) when its share's room is full."""
        host = self._host
        for old in self.queue.superseded_by(entry):
            self.queue.remove(old)
            host.stats["superseded"] += 1
            if old.cmd is not None:
                host._log_answer(old, CANCELLED, "a newer command of its kind replaced it")
            self.finish(old, CANCELLED)
        refusal = self.queue.refusal(entry)
        if refusal is not None:
            host.stats["rejected"] += 1
            if isinstance(entry.share, admission.Share):
                entry.share.refused += 1
            if entry.cmd is not None:
                host._log_answer(entry, TEMPORARILY_REJECTED, refusal)
            self.finish(entry, TEMPORARILY_REJECTED)
            return
        self.queue.push(entry)
        if entry.cmd is not None:
            entry.timer = asyncio.get_running_loop().call_later(
                self.in_progress_after, self._in_progress, entry)
        self._wake.set()

    def _in_progress(self, entry: admission.Entry) -> None:
        if entry.result is None and entry.cmd is not None:
            self._host._ack(entry.component, entry.cmd, entry.reply, IN_PROGRESS, progress=255)

    def finish(self, entry: admission.Entry, result: int, param2: int = 0) -> None:
        """The final answer of ``entry`` (once; a retransmission gets it again)."""
        entry.state = "done"
        entry.result, entry.param2 = result, param2
        entry.done_at = time.monotonic()
        if entry.timer is not None:
            entry.timer.cancel()
            entry.timer = None
        if entry.cmd is not None:
            self._host._ack(entry.component, entry.cmd, entry.reply, result, param2)

    def reject_waiting(self) -> None:
        """Answer every waiting entry TEMPORARILY_REJECTED (the bridge closes: never sent)."""
        for entry in list(self.queue):
            self.queue.remove(entry)
            self.finish(entry, TEMPORARILY_REJECTED)

    # -- running, one at a time -----------------------------------------------------------
    async def run(self) -> None:
        """Run the waiting entries one at a time, the shares taking turns, each once the
        GCU is ready (:func:`~gcu_async.bridge.gcu_link.ready`); what waits past its
        :data:`~gcu_async.bridge.admission.COMMAND_WAIT` is answered TEMPORARILY_REJECTED."""
        client = self._host.client
        while True:
            if not self.queue.size:
                self._wake.clear()
                await self._wake.wait()
                continue
            self._expire(time.monotonic())
            if not self.queue.size:
                continue
            if not gcu_link.ready(client):
                # readiness changes with a reply or the client's timers: look again each
                # host packet period, and at the next deadline at the latest
                wait = min(1.0 / client.rate_hz, self.queue.next_deadline() - time.monotonic())
                await asyncio.sleep(max(0.0, wait))
                continue
            entry = self.queue.pop()
            assert entry is not None
            try:
                await self._run_entry(entry)
            except asyncio.CancelledError:
                raise
            except Exception:
                self._host.stats["handler_errors"] += 1
                self._logs.log(logging.ERROR, "handler failure", "bridge: command failed "
                               "unexpectedly", exc_info=True)  # fmt: skip
                if entry.result is None:
                    self.finish(entry, FAILED, NO_STATUS)

    def _expire(self, now: float) -> None:
        """Answer the entries that waited their :data:`~gcu_async.bridge.admission.COMMAND_WAIT`
        TEMPORARILY_REJECTED: never sent, never will be."""
        expired = self.queue.expired(now)
        if not expired:
            return
        client = self._host.client
        reason = (f"not sent within {admission.COMMAND_WAIT:g} s: "
                  + ("other commands went first" if gcu_link.ready(client) else
                     "the GCU does not answer" if gcu_link.opened(client) else
                     "the GCU link is not open yet"))  # fmt: skip
        for entry in expired:
            self.queue.remove(entry)
            self._host.stats["expired"] += 1
            if entry.cmd is not None:
                self._host._log_answer(entry, TEMPORARILY_REJECTED, reason)
            self.finish(entry, TEMPORARILY_REJECTED)

    async def _run_entry(self, entry: admission.Entry) -> None:
        host = self._host
        remaining = entry.deadline - time.monotonic()
        if remaining <= 0:  # (its deadline passed since the executor looked)
            host.stats["expired"] += 1
            if entry.cmd is not None:
                host._log_answer(entry, TEMPORARILY_REJECTED, f"not sent within "
                                 f"{admission.COMMAND_WAIT:g} s")  # fmt: skip
            self.finish(entry, TEMPORARILY_REJECTED)
            return
        if entry.cmd is None:
            call = entry.call
            assert call is not None
        else:  # planned again: the state may have changed while it waited
            plan = dispatch.plan(entry.cmd, entry.component, host.view(), host.camera)
            if plan.call is None:
                host._answer_plan(entry, plan)
                return
            call = plan.call
        entry.state = "running"
        entry.ran = True
        error: BaseException | None = None
        try:
            await self._execute(call, queue_timeout=remaining)
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            error = exc
        if entry.cmd is None:
            entry.state = "done"
            if error is not None:
                self._logs.log(logging.INFO, "control message failure",
                               "bridge: %s failed: %s", call.method, error)  # fmt: skip
            return
        try:
            result, param2 = result_for(error)
        except Exception:
            self._logs.log(logging.ERROR, "handler failure", "bridge: %s failed "
                           "unexpectedly", command_name(entry.cmd.command),
                           exc_info=True)  # fmt: skip
            result, param2 = FAILED, NO_STATUS
        if error is not None:
            host._log_answer(entry, result, str(error))
        self.finish(entry, result, param2)
        if result == ACCEPTED and call.then == "image_captured":
            host.send(camera.COMPONENT, camera.image_captured(host.view(), self.images))
            self.images += 1

    async def _execute(self, call: GcuCall, *, queue_timeout: float) -> None:
        """Run ``call`` on the client; a command not sent within ``queue_timeout`` seconds
        ends NOT_SENT (the client's own queue deadline: exact, the session drops it before
        any packet could carry it). The bridge is the client's only user (B2), so setting
        the session's default for this one submission and restoring it right after is
        safe."""
        method = getattr(self._host.client, call.method)
        if call.mode is not None:
            self.pending_mode = call.mode
        session = self._host.client.session
        saved = session.config
        session.config = replace(saved, queue_timeout=queue_timeout)
        asyncio.get_running_loop().call_soon(setattr, session, "config", saved)
        try:
            result = method(**call.kwargs)
            if inspect.isawaitable(result):
                await result  # submitted in this first step, before the restore runs
        except BaseException:
            if call.mode is not None:
                self.bridge_mode = None
            raise
        else:
            if call.mode is not None:
                self.bridge_mode = call.mode
            if call.method == "track":
                self.tracking_mode = call.tracking_mode
                self.tracking_box = call.kwargs["box"]
        finally:
            if self.pending_mode is call.mode:
                self.pending_mode = None
