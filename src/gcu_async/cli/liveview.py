"""A live status line for interactive CLI sessions (used by ``gcu-async demo``).

:class:`Console` owns the output: progress lines go through :meth:`Console.line`; the status
line is redrawn in place (``\\r`` + ANSI clear-line) on a terminal, printed as plain periodic
lines otherwise (CI logs stay readable), or not shown at all. :class:`LiveView` is the task
that feeds it from :meth:`GcuClient.telemetry`.
"""

from __future__ import annotations

import asyncio
import contextlib
import shutil
import time
from typing import TextIO

from gcu_async.client.client import GcuClient
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.protocol.enums import CameraFlags, PodStatus
from gcu_async.protocol.gcu_frames import GcuMainFrame
from gcu_async.protocol.units import Attitude
from gcu_async.session import LinkHealth

CLEAR_LINE = "\r\x1b[2K"
LIVE_MODES = ("tty", "plain", "off")

_POD_FLAGS = (
    (PodStatus.TRACKING_OK, "tracking"),
    (PodStatus.RANGING_ON, "ranging"),
    (PodStatus.NIGHT_VISION_ON, "night"),
    (PodStatus.FILL_LIGHT_ON, "light"),
    (PodStatus.INVERTED, "inverted"),
)
_CAMERA_FLAGS = (
    (CameraFlags.RECORDING, "REC"),
    (CameraFlags.DIGITAL_ZOOM_ON, "dzoom"),
    (CameraFlags.TARGET_DETECTION_ON, "ai"),
)


def relative_attitude(status: GcuMainFrame) -> Attitude:
    """The camera's roll, pitch and yaw relative to the aircraft, degrees, from the main
    frame's relative axis angles (``relative_angles``): roll = Y, pitch = −X, yaw = Z, as the
    protocol's example packet shows (relative X −8.03° with a camera pitch of 9.33°)."""
    rel = status.relative_angles
    return Attitude(rel.y, -rel.x if rel.x else 0.0, rel.z)


def format_status(sample: TelemetrySample | None, link: LinkHealth) -> str:
    """One compact status line: the GCU main frame's mode, camera attitude, attitude
    relative to the aircraft (:func:`relative_attitude`) and pod status flags, the sub
    frame's camera-1 zoom, camera flags and laser distance, and link health."""
    parts: list[str] = []
    if sample is None:
        parts.append("waiting for telemetry")
    else:
        st, info = sample.status, sample.info
        att, rel = st.attitude, relative_attitude(st)
        parts.append(f"{st.mode.name.lower():<15}")
        parts.append(f"cam r{att.roll:+6.1f} p{att.pitch:+6.1f} y{att.yaw:5.1f}")
        parts.append(f"vs aircraft r{rel.roll:+6.1f} p{rel.pitch:+6.1f} y{rel.yaw:+6.1f}")
        flags = [name for bit, name in _POD_FLAGS if bit & st.pod_status]
        if info is not None:
            parts.append(f"zoom {info.camera1_zoom:4.1f}x")
            flags += [name for bit, name in _CAMERA_FLAGS if bit & info.camera_flags]
            if info.target_distance is not None:
                flags.append(f"{info.target_distance:.1f}m")
        parts.append(f"[{' '.join(flags)}]")
    state = "up" if link.up else "DOWN"
    parts.append(
        f"link {state} {link.reply_rate:.0f}/s crc {link.crc_errors} lost {link.lost_count}"
    )
    return " | ".join(parts)


class Console:
    """Progress lines plus an optional status line, on one text stream.

    ``mode``: ``"tty"`` redraws the status line in place, ``"plain"`` prints it as its own
    line at most every ``plain_interval`` seconds, ``"off"`` drops it.
    """

    def __init__(self, stream: TextIO, mode: str, *, plain_interval: float = 1.0) -> None:
        if mode not in LIVE_MODES:
            raise ValueError(f"mode: {mode!r} is not one of {', '.join(LIVE_MODES)}")
        self.stream = stream
        self.mode = mode
        self.plain_interval = plain_interval
        self._status = ""
        self._last_plain = -float("inf")

    def line(self, text: str) -> None:
        """Print a progress line (above the status line on a terminal)."""
        if self.mode == "tty" and self._status:
            self.stream.write(CLEAR_LINE + text + "\n" + self._status)
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def status(self, text: str) -> None:
        """Show ``text`` as the current status."""
        if self.mode == "tty":
            width = shutil.get_terminal_size((120, 24)).columns
            self._status = text[: max(width - 1, 20)]
            self.stream.write(CLEAR_LINE + self._status)
            self.stream.flush()
        elif self.mode == "plain":
            now = time.monotonic()
            if now - self._last_plain >= self.plain_interval:
                self._last_plain = now
                self.stream.write(f"  live: {text}\n")
                self.stream.flush()

    def finish(self) -> None:
        """Remove the status line (terminal) so what follows starts on a clean line."""
        if self.mode == "tty" and self._status:
            self.stream.write(CLEAR_LINE)
            self.stream.flush()
        self._status = ""


class LiveView:
    """Feeds a :class:`Console` from a client's telemetry about ``rate_hz`` times a second.

    One task reads :meth:`GcuClient.telemetry` and keeps the newest sample; a second redraws
    on a timer, so link health (e.g. "DOWN") still updates when replies stop.
    """

    def __init__(self, gcu: GcuClient, console: Console, *, rate_hz: float = 8.0) -> None:
        if not rate_hz > 0:
            raise ValueError(f"rate_hz: {rate_hz!r} must be > 0")
        self.gcu = gcu
        self.console = console
        self.period = 1.0 / rate_hz
        self.latest: TelemetrySample | None = None
        self.samples = 0
        self._tasks: list[asyncio.Task[None]] = []

    async def __aenter__(self) -> LiveView:
        if self.console.mode != "off":
            self._tasks = [
                asyncio.create_task(self._read(), name="live-read"),
                asyncio.create_task(self._draw(), name="live-draw"),
            ]
        return self

    async def __aexit__(self, *exc: object) -> None:
        tasks, self._tasks = self._tasks, []
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self.console.finish()

    async def _read(self) -> None:
        stream = self.gcu.telemetry()
        async with contextlib.aclosing(stream) as samples:
            async for sample in samples:
                self.latest = sample
                self.samples += 1

    async def _draw(self) -> None:
        while True:
            if self.latest is not None:
                self.console.status(format_status(self.latest, self.gcu.link))
            await asyncio.sleep(self.period)
