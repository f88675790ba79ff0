"""``MavlinkBridge``: the asyncio part. It owns the MAVLink links, builds a
:class:`~gcu_async.bridge.view.GcuView` when it needs one, and carries out what the pure
planners decide on a :class:`~gcu_async.client.GcuClient` (docs/mavlink-bridge.md).

Streams go to every link: HEARTBEAT of both components at 1 Hz, the streams of
:mod:`~gcu_async.bridge.streams` (adjustable with MAV_CMD_SET_MESSAGE_INTERVAL);
acknowledgements and requested messages go to the peer that sent the command.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from types import TracebackType
from typing import Any

from gcu_async.bridge import admission, camera, dispatch, gcu_link, gimbal, streams
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.autopilot import AutopilotFeed
from gcu_async.bridge.camera import CameraConfig
from gcu_async.bridge.commands import (
    ACCEPTED,
    DENIED,
    FAILED,
    IN_PROGRESS,
    TEMPORARILY_REJECTED,
    CommandIn,
    GcuCall,
    Plan,
    command_name,
    result_name,
)
from gcu_async.bridge.endpoint import Endpoint, parse_endpoint
from gcu_async.bridge.executor import CommandExecutor
from gcu_async.bridge.links import MavlinkLink, Peer
from gcu_async.bridge.lograte import LogLimiter
from gcu_async.bridge.stream_link import SerialLink, TcpInLink, TcpLink
from gcu_async.bridge.udp_link import UdpInLink, UdpOutLink
from gcu_async.bridge.view import Control, GcuView
from gcu_async.client.client import ClientState, GcuClient
from gcu_async.errors import GcuError
from gcu_async.protocol.enums import Mode
from gcu_async.transport.base import LinkEvent

log = logging.getLogger("gcu_async.bridge")

IN_PROGRESS_AFTER = 0.5
"""Seconds a GCU command may take before the bridge acknowledges IN_PROGRESS."""
OPEN_RETRY_SECONDS = 2.0
"""Pause between attempts to open the GCU link."""
WARN_RESULTS = frozenset({TEMPORARILY_REJECTED, FAILED, DENIED})
"""Answers logged as warnings (seen without ``-v``): the command was not carried out and
the user may want to know why; UNSUPPORTED and CANCELLED are routine (INFO)."""

Origin = tuple[MavlinkLink, Peer]
"""Where a command came from, and so where its answers go."""
LINKS: dict[str, Callable[[Endpoint], MavlinkLink]] = {
    "udpout": UdpOutLink, "udpin": UdpInLink, "tcp": TcpLink, "tcpin": TcpInLink,
    "serial": SerialLink}  # fmt: skip
"""Each connection kind's link (:mod:`~gcu_async.bridge.endpoint`)."""


def make_link(connection: str) -> MavlinkLink:
    """The link for one connection string (ValueError, one line, for a malformed one)."""
    endpoint = parse_endpoint(connection)
    return LINKS[endpoint.kind](endpoint)


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
        self._camera_mode = 0
        self._recording: bool | None = None
        self._recording_since: int | None = None
        self._was_tracking = False
        self._logs = LogLimiter(log)
        self.executor = CommandExecutor(self, self._logs, in_progress_after)
        """Runs the commands on the client, one at a time (:mod:`~gcu_async.bridge.executor`)."""
        self._latest_control: tuple[admission.Share, Origin, Any] | None = None
        self._control_timer: asyncio.TimerHandle | None = None
        self._control_at = -math.inf
        self._mode_message_at = -math.inf
        self._tasks: set[asyncio.Task[Any]] = set()
        self._main: asyncio.Task[None] | None = None
        self._aircraft_errors: set[str] = set()
        self._unsubscribe: Any = None
        self._reopening = False
        self.stats = dict.fromkeys(
            ("messages", "commands", "acks", "sent", "handler_errors", "retransmissions",
             "superseded",
             "rejected", "expired", "shed", "control_messages", "control_coalesced"),
            0)  # fmt: skip
        """Counters: messages and commands received, retransmissions answered without running,
        commands superseded (CANCELLED), rejected because their share's room was full,
        expired (waited :data:`~gcu_async.bridge.admission.COMMAND_WAIT`), shed (over their
        share's command rate, dropped unanswered), control messages received and coalesced
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
        self._unsubscribe = self.client.on_link_change(self._on_gcu_event)
        self._main = asyncio.ensure_future(self._run())
        self._spawn(self.executor.run())

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
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None
        self.executor.reject_waiting()  # never sent: say so before the links close
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
                    if gcu_link.failed(self.client):
                        self._start_reopen()
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

    def _start_reopen(self) -> None:
        if not self._reopening:
            self._reopening = True
            self._spawn(self._reopen_client())

    async def _reopen_client(self) -> None:
        """The client's transport gave up reconnecting: close the client and open it again
        the bridge's way (retrying until the GCU answers)."""
        try:
            log.warning("bridge: the GCU link gave up; reopening it")
            await self.client.close()
            await self._open_client()
        finally:
            self._reopening = False

    def _on_gcu_event(self, event: LinkEvent) -> None:
        """Link events of the GCU client: a transport that gave up is reopened; after a
        restart the pod is in its power-on mode, so the bridge forgets the mode and the
        tracking it had set (the next request sends its mode command again)."""
        if gcu_link.gave_up(event):
            self._start_reopen()
        elif gcu_link.restarted(event):
            self.executor.forget_mode()

    # -- the view ---------------------------------------------------------------------------
    def view(self) -> GcuView:
        """What the bridge knows now."""
        client, session, executor = self.client, self.client.session, self.executor
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
            images_captured=executor.images, control=self._control,
            bridge_mode=executor.bridge_mode, pending_mode=executor.pending_mode,
            tracking_mode=executor.tracking_mode, tracking_box=executor.tracking_box,
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

    def reply(self, component: int, message: Any, origin: Origin) -> None:
        """Pack ``message`` as ``component`` and write it to the peer ``origin`` names alone
        (an answer is nobody else's business: on a shared ``udpin`` port, a flood's answers
        never reach a ground station, nor a spoofer's answers addressed with its ids)."""
        packer = self._packers[component]
        data = message.pack(packer)
        packer.seq = (packer.seq + 1) % 256
        self.stats["sent"] += 1
        link, peer = origin
        link.send_to(peer, data)

    def _ack(self, component: int, cmd: CommandIn, origin: Origin, result: int,
             param2: int = 0, progress: int = 0) -> None:  # fmt: skip
        """COMMAND_ACK to the sender, on the peer the command came from."""
        self.stats["acks"] += 1
        self.reply(component, mavlink.MAVLink_command_ack_message(
            cmd.command, result, progress, param2, *cmd.source), origin)

    def _log_answer(self, entry: admission.Entry, result: int, reason: str) -> None:
        """One rate-limited line naming the command, the sender and the answer."""
        assert entry.cmd is not None
        name = result_name(result)
        level = logging.WARNING if result in WARN_RESULTS else logging.INFO
        link, peer = entry.reply
        self._logs.log(level, name, "bridge: %s from %d/%d (%s): %s: %s",
                       command_name(entry.cmd.command), *entry.cmd.source,
                       link.peer_name(peer), name, reason)  # fmt: skip

    # -- receiving --------------------------------------------------------------------------
    def _on_message(self, link: MavlinkLink, peer: Peer, msg: Any) -> None:
        now = time.monotonic()
        link.note_message(now)
        self.stats["messages"] += 1
        try:
            self._handle((link, peer), msg, now)
        except Exception:  # hostile input must never stop the bridge
            self.stats["handler_errors"] += 1
            self._logs.log(logging.ERROR, "handler failure", "bridge: handling %s failed",
                           msg.get_type(), exc_info=True)  # fmt: skip

    def share_of(self, link: MavlinkLink, peer: Peer, now: float) -> admission.Share:
        """The :class:`~gcu_async.bridge.admission.Share` ``peer`` sends in: its own while
        the link says it holds one (a station), else the link's pool."""
        if link.own_share(peer, now):
            if peer.share is None:
                peer.share = admission.Share(link.peer_name(peer))
            share: admission.Share = peer.share
            return share
        if link.pool is None:
            link.pool = admission.Share(f"{link.url}, senders without a share")
        pool: admission.Share = link.pool
        return pool

    def shares(self) -> list[admission.Share]:
        """The shares in use: each link's pool and its stations' own (for inspection)."""
        pools = [link.pool for link in self.links if link.pool is not None]
        own = [peer.share for link in self.links for peer in link.destinations()
               if peer.share is not None]  # fmt: skip
        return [*pools, *own]

    def _handle(self, origin: Origin, msg: Any, now: float) -> None:
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
            share = self.share_of(*origin, now)
            if not share.budget.take(now):
                self.stats["shed"] += 1
                share.shed += 1
                self._logs.log(logging.WARNING, "shed command", "bridge: more than %g "
                               "commands/s from %s: %s dropped unanswered", share.budget.rate,
                               share.name, command_name(msg.command))  # fmt: skip
                return
            cmd = CommandIn.from_message(msg)
            assert cmd is not None
            for component in dispatch.components_for(cmd, self.system_id, self.camera):
                self._command(cmd, component, share, origin, now)
            return
        if kind in gimbal.CONTROL_MESSAGES:
            target = (msg.target_system, msg.target_component)
            if target[0] in (0, self.system_id) and target[1] in (0, gimbal.COMPONENT):
                self._coalesce_control(self.share_of(*origin, now), origin, msg, now)

    def _coalesce_control(self, share: admission.Share, origin: Origin, msg: Any,
                          now: float) -> None:  # fmt: skip
        """Keep the latest control message; take one per :data:`admission.CONTROL_INTERVAL`
        (a flood costs a store per message, not a mode change)."""
        self.stats["control_messages"] += 1
        if not self._control.allows((msg.get_srcSystem(), msg.get_srcComponent())):
            return  # another component holds control (checked here: before coalescing)
        if self._latest_control is not None:
            self.stats["control_coalesced"] += 1
        self._latest_control = (share, origin, msg)
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
        share, origin, msg = latest
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
        self._control_message(call, share, origin, now)

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

    def _control_message(self, call: GcuCall, share: admission.Share, origin: Origin,
                         now: float) -> None:  # fmt: skip
        """A gimbal control message's call: new control values apply at once while the GCU
        is ready and no pointing command waits; otherwise the call waits its turn in the
        pointing slot (the latest of its share replacing the one waiting), within
        :data:`~gcu_async.bridge.admission.COMMAND_WAIT` like a command."""
        immediate = call.method in admission.IMMEDIATE_CALLS
        waiting = any(e.slot == admission.POINTING for e in self.executor.queue)
        if immediate and not waiting and gcu_link.ready(self.client):
            try:
                getattr(self.client, call.method)(**call.kwargs)
            except ValueError as exc:
                self._logs.log(logging.INFO, "control message failure",
                               "bridge: %s failed: %s", call.method, exc)  # fmt: skip
            return
        entry = admission.Entry(None, gimbal.COMPONENT, share, now, admission.POINTING,
                                call=call, reply=origin)  # fmt: skip
        self.executor.admit(entry)

    def _command(self, cmd: CommandIn, component: int, share: admission.Share,
                 origin: Origin, now: float) -> None:  # fmt: skip
        self.stats["commands"] += 1
        memory = share.memory
        old = memory.find(cmd, component, now)
        if old is not None:  # a retransmission: answered, never run again
            self.stats["retransmissions"] += 1
            old.confirmation = max(old.confirmation, cmd.confirmation)
            if old.result is not None:
                self._ack(component, cmd, origin, old.result, old.param2)
                if old.result == ACCEPTED and dispatch.requested_id(cmd) is not None:
                    # its message may be what was lost: send it again (a request runs
                    # nothing on the GCU)
                    plan = dispatch.plan(cmd, component, self.view(), self.camera)
                    for reply in plan.replies:
                        self.reply(component, reply, origin)
            else:
                self._ack(component, cmd, origin, IN_PROGRESS, progress=255)
            return
        entry = admission.Entry(cmd, component, share, now, admission.SLOTS.get(cmd.command),
                                stop=admission.is_stop(cmd), reply=origin,
                                confirmation=cmd.confirmation)  # fmt: skip
        memory.add(entry, now)
        plan = dispatch.plan(cmd, component, self.view(), self.camera)
        if plan.call is None:
            self._answer_plan(entry, plan)
            return
        self.executor.admit(entry)

    def _answer_plan(self, entry: admission.Entry, plan: Plan) -> None:
        """Answer a command whose plan needs no GCU call (a refusal or a reply)."""
        assert plan.result is not None
        if plan.reason:
            self._log_answer(entry, plan.result, plan.reason)
        if plan.result == ACCEPTED:
            self._take(plan, entry.component)
        self.executor.finish(entry, plan.result)
        for reply in plan.replies:
            self.reply(entry.component, reply, entry.reply)

    def _take(self, plan: Plan, component: int) -> None:
        if plan.interval is not None:
            self.schedules[component].set(*plan.interval, time.monotonic())
        if plan.control is not None:
            self._control = plan.control
        if plan.camera_mode is not None:
            self._camera_mode = plan.camera_mode

    def _spawn(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def replace_camera(self, **changes: Any) -> None:
        """Change the :class:`CameraConfig` (e.g. ``video_url``) while running."""
        self.camera = replace(self.camera, **changes)
