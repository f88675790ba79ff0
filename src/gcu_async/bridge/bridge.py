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
import time
from collections.abc import Sequence
from dataclasses import replace
from types import TracebackType
from typing import Any

from gcu_async.bridge import camera, dispatch, gimbal, streams
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.autopilot import AutopilotFeed
from gcu_async.bridge.camera import CameraConfig
from gcu_async.bridge.commands import (
    ACCEPTED,
    FAILED,
    IN_PROGRESS,
    CommandIn,
    GcuCall,
    Plan,
    result_for,
)
from gcu_async.bridge.links import MavlinkLink, make_link
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
        self._inflight: set[tuple[tuple[int, int], int, int]] = set()
        self._tasks: set[asyncio.Task[Any]] = set()
        self._main: asyncio.Task[None] | None = None
        self._aircraft_errors: set[str] = set()
        self.stats = {"commands": 0, "acks": 0, "sent": 0, "handler_errors": 0}

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

    async def close(self) -> None:
        """Stop streaming, cancel running commands, close the links (at once, whatever
        they are doing; :mod:`~gcu_async.bridge.links`) and the client."""
        tasks = [t for t in (self._main, *self._tasks) if t is not None]
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        self._main = None
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
    def send(self, component: int, message: Any) -> None:
        """Pack ``message`` as ``component`` of this system and write it to every link."""
        packer = self._packers[component]
        data = message.pack(packer)
        packer.seq = (packer.seq + 1) % 256
        self.stats["sent"] += 1
        for link in self.links:
            link.send(data)

    def _heartbeat(self, now: float) -> None:
        view = self.view()
        self.send(gimbal.COMPONENT, gimbal.heartbeat(view, mavlink.MAV_TYPE_GIMBAL))
        self.send(camera.COMPONENT, gimbal.heartbeat(view, mavlink.MAV_TYPE_CAMERA))
        for link in self.links:
            link.check_silence(now)

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

    def _ack(self, component: int, cmd: CommandIn, result: int, param2: int = 0,
             progress: int = 0) -> None:  # fmt: skip
        self.stats["acks"] += 1
        self.send(component, mavlink.MAVLink_command_ack_message(
            cmd.command, result, progress, param2, *cmd.source))

    # -- receiving --------------------------------------------------------------------------
    def _on_message(self, link: MavlinkLink, msg: Any) -> None:
        now = time.monotonic()
        link.note_message(now)
        try:
            self._handle(msg, now)
        except Exception:  # hostile input must never stop the bridge
            self.stats["handler_errors"] += 1
            log.exception("bridge: handling %s failed", msg.get_type())

    def _handle(self, msg: Any, now: float) -> None:
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if source[0] == self.system_id and source[1] in dispatch.COMPONENTS:
            return  # our own messages echoed by a router
        if self.autopilot.accepts(msg):
            self._aircraft(msg, now)
        cmd = CommandIn.from_message(msg)
        if cmd is not None:
            for component in dispatch.components_for(cmd, self.system_id, self.camera):
                self._command(cmd, component)
            return
        target = (getattr(msg, "target_system", 0), getattr(msg, "target_component", 0))
        if target[0] in (0, self.system_id) and target[1] in (0, gimbal.COMPONENT):
            try:
                call = gimbal.message_call(msg, self.view())
            except ValueError as exc:
                log.warning("bridge: %s ignored: %s", msg.get_type(), exc)
                return
            if call is not None:
                self._spawn(self._message_call(msg.get_type(), call))

    def _aircraft(self, msg: Any, now: float) -> None:
        kind = msg.get_type()
        try:
            changes = self.autopilot.update(msg, now)
            if changes:
                self.client.update_aircraft(**changes)
        except (ValueError, TypeError) as exc:
            if kind not in self._aircraft_errors:
                self._aircraft_errors.add(kind)
                log.warning("bridge: autopilot %s not used: %s", kind, exc)
            return
        self._aircraft_errors.discard(kind)

    def _command(self, cmd: CommandIn, component: int) -> None:
        self.stats["commands"] += 1
        key = (cmd.source, component, cmd.command)
        if key in self._inflight:  # a retransmission of a command still running
            self._ack(component, cmd, IN_PROGRESS, progress=255)
            return
        plan = dispatch.plan(cmd, component, self.view(), self.camera)
        if plan.call is None:
            assert plan.result is not None
            if plan.reason:
                log.info("bridge: command %d refused (%d): %s", cmd.command, plan.result,
                         plan.reason)  # fmt: skip
            if plan.result == ACCEPTED:
                self._take(plan, component)
            self._ack(component, cmd, plan.result)
            for reply in plan.replies:
                self.send(component, reply)
            return
        self._inflight.add(key)
        self._spawn(self._command_call(cmd, component, plan, key))

    def _take(self, plan: Plan, component: int) -> None:
        if plan.interval is not None:
            self.schedules[component].set(*plan.interval, time.monotonic())
        if plan.control is not None:
            self._control = plan.control
        if plan.camera_mode is not None:
            self._camera_mode = plan.camera_mode

    async def _command_call(self, cmd: CommandIn, component: int, plan: Plan,
                            key: tuple[tuple[int, int], int, int]) -> None:  # fmt: skip
        assert plan.call is not None
        loop = asyncio.get_running_loop()
        timer = loop.call_later(self.in_progress_after, self._ack, component, cmd,
                                IN_PROGRESS, 0, 255)  # fmt: skip
        error: BaseException | None = None
        try:
            await self._execute(plan.call)
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            error = exc
        finally:
            timer.cancel()
            self._inflight.discard(key)
        try:
            result, param2 = result_for(error)
        except Exception:
            log.exception("bridge: command %d failed unexpectedly", cmd.command)
            result, param2 = FAILED, -1
        if error is not None:
            log.info("bridge: command %d -> %d: %s", cmd.command, result, error)
        self._ack(component, cmd, result, param2)
        if result == ACCEPTED and plan.call.then == "image_captured":
            view = self.view()
            self.send(camera.COMPONENT, camera.image_captured(view, self._images))
            self._images += 1

    async def _message_call(self, kind: str, call: GcuCall) -> None:
        try:
            await self._execute(call)
        except Exception as exc:
            log.warning("bridge: %s -> %s failed: %s", kind, call.method, exc)

    async def _execute(self, call: GcuCall) -> None:
        method = getattr(self.client, call.method)
        if call.mode is not None:
            self._pending_mode = call.mode
        try:
            result = method(**call.kwargs)
            if inspect.isawaitable(result):
                await result
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
