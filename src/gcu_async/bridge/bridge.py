"""``MavlinkBridge``: the asyncio part. It owns the MAVLink links, builds a
:class:`~gcu_async.bridge.view.GcuView` when it needs one, and carries out what the pure
planners decide on a :class:`~gcu_async.client.GcuClient` (docs/mavlink-bridge.md).

Everything it sends goes to every link: HEARTBEAT of both components at 1 Hz, the streams
of :mod:`~gcu_async.bridge.streams` (adjustable with MAV_CMD_SET_MESSAGE_INTERVAL),
acknowledgements and requested messages.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import logging
import math
import time
from collections.abc import Sequence
from dataclasses import replace
from types import TracebackType
from typing import Any

from gcu_async.bridge import admission, camera, dispatch, gimbal, streams
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.autopilot import AutopilotFeed
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
    result_for,
)
from gcu_async.bridge.links import MavlinkLink, make_link
from gcu_async.bridge.lograte import LogLimiter
from gcu_async.bridge.view import Control, GcuView
from gcu_async.client.client import ClientState, GcuClient
from gcu_async.errors import GcuError
from gcu_async.protocol.enums import Mode

log = logging.getLogger("gcu_async.bridge")

IN_PROGRESS_AFTER = 0.5
"""Seconds a GCU command may take before the bridge acknowledges IN_PROGRESS."""
OPEN_RETRY_SECONDS = 2.0
"""Pause between attempts to open the GCU link."""


class MavlinkBridge:
    """The XF gimbal and camera as MAVLink components on ``connections``.

    Args:
        client: a :class:`GcuClient` (opened by the bridge if it is not open; best built
            with ``check_support=True`` so that Appendix 8 refusals are UNSUPPORTED).
        connections: MAVLink connection strings (``udpout:HOST:PORT``,
            ``udpin:HOST:PORT``, ``tcp:HOST:PORT``, ``tcpin:HOST:PORT``,
            ``/dev/ttyACM0,115200``; :mod:`~gcu_async.bridge.endpoint`), checked here.
        system_id: the vehicle's MAVLink system id (the autopilot's); the components use it.
        camera: what the GCU does not report about the camera (:class:`CameraConfig`).
        autopilot_component: the autopilot's component id (its messages feed the GCU).
        in_progress_after: seconds before a running command is acknowledged IN_PROGRESS.
    """

    def __init__(
        self,
        client: GcuClient,
        connections: Sequence[str],
        *,
        system_id: int = 1,
        camera: CameraConfig | None = None,
        autopilot_component: int = mavlink.MAV_COMP_ID_AUTOPILOT1,
        in_progress_after: float = IN_PROGRESS_AFTER,
    ) -> None:
        if not connections:
            raise ValueError("connections: give at least one MAVLink connection")
        if not 1 <= system_id <= 255:
            raise ValueError(f"system_id: {system_id!r} is outside the allowed range [1, 255]")
        if not (isinstance(in_progress_after, (int, float)) and 0 < in_progress_after < 60):
            raise ValueError(f"in_progress_after: {in_progress_after!r} is outside the allowed "
                             "range (0, 60) s")  # fmt: skip
        self.client = client
        self.system_id = system_id
        self.camera = camera if camera is not None else CameraConfig()
        self.in_progress_after = in_progress_after
        self.links = [make_link(url) for url in connections]
        self.autopilot = AutopilotFeed(system_id, autopilot_component)
        self._packers = {c: mavlink.MAVLink(None, srcSystem=system_id, srcComponent=c)
                         for c in dispatch.COMPONENTS}  # fmt: skip
        self._started = time.monotonic()
        self.schedules = {
            c: streams.StreamSchedule(set(dispatch.builders(c, self.camera)), self._started)
            for c in dispatch.COMPONENTS}  # fmt: skip
        """Component → its :class:`~gcu_async.bridge.streams.StreamSchedule`."""
        self._control = Control()
        self._bridge_mode: Mode | None = None
        self._pending_mode: Mode | None = None
        self._tracking_mode = 0
        self._tracking_box: tuple[float, float, float, float] | None = None
        self._camera_mode = 0
        self._images = 0
        self._recording: bool | None = None
        self._recording_since: int | None = None
        self._was_tracking = False
        self._memory: dict[Any, admission.Memory] = {}
        """Link → the commands it brought (retransmissions are told per link)."""
        self._queue = admission.Queue()
        self._wake = asyncio.Event()
        self._logs = LogLimiter(log)
        self._budgets: dict[Any, admission.Budget] = {}
        self._latest_control: tuple[Any, Any] | None = None
        self._control_timer: asyncio.TimerHandle | None = None
        self._control_at = -math.inf
        self._mode_message_at = -math.inf
        self._tasks: set[asyncio.Task[Any]] = set()
        self._main: asyncio.Task[None] | None = None
        self._aircraft_errors: set[str] = set()
        self.stats = dict.fromkeys(
            ("messages", "commands", "acks", "sent", "handler_errors", "retransmissions",
             "superseded",
             "rejected", "expired", "shed", "control_messages", "control_coalesced"),
            0)  # fmt: skip
        """Counters: messages and commands received, retransmissions answered without running,
        commands superseded (CANCELLED), rejected because a bound was full, expired
        (waited :data:`~gcu_async.bridge.admission.COMMAND_WAIT`), shed (over a link's
        command rate, dropped unanswered), control messages received and coalesced
        (replaced by a newer one before they were taken)."""

    # -- lifecycle ------------------------------------------------------------------------
    async def __aenter__(self) -> MavlinkBridge:
        await self.start()
        return self

    async def __aexit__(self, exc_type: type[BaseException] | None,
                        exc: BaseException | None, tb: TracebackType | None) -> None:  # fmt: skip
        await self.close()

    async def start(self) -> None:
        """Open the MAVLink links and start streaming; the GCU client is opened in the
        background if it is not open yet (until then the heartbeats say CRITICAL)."""
        opened: list[MavlinkLink] = []
        try:
            for link in self.links:
                await link.open(self._on_message)
                opened.append(link)
        except BaseException:
            for link in opened:
                await link.close()
            raise
        self._main = asyncio.ensure_future(self._run())
        self._spawn(self._executor())

    async def close(self) -> None:
        """Stop streaming, cancel running commands, close the links (at once, whatever
        they are doing; :mod:`~gcu_async.bridge.links`) and the client."""
        if self._control_timer is not None:
            self._control_timer.cancel()
            self._control_timer = None
        tasks = [t for t in (self._main, *self._tasks) if t is not None]
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        self._main = None
        for entry in list(self._queue):  # never sent: say so before the links close
            self._queue.remove(entry)
            self._finish(entry, TEMPORARILY_REJECTED)
        for link in self.links:
            await link.close()
        await self.client.close()

    async def _run(self) -> None:
        if self.client.state is ClientState.CLOSED:
            self._spawn(self._open_client())
        next_heartbeat = time.monotonic()
        while True:
            now = time.monotonic()
            try:
                if now >= next_heartbeat:
                    self._heartbeat(now)
                    next_heartbeat = max(next_heartbeat + 1.0, now)
                self._stream(now)
            except Exception:
                self.stats["handler_errors"] += 1
                log.exception("bridge: streaming step failed")
            wake = min(next_heartbeat, *(s.next_time() for s in self.schedules.values()))
            await asyncio.sleep(min(1.0, max(0.0, wake - time.monotonic())))

    async def _open_client(self) -> None:
        """Open the client, retrying every :data:`OPEN_RETRY_SECONDS` until it opens (a GCU
        powered after the bridge); each failure is logged once per outage."""
        failed = False
        while True:
            try:
                await self.client.open()
            except (GcuError, OSError) as exc:
                if not failed:
                    log.warning("bridge: GCU link not up yet (%s); retrying every %g s", exc,
                                OPEN_RETRY_SECONDS)  # fmt: skip
                failed = True
                await asyncio.sleep(OPEN_RETRY_SECONDS)
            else:
                if failed:
                    log.warning("bridge: GCU link up")
                return

    # -- the view ---------------------------------------------------------------------------
    def view(self) -> GcuView:
        """What the bridge knows now."""
        client, session = self.client, self.client.session
        now = time.monotonic()
        up = client.state is ClientState.OPEN and client.link.up
        recording = client.recording
        ms = self._ms(now)
        if recording and not self._recording:
            self._recording_since = ms
        self._recording = recording
        return GcuView(
            time_boot_ms=ms, link_up=up, status=session.status, info=session.info,
            ins_valid=client.ins_valid if up else False, aircraft=client.aircraft,
            position_current=self.autopilot.position_current(now, client.aircraft_timeout),
            home_altitude=self.autopilot.home_altitude, utc_usec=self.autopilot.utc_usec(now),
            recording=recording, recording_since_ms=self._recording_since,
            images_captured=self._images, control=self._control,
            bridge_mode=self._bridge_mode, pending_mode=self._pending_mode,
            tracking_mode=self._tracking_mode, tracking_box=self._tracking_box,
            camera_mode=self._camera_mode,
        )  # fmt: skip

    def _ms(self, now: float) -> int:
        return int((now - self._started) * 1000) & 0xFFFFFFFF

    # -- sending ----------------------------------------------------------------------------
    def send(self, component: int, message: Any, link: Any = None) -> None:
        """Pack ``message`` as ``component`` of this system and write it to ``link``, or to
        every link (``None``)."""
        packer = self._packers[component]
        data = message.pack(packer)
        packer.seq = (packer.seq + 1) % 256
        self.stats["sent"] += 1
        for each in self.links if link is None else (link,):
            each.send(data)

    def _heartbeat(self, now: float) -> None:
        view = self.view()
        self.send(gimbal.COMPONENT, gimbal.heartbeat(view, mavlink.MAV_TYPE_GIMBAL))
        self.send(camera.COMPONENT, gimbal.heartbeat(view, mavlink.MAV_TYPE_CAMERA))
        for link in self.links:
            link.check_silence(now)
        self._logs.flush()

    def _stream(self, now: float) -> None:
        due = {c: s.due(now) for c, s in self.schedules.items()}
        if not any(due.values()):
            return
        view = self.view()
        tracking = view.mode is Mode.TRACK
        for component, messages in due.items():
            builders = dispatch.builders(component, self.camera)
            for mid in messages:
                if mid == streams.TRACKING and not self.schedules[component].explicit(mid):
                    if not (tracking or self._was_tracking):
                        continue  # by default only while tracking, plus one IDLE after
                    self._was_tracking = tracking
                message = builders[mid](view)
                if message is not None:
                    self.send(component, message)

    def _ack(self, component: int, cmd: CommandIn, link: Any, result: int, param2: int = 0,
             progress: int = 0) -> None:  # fmt: skip
        """COMMAND_ACK to the sender, on the link the command came by (a flood on one link
        is not echoed to the others)."""
        self.stats["acks"] += 1
        self.send(component, mavlink.MAVLink_command_ack_message(
            cmd.command, result, progress, param2, *cmd.source), link)

    # -- receiving --------------------------------------------------------------------------
    def _on_message(self, link: Any, msg: Any) -> None:
        now = time.monotonic()
        link.note_message(now)
        self.stats["messages"] += 1
        try:
            self._handle(link, msg, now)
        except Exception:  # hostile input must never stop the bridge
            self.stats["handler_errors"] += 1
            self._logs.log(logging.ERROR, "handler failure", "bridge: handling %s failed",
                           msg.get_type(), exc_info=True)  # fmt: skip

    def _handle(self, link: Any, msg: Any, now: float) -> None:
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if source[0] == self.system_id and source[1] in dispatch.COMPONENTS:
            return  # our own messages echoed by a router
        if self.autopilot.accepts(msg):
            self._aircraft(msg, now)
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT"):
            if (msg.target_system not in (0, self.system_id)
                    or msg.target_component not in (0, *dispatch.COMPONENTS)):  # fmt: skip
                return  # for another system or component: costs this link no budget
            budget = self._budgets.get(link)
            if budget is None:
                budget = self._budgets[link] = admission.Budget()
            if not budget.take(now):
                self.stats["shed"] += 1
                self._logs.log(logging.WARNING, "shed command", "bridge: more than %g "
                               "commands/s on %s: dropped unanswered", budget.rate,
                               getattr(link, "url", link))  # fmt: skip
                return
            cmd = CommandIn.from_message(msg)
            assert cmd is not None
            for component in dispatch.components_for(cmd, self.system_id, self.camera):
                self._command(cmd, component, link, now)
            return
        if kind in gimbal.CONTROL_MESSAGES:
            target = (msg.target_system, msg.target_component)
            if target[0] in (0, self.system_id) and target[1] in (0, gimbal.COMPONENT):
                self._coalesce_control(link, msg, now)

    def _coalesce_control(self, link: Any, msg: Any, now: float) -> None:
        """Keep the latest control message; take one per :data:`admission.CONTROL_INTERVAL`
        (a flood costs a store per message, not a mode change)."""
        self.stats["control_messages"] += 1
        if not self._control.allows((msg.get_srcSystem(), msg.get_srcComponent())):
            return  # another component holds control (checked here: before coalescing)
        if self._latest_control is not None:
            self.stats["control_coalesced"] += 1
        self._latest_control = (link, msg)
        if self._control_timer is None:
            self._control_later(self._control_at + admission.CONTROL_INTERVAL - now)

    def _control_later(self, delay: float) -> None:
        self._control_timer = asyncio.get_running_loop().call_later(max(0.0, delay),
                                                                   self._take_control)

    def _take_control(self) -> None:
        self._control_timer = None
        latest, self._latest_control = self._latest_control, None
        if latest is None:
            return
        link, msg = latest
        now = self._control_at = time.monotonic()
        try:
            call = gimbal.message_call(msg, self.view())
        except ValueError as exc:
            self._logs.log(logging.WARNING, "ignored control message",
                           "bridge: %s ignored: %s", msg.get_type(), exc)  # fmt: skip
            return
        except Exception:
            self.stats["handler_errors"] += 1
            self._logs.log(logging.ERROR, "handler failure", "bridge: handling %s failed",
                           msg.get_type(), exc_info=True)  # fmt: skip
            return
        if call is None:
            return
        if call.method not in admission.IMMEDIATE_CALLS:  # a mode change: spaced out
            due = self._mode_message_at + admission.MESSAGE_MODE_INTERVAL
            if now < due:
                if self._latest_control is None:
                    self._latest_control = latest
                self._control_later(due - now)
                return
            self._mode_message_at = now
        self._control_message(call, link, now)

    def _aircraft(self, msg: Any, now: float) -> None:
        kind = msg.get_type()
        try:
            changes = self.autopilot.update(msg, now)
            if changes:
                self.client.update_aircraft(**changes)
        except (ValueError, TypeError, ArithmeticError) as exc:
            # ArithmeticError: OverflowError from a date or a conversion out of every range
            if kind not in self._aircraft_errors:
                self._aircraft_errors.add(kind)
                log.warning("bridge: autopilot %s not used: %s", kind, exc)
            return
        self._aircraft_errors.discard(kind)

    def _control_message(self, call: GcuCall, link: Any, now: float) -> None:
        """A gimbal control message's call: new control values apply at once; a mode
        change waits its turn in the pointing slot, where the latest replaces any waiting."""
        immediate = call.method in admission.IMMEDIATE_CALLS
        waiting = any(e.slot == admission.POINTING for e in self._queue)
        if immediate and not waiting:
            try:
                getattr(self.client, call.method)(**call.kwargs)
            except ValueError as exc:
                self._logs.log(logging.INFO, "control message failure",
                               "bridge: %s failed: %s", call.method, exc)  # fmt: skip
            return
        entry = admission.Entry(None, gimbal.COMPONENT, link, now, admission.POINTING,
                                call=call)  # fmt: skip
        self._admit(entry)

    def _command(self, cmd: CommandIn, component: int, link: Any, now: float) -> None:
        self.stats["commands"] += 1
        memory = self._memory.get(link)
        if memory is None:
            memory = self._memory[link] = admission.Memory()
        old = memory.find(cmd, component, now)
        if old is not None:  # a retransmission: answered, never run again
            self.stats["retransmissions"] += 1
            old.confirmation = max(old.confirmation, cmd.confirmation)
            if old.result is not None:
                self._ack(component, cmd, link, old.result, old.param2)
                if old.result == ACCEPTED and dispatch.requested_id(cmd) is not None:
                    # its message may be what was lost: send it again (a request runs
                    # nothing on the GCU)
                    plan = dispatch.plan(cmd, component, self.view(), self.camera)
                    for reply in plan.replies:
                        self.send(component, reply, link)
            else:
                self._ack(component, cmd, link, IN_PROGRESS, progress=255)
            return
        entry = admission.Entry(cmd, component, link, now, admission.SLOTS.get(cmd.command),
                                stop=admission.is_stop(cmd),
                                confirmation=cmd.confirmation)  # fmt: skip
        memory.add(entry, now)
        plan = dispatch.plan(cmd, component, self.view(), self.camera)
        if plan.call is None:
            self._answer_plan(entry, plan)
            return
        self._admit(entry)

    def _answer_plan(self, entry: admission.Entry, plan: Plan) -> None:
        """Answer a command whose plan needs no GCU call (a refusal or a reply)."""
        assert plan.result is not None
        assert entry.cmd is not None
        if plan.reason:
            self._logs.log(logging.INFO, "refused command", "bridge: command %d refused (%d): %s",
                           entry.cmd.command, plan.result, plan.reason)  # fmt: skip
        if plan.result == ACCEPTED:
            self._take(plan, entry.component)
        self._finish(entry, plan.result)
        for reply in plan.replies:
            self.send(entry.component, reply, entry.link)

    def _admit(self, entry: admission.Entry) -> None:
        """Queue ``entry``: it replaces what waits in its slot (answered CANCELLED), or is
        refused (TEMPORARILY_REJECTED) when a bound is full."""
        for old in self._queue.superseded_by(entry):
            self._queue.remove(old)
            self.stats["superseded"] += 1
            self._finish(old, CANCELLED)
        refusal = self._queue.refusal(entry)
        if refusal is not None:
            self.stats["rejected"] += 1
            self._logs.log(logging.INFO, "queue full", "bridge: command refused: %s", refusal)
            self._finish(entry, TEMPORARILY_REJECTED)
            return
        self._queue.push(entry)
        if entry.cmd is not None:
            entry.timer = asyncio.get_running_loop().call_later(
                self.in_progress_after, self._in_progress, entry)
        self._wake.set()

    def _in_progress(self, entry: admission.Entry) -> None:
        if entry.result is None and entry.cmd is not None:
            self._ack(entry.component, entry.cmd, entry.link, IN_PROGRESS, progress=255)

    def _finish(self, entry: admission.Entry, result: int, param2: int = 0) -> None:
        """The final answer of ``entry`` (once; a retransmission gets it again)."""
        entry.state = "done"
        entry.result, entry.param2 = result, param2
        entry.done_at = time.monotonic()
        if entry.timer is not None:
            entry.timer.cancel()
            entry.timer = None
        if entry.cmd is not None:
            self._ack(entry.component, entry.cmd, entry.link, result, param2)

    def _take(self, plan: Plan, component: int) -> None:
        if plan.interval is not None:
            self.schedules[component].set(*plan.interval, time.monotonic())
        if plan.control is not None:
            self._control = plan.control
        if plan.camera_mode is not None:
            self._camera_mode = plan.camera_mode

    # -- running commands, one at a time ----------------------------------------------------
    async def _executor(self) -> None:
        """Run the waiting entries one at a time, in turn per link."""
        while True:
            entry = self._queue.pop()
            if entry is None:
                self._wake.clear()
                await self._wake.wait()
                continue
            try:
                await self._run_entry(entry)
            except asyncio.CancelledError:
                raise
            except Exception:
                self.stats["handler_errors"] += 1
                self._logs.log(logging.ERROR, "handler failure", "bridge: command failed "
                               "unexpectedly", exc_info=True)  # fmt: skip
                if entry.result is None:
                    self._finish(entry, FAILED, NO_STATUS)

    async def _run_entry(self, entry: admission.Entry) -> None:
        remaining = entry.deadline - time.monotonic()
        if remaining <= 0:
            self.stats["expired"] += 1
            self._logs.log(logging.INFO, "expired command", "bridge: command waited %g s "
                           "without reaching the GCU: not run", admission.COMMAND_WAIT)
            self._finish(entry, TEMPORARILY_REJECTED)
            return
        if entry.cmd is None:
            call = entry.call
            assert call is not None
        else:  # planned again: the state may have changed while it waited
            plan = dispatch.plan(entry.cmd, entry.component, self.view(), self.camera)
            if plan.call is None:
                self._answer_plan(entry, plan)
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
            self._logs.log(logging.ERROR, "handler failure", "bridge: command %d failed "
                           "unexpectedly", entry.cmd.command, exc_info=True)  # fmt: skip
            result, param2 = FAILED, NO_STATUS
        if error is not None:
            self._logs.log(logging.INFO, "failed command", "bridge: command %d -> %d: %s",
                           entry.cmd.command, result, error)  # fmt: skip
        self._finish(entry, result, param2)
        if result == ACCEPTED and call.then == "image_captured":
            self.send(camera.COMPONENT, camera.image_captured(self.view(), self._images))
            self._images += 1

    async def _execute(self, call: GcuCall, *, queue_timeout: float) -> None:
        """Run ``call`` on the client; a command not sent within ``queue_timeout`` seconds
        ends NOT_SENT (the client's own queue deadline: exact, the session drops it before
        any packet could carry it). The bridge is the client's only user (B2), so setting
        the session's default for this one submission and restoring it right after is
        safe."""
        method = getattr(self.client, call.method)
        if call.mode is not None:
            self._pending_mode = call.mode
        session = self.client.session
        saved = session.queue_timeout
        session.queue_timeout = queue_timeout
        asyncio.get_running_loop().call_soon(setattr, session, "queue_timeout", saved)
        try:
            result = method(**call.kwargs)
            if inspect.isawaitable(result):
                await result  # submitted in this first step, before the restore runs
        except BaseException:
            if call.mode is not None:
                self._bridge_mode = None
            raise
        else:
            if call.mode is not None:
                self._bridge_mode = call.mode
            if call.method == "track":
                self._tracking_mode = call.tracking_mode
                self._tracking_box = call.kwargs["box"]
        finally:
            if self._pending_mode is call.mode:
                self._pending_mode = None

    def _spawn(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def replace_camera(self, **changes: Any) -> None:
        """Change the :class:`CameraConfig` (e.g. ``video_url``) while running."""
        self.camera = replace(self.camera, **changes)
