"""``gcu-async demo``: a scripted session against the built-in simulator (or a real GCU).

By default a :class:`~gcu_async.sim.GcuSimulator` listens on an ephemeral loopback UDP port
in this process and the client connects to it over real UDP. While a slowly turning
aircraft is fed to the GCU, the script switches modes, slews, pans, zooms, takes a photo,
records, ranges and tracks a box, checking each effect in the telemetry; a live view shows
mode, attitude, zoom, flags and link health; a summary closes the run.

Exit status: 0 every step passed, 1 a step failed or no connection, 2 bad options,
130 interrupted (Ctrl-C / SIGTERM: the session closes cleanly and the summary so far is
printed).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import math
import os
import statistics
import sys
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from gcu_async.capture import CaptureUnavailable, PacketCapture, as_capture
from gcu_async.cli._exit import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    Interrupted,
    interruptible,
)
from gcu_async.cli.liveview import Console, LiveView
from gcu_async.client.api import RATE_LIMIT
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.errors import CommandFailed, CommandTimeout, GcuError, LinkLost
from gcu_async.protocol.enums import Mode, Opcode, PodModel, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.pods import POD_NAMES, pod_name, resolve_pod_model, supports
from gcu_async.protocol.units import GeoPosition, wrap_degrees_180, wrap_degrees_360
from gcu_async.sim.listen import ListenSpec, parse_listen_url
from gcu_async.sim.model import DEFAULT_POD
from gcu_async.sim.simulator import GcuSimulator

PROG = "gcu-async demo"
DEFAULT_LISTEN = "udp://127.0.0.1:0"
QUICK_SPEED = 10.0
MAX_SPEED = 1000.0
EXPECT_TIMEOUT = 10.0
"""Seconds an expected effect may take to show in the telemetry (physical, not scaled)."""
CONNECT_TIMEOUT = 3.0
TRACK_BOX = (0.56, 0.40, 0.66, 0.52)
"""Image box (left, top, right, bottom fractions) the demo tracks: right of centre."""


# -- options --------------------------------------------------------------------------------
def register(sub: Any) -> None:
    p = sub.add_parser(
        "demo",
        help="run a scripted session against a built-in simulator (or a real GCU)",
        description="Start a simulated GCU in this process on loopback, connect over real "
        "UDP and run a short scripted session: pointing-follow, Euler slew, pointing-lock "
        "pan, centre, top-down, zoom to 10x and back, photo, recording, laser ranging, "
        "tracking. A live view shows mode, attitude, zoom, flags and link health; a summary "
        "(commands, latency, packets, errors) closes the run. No hardware, no network "
        "beyond loopback.",
        epilog="Exit status: 0 all steps passed, 1 a step failed or no connection, 2 bad "
        "options, 130 interrupted (Ctrl-C or SIGTERM stop cleanly and print the summary so "
        "far). Against a real GCU over UDP the client binds local port 2338 unless the URL "
        "says otherwise (udp://HOST:PORT?local_port=0 picks a free one).",
    )
    p.add_argument("--url", metavar="URL",
                   help="drive an existing GCU or simulator instead of starting one: "
                   "udp://HOST[:PORT][?local_port=N], tcp://HOST[:PORT], "
                   "serial:///dev/ttyX[?baudrate=N]")  # fmt: skip
    p.add_argument("--listen", metavar="URL",
                   help=f"where the in-process simulator listens (default {DEFAULT_LISTEN}): "
                   "udp://HOST[:PORT], tcp://HOST[:PORT] or pty; port 0 = a free port")  # fmt: skip
    p.add_argument(
        "--pod",
        metavar="NAME",
        help=f"simulated pod model, Appendix 7 name or code (default {DEFAULT_POD})",
    )
    p.add_argument("--speed", metavar="FACTOR",
                   help="divide the script's pauses by FACTOR (default 1); the gimbal and zoom "
                   "still move at their own pace")  # fmt: skip
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"short pauses, same as --speed {QUICK_SPEED:g} (--speed wins)",
    )
    p.add_argument(
        "--no-live", action="store_true", help="no live status view, only the progress lines"
    )
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets the client exchanges to FILE (pcapng; open it in "
                   "Wireshark with the dissector: gcu-async wireshark --install)")  # fmt: skip
    p.set_defaults(run=run)


@dataclass(frozen=True)
class DemoOptions:
    url: str | None
    """``None``: start the simulator in-process."""
    listen: ListenSpec
    pod: PodModel
    speed: float
    live: str
    """``tty``, ``plain`` or ``off`` (see :class:`Console`)."""
    capture: PacketCapture | None = None
    """Where the client records its packets."""


def parse_options(args: argparse.Namespace, *, isatty: bool) -> DemoOptions:
    """Check the options; ``ValueError`` with a one-line reason for any problem."""
    if args.url is not None:
        for option, value in (("--listen", args.listen), ("--pod", args.pod)):
            if value is not None:
                raise ValueError(f"{option}: only for the in-process simulator, not with --url")
        try:
            connect(args.url)  # validates the URL and its options; opens nothing
        except ValueError as exc:
            raise ValueError(f"--url: {exc}") from None
    try:
        listen = parse_listen_url(args.listen if args.listen is not None else DEFAULT_LISTEN)
    except ValueError as exc:
        raise ValueError(f"--listen: {exc}") from None
    if listen.kind == "serial":
        raise ValueError(
            "--listen: a serial device would be shared by simulator and client; use pty, or "
            "run `gcu-async sim --listen serial://...` and `gcu-async demo --url serial://...`"
        )
    try:
        pod = resolve_pod_model(args.pod if args.pod is not None else DEFAULT_POD)
    except ValueError as exc:
        raise ValueError(f"--pod: {exc}") from None
    speed = QUICK_SPEED if args.quick else 1.0
    if args.speed is not None:
        try:
            speed = float(args.speed)
        except ValueError:
            raise ValueError(f"--speed: {args.speed!r} is not a number") from None
        if not 0 < speed <= MAX_SPEED:
            raise ValueError(f"--speed: {speed!r} is outside the allowed range (0, {MAX_SPEED:g}]")
    live = "off" if args.no_live else ("tty" if isatty else "plain")
    try:
        capture = as_capture(getattr(args, "capture", None))
    except (TypeError, CaptureUnavailable) as exc:
        raise ValueError(f"--capture: {exc}") from None
    return DemoOptions(args.url, listen, pod, speed, live, capture)


# -- the aircraft -----------------------------------------------------------------------------
@dataclass(frozen=True)
class FlightPath:
    """A level, coordinated right turn at constant speed (what the demo tells the GCU)."""

    start: GeoPosition = GeoPosition(22.5760, 113.9400, 150.0)
    heading: float = 30.0
    """Degrees at t = 0."""
    turn_rate: float = 3.0
    """Degrees per second (positive: to the right)."""
    speed: float = 12.0
    """Ground speed, m/s."""
    height: float = 120.0
    """Metres above the take-off point (sent as the relative altitude)."""
    pitch: float = 2.0

    def heading_at(self, t: float) -> float:
        return wrap_degrees_360(self.heading + self.turn_rate * t)

    def state_at(self, t: float) -> dict[str, Any]:
        """Keyword arguments for :meth:`GcuClient.update_aircraft` at ``t`` seconds."""
        w = math.radians(self.turn_rate)
        h0, h = math.radians(self.heading), math.radians(self.heading + self.turn_rate * t)
        v = self.speed
        north = v * t * math.cos(h0) if w == 0 else v / w * (math.sin(h) - math.sin(h0))
        east = v * t * math.sin(h0) if w == 0 else v / w * (math.cos(h0) - math.cos(h))
        lat, lon, alt = self.start
        bank = math.degrees(math.atan2(v * w, 9.80665))
        return {
            "attitude": (bank, self.pitch, self.heading_at(t)),
            "velocity": (v * math.cos(h), v * math.sin(h), 0.0),
            "acceleration": (-v * w * math.sin(h), v * w * math.cos(h), 0.0),  # centripetal
            "position": (
                lat + north / 111_320.0,
                lon + east / (111_320.0 * math.cos(math.radians(lat))),
                alt,
            ),
            "relative_altitude": self.height,
            "satellites": 18,
            "gnss_time": datetime.now(timezone.utc),
        }


async def fly(gcu: GcuClient, path: FlightPath, started: float, period: float = 0.1) -> None:
    """Keep the client's aircraft state on ``path`` (until cancelled)."""
    while True:
        gcu.update_aircraft(**path.state_at(time.monotonic() - started))
        await asyncio.sleep(period)


# -- the script -------------------------------------------------------------------------------
class StepFailed(Exception):
    """A command failed or an expected effect did not show: the step ends here."""


@dataclass
class Tally:
    """What the run did, for the summary."""

    steps_total: int = 0
    steps_ok: int = 0
    steps_failed: int = 0
    steps_skipped: int = 0
    commands_run: int = 0
    commands_failed: int = 0
    latencies: list[float] = field(default_factory=list)
    """Seconds from each command's call to its feedback (successful commands)."""
    aborted: str | None = None

    @property
    def ok(self) -> bool:
        return (
            self.aborted is None
            and not self.steps_failed
            and self.steps_ok + self.steps_skipped == self.steps_total
        )


def _angle(a: float, b: float) -> float:
    """Absolute difference of two angles, degrees (wrapped)."""
    return abs(wrap_degrees_180(a - b))


def _zoom(sample: TelemetrySample) -> float:
    return sample.info.camera1_zoom if sample.info is not None else 0.0


Predicate = Callable[[TelemetrySample], bool]
Describe = Callable[[TelemetrySample], str]


class Demo:
    """The scripted session on an open client; progress goes to ``console``."""

    def __init__(
        self, gcu: GcuClient, console: Console, speed: float, path: FlightPath, started: float
    ) -> None:
        self.gcu = gcu
        self.console = console
        self.speed = speed
        self.path = path
        self.started = started
        self.tally = Tally()
        self.pod: PodModel | None = None

    # -- helpers ------------------------------------------------------------------------------
    def say(self, text: str) -> None:
        self.console.line(f"        {text}")

    def heading(self) -> float:
        return self.path.heading_at(time.monotonic() - self.started)

    def supported(self, opcode: Opcode) -> bool:
        """Appendix 8 for the reported pod model (unknown models: assume yes)."""
        return self.pod is None or self.pod not in POD_NAMES or supports(self.pod, opcode)

    async def hold(self, seconds: float, why: str = "") -> None:
        pause = seconds / self.speed
        if why:
            self.say(f"{why} ({pause:.1f} s)")
        await asyncio.sleep(pause)

    async def cmd(self, label: str, call: Callable[[], Awaitable[Feedback | None]]) -> None:
        """Run one command, time it, report it; :class:`StepFailed` if it fails."""
        t0 = time.monotonic()
        try:
            feedback = await call()
        except (CommandFailed, CommandTimeout) as exc:
            self.tally.commands_run += 1
            self.tally.commands_failed += 1
            self.say(f"{label}: FAILED: {exc}")
            raise StepFailed(str(exc)) from None
        except LinkLost:
            self.tally.commands_run += 1
            self.tally.commands_failed += 1
            raise
        elapsed = time.monotonic() - t0
        if feedback is None:
            self.say(f"{label}: nothing to send (the camera flags say it is done already)")
            return
        self.tally.commands_run += 1
        self.tally.latencies.append(elapsed)
        self.say(f"{label}: ok in {elapsed * 1000:.1f} ms")

    async def expect(
        self,
        what: str,
        predicate: Predicate,
        describe: Describe,
        *,
        trace: Describe | None = None,
        timeout: float = EXPECT_TIMEOUT,
    ) -> TelemetrySample:
        """Wait until a telemetry sample satisfies ``predicate``; report what was seen
        (and the ``trace`` of values on the way). :class:`StepFailed` after ``timeout``."""
        t0 = time.monotonic()
        seen: list[str] = []
        last: list[TelemetrySample] = []

        async def first() -> TelemetrySample:
            stream = self.gcu.telemetry()
            next_trace = 0.0
            async with contextlib.aclosing(stream) as samples:
                async for sample in samples:
                    last[:] = [sample]
                    now = time.monotonic()
                    if trace is not None and now >= next_trace:
                        next_trace = now + 0.2
                        if not seen or seen[-1] != trace(sample):
                            seen.append(trace(sample))
                    if predicate(sample):
                        if trace is not None and (not seen or seen[-1] != trace(sample)):
                            seen.append(trace(sample))
                        return sample
            raise LinkLost("telemetry ended")

        task = asyncio.create_task(first())
        try:
            while not task.done():
                await asyncio.wait({task}, timeout=0.1)
                if task.done():
                    break
                if not self.gcu.link.up:
                    raise LinkLost("no telemetry: the link is down")
                if time.monotonic() - t0 >= timeout:
                    now = describe(last[0]) if last else "no telemetry"
                    self.say(f"expected {what}: NOT SEEN within {timeout:g} s (now: {now})")
                    raise StepFailed(f"{what} not seen")
        finally:
            if not task.done():
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
        sample = task.result()
        way = ""
        if len(seen) > 1:
            points = seen if len(seen) <= 8 else seen[:: math.ceil(len(seen) / 7)]
            if points[-1] is not seen[-1]:
                points.append(seen[-1])
            way = f" [{' -> '.join(points)}]"
        self.say(f"seen {what}: {describe(sample)} after {time.monotonic() - t0:.2f} s{way}")
        return sample

    def _pose(self, sample: TelemetrySample) -> str:
        att = sample.status.attitude
        return f"{sample.status.mode.name.lower()}, pitch {att.pitch:+.1f}, yaw {att.yaw:.1f}"

    async def expect_pose(
        self, mode: Mode, *, pitch: float | None = None, yaw: float | None = None,
        tolerance: float = 0.5, what: str = "the slew",
    ) -> TelemetrySample:  # fmt: skip
        """Wait for ``mode`` and the camera at ``pitch``/``yaw`` (absolute, degrees)."""

        def there(s: TelemetrySample) -> bool:
            att = s.status.attitude
            return (
                s.status.mode == mode
                and (pitch is None or abs(att.pitch - pitch) <= tolerance)
                and (yaw is None or _angle(att.yaw, yaw) <= tolerance)
            )

        return await self.expect(what, there, self._pose)

    # -- steps --------------------------------------------------------------------------------
    async def step_follow(self) -> None:
        gcu = self.gcu
        await self.cmd("pointing_follow()", gcu.pointing_follow)
        await self.cmd("centre()", gcu.centre)

        def following(s: TelemetrySample) -> bool:
            att = s.status.attitude
            return (
                s.status.mode == Mode.POINTING_FOLLOW
                and abs(att.pitch) <= 1.0
                and _angle(att.yaw, self.heading()) <= 3.0
            )

        await self.expect(
            "camera on the aircraft's heading",
            following,
            lambda s: f"{self._pose(s)} (aircraft heading {self.heading():.1f})",
        )
        await self.hold(1.5, "following the turning aircraft")

    async def step_euler(self) -> None:
        yaw = wrap_degrees_360(self.heading() + 40.0)
        self.say(f"target: pitch -45, yaw {yaw:.1f} (aircraft heading + 40)")
        await self.cmd("euler_control(pitch=-45)", lambda: self.gcu.euler_control(
            pitch=-45.0, yaw=yaw))  # fmt: skip
        await self.expect_pose(Mode.EULER_CONTROL, pitch=-45.0, yaw=yaw)
        z0, h0 = self.gcu.status.relative_angles.z, self.heading()
        await self.hold(3.0, "holding the Euler angles while the aircraft turns")
        s = self.gcu.status
        self.say(
            f"aircraft turned {wrap_degrees_180(self.heading() - h0):+.1f} deg, camera yaw "
            f"{s.attitude.yaw:.1f}, relative z {z0:+.1f} -> {s.relative_angles.z:+.1f}"
        )

    async def step_pan(self) -> None:
        # the rate limit shrinks with the zoom (150 / zoom deg/s): stay inside it
        info = self.gcu.info
        zoom = max(info.camera1_zoom, 1.0) if info is not None else 1.0
        rate = round(min(15.0 * self.speed, 90.0, 0.9 * RATE_LIMIT / zoom), 1)
        await self.cmd(f"pointing_lock(yaw_rate={rate:g})",
                       lambda: self.gcu.pointing_lock(yaw_rate=rate))  # fmt: skip
        yaw0 = self.gcu.status.attitude.yaw
        await self.expect(
            "a 30 deg pan",
            lambda s: (
                s.status.mode == Mode.POINTING_LOCK and _angle(s.status.attitude.yaw, yaw0) >= 30.0
            ),
            self._pose,
            trace=lambda s: f"{s.status.attitude.yaw:.0f}",
        )
        self.gcu.set_rates()
        self.say("rates 0: the camera holds its pointing")

    async def step_centre(self) -> None:
        await self.cmd("centre()", self.gcu.centre)
        await self.expect_pose(Mode.POINTING_LOCK, pitch=0.0, what="pitch back to 0")
        await self.hold(1.0)

    async def step_top_down(self) -> None:
        await self.cmd("top_down()", self.gcu.top_down)
        await self.expect_pose(Mode.TOP_DOWN, pitch=-90.0, tolerance=0.5,
                               what="camera looking down")  # fmt: skip
        await self.hold(1.5, "looking straight down")

    async def _zoom_to(self, ratio: float) -> None:
        gcu = self.gcu
        start = gcu.info.camera1_zoom
        continuous = not self.supported(Opcode.ZOOM_TO)
        if continuous:
            call = gcu.zoom_in if ratio > start else gcu.zoom_out
            await self.cmd(f"{call.__name__}() (this pod has no zoom-to)", call)
        else:
            await self.cmd(f"zoom_to({ratio:g})", lambda: gcu.zoom_to(ratio))
        changed = [time.monotonic(), start]

        def settled(s: TelemetrySample) -> bool:
            zoom, now = _zoom(s), time.monotonic()
            if abs(zoom - ratio) <= 0.06:  # the sub frame reports 0.1x steps
                return True
            if zoom != changed[1]:
                changed[:] = [now, zoom]
            return zoom != start and now - changed[0] >= 1.0  # stopped at the camera's limit

        await self.expect(f"zoom {ratio:g}x", settled, lambda s: f"{_zoom(s):.1f}x",
                          trace=lambda s: f"{_zoom(s):.1f}x")  # fmt: skip
        if continuous:
            await self.cmd("zoom_stop()", gcu.zoom_stop)

    async def step_zoom(self) -> None:
        await self._zoom_to(10.0)
        await self.hold(1.0, "zoomed in")
        await self._zoom_to(1.0)

    async def step_photo(self) -> None:
        await self.cmd("take_photo()", self.gcu.take_photo)
        await self.hold(0.5)

    async def step_record(self) -> None:
        gcu = self.gcu
        await self.cmd("start_recording()", gcu.start_recording)
        await self.expect("the recording flag", lambda s: s.info is not None and s.info.recording,
                          lambda s: "recording")  # fmt: skip
        await self.hold(3.0, "recording")
        await self.cmd("stop_recording()", gcu.stop_recording)
        await self.expect("the recording flag cleared",
                          lambda s: s.info is not None and not s.info.recording,
                          lambda s: "not recording")  # fmt: skip

    async def step_ranging(self) -> None:
        await self.cmd("set_ranging(True)", self.gcu.set_ranging)
        await self.expect(
            "a laser distance",
            lambda s: s.info is not None and s.info.target_distance is not None,
            lambda s: f"{s.info.target_distance:.1f} m" if s.info is not None else "-",
        )
        await self.hold(1.5, "ranging (the distance is in the live view)")

    async def step_track(self) -> None:
        gcu = self.gcu
        yaw = self.heading()
        await self.cmd("euler_control(pitch=-30)", lambda: gcu.euler_control(pitch=-30.0,
                                                                              yaw=yaw))  # fmt: skip
        await self.expect_pose(Mode.EULER_CONTROL, pitch=-30.0, yaw=yaw)
        await self.cmd(f"track({', '.join(f'{v:g}' for v in TRACK_BOX)})",
                       lambda: gcu.track(TRACK_BOX))  # fmt: skip
        await self.expect(
            "tracking",
            lambda s: s.status.mode == Mode.TRACK and s.status.tracking_ok,
            lambda s: f"{self._pose(s)}, miss x {s.status.miss_x} y {s.status.miss_y}",
        )
        await self.hold(3.0, "tracking the target while the aircraft flies on")
        await self.cmd("stop_tracking()", gcu.stop_tracking)
        await self.expect("tracking ended", lambda s: s.status.mode != Mode.TRACK, self._pose)

    async def step_finish(self) -> None:
        gcu = self.gcu
        if self.supported(Opcode.RANGING):
            await self.cmd("set_ranging(False)", lambda: gcu.set_ranging(False))
        await self.cmd("pointing_follow()", gcu.pointing_follow)
        await self.cmd("centre()", gcu.centre)
        await self.expect_pose(Mode.POINTING_FOLLOW, pitch=0.0, what="back to the start")

    def steps(self) -> list[tuple[str, tuple[Opcode, ...], Callable[[], Awaitable[None]]]]:
        """(title, opcodes the pod must support, step) in order."""
        return [
            ("pointing-follow, centred: the camera follows the aircraft", (), self.step_follow),
            ("Euler control: slew to pitch -45, yaw heading+40", (), self.step_euler),
            ("pointing-lock: pan right with a yaw rate", (), self.step_pan),
            ("centre", (), self.step_centre),
            ("top-down", (), self.step_top_down),
            ("zoom to 10x and back to 1x", (), self.step_zoom),
            ("take a photo", (), self.step_photo),
            ("start and stop recording", (), self.step_record),
            ("laser ranging on", (Opcode.RANGING,), self.step_ranging),
            ("track a box right of centre, then stop", (Opcode.TRACK,), self.step_track),
            ("back to pointing-follow, centred, ranging off", (), self.step_finish),
        ]

    async def prepare(self) -> None:
        """Start from the state the script assumes, whatever state the GCU is in: camera 1
        back at 1x (a GCU left zoomed in would cap the script's rates at 150 / zoom deg/s).
        A failure is reported and the script goes on (its rates follow the zoom)."""
        info = self.gcu.info
        if info is None or info.camera1_zoom <= 1.05:
            return
        self.console.line(f"[prep] camera 1 is at {info.camera1_zoom:.1f}x: back to 1x first "
                          f"(rates are limited to {RATE_LIMIT:g}/zoom deg/s)")  # fmt: skip
        try:
            await self._zoom_to(1.0)
        except StepFailed as exc:
            self.say(f"=> not at 1x ({exc}): the script goes on at this zoom")

    async def run(self) -> None:
        """Run every step; a failed step is reported and the next one runs, a lost link
        ends the script."""
        steps = self.steps()
        self.tally.steps_total = len(steps)
        try:
            await self.prepare()
        except LinkLost as exc:
            self.tally.aborted = f"link lost: {exc}"
            self.say(f"=> FAILED: link lost: {exc}")
            return
        for number, (title, needs, step) in enumerate(steps, 1):
            self.console.line(f"[{number:>2}/{len(steps)}] {title}")
            missing = [op for op in needs if not self.supported(op)]
            if missing and self.pod is not None:
                names = ", ".join(op.name.lower() for op in missing)
                self.say(f"=> skipped: {pod_name(self.pod)} does not support {names} "
                         "(Appendix 8)")  # fmt: skip
                self.tally.steps_skipped += 1
                continue
            t0 = time.monotonic()
            try:
                await step()
            except StepFailed as exc:
                self.tally.steps_failed += 1
                self.say(f"=> FAILED: {exc}")
                continue
            except LinkLost as exc:
                self.tally.steps_failed += 1
                self.tally.aborted = f"link lost: {exc}"
                self.say(f"=> FAILED: link lost: {exc}")
                return
            self.tally.steps_ok += 1
            self.say(f"=> ok ({time.monotonic() - t0:.1f} s)")


# -- the session ------------------------------------------------------------------------------
@dataclass
class Report:
    """What the session leaves for the summary (filled while it runs)."""

    started: float = field(default_factory=time.monotonic)
    url: str = ""
    sim: GcuSimulator | None = None
    gcu: GcuClient | None = None
    demo: Demo | None = None
    error: str | None = None


async def _session(opts: DemoOptions, console: Console, report: Report) -> None:
    async with contextlib.AsyncExitStack() as stack:
        options: dict[str, Any] = {}
        if opts.url is None:
            report.sim = sim = GcuSimulator(pod=opts.pod)
            server = await stack.enter_async_context(sim.serve(opts.listen))
            report.url = server.url
            if report.url.startswith("udp:"):
                options["local_port"] = 0
            console.line(f"simulator: {sim.model.profile.name} on {report.url} (in this process)")
        else:
            report.url = opts.url
        console.line(f"connecting to {report.url} ...")
        t0 = time.monotonic()
        gcu = connect(report.url, connect_timeout=CONNECT_TIMEOUT, capture=opts.capture,
                      **options)  # fmt: skip
        report.gcu = await stack.enter_async_context(gcu)
        path = FlightPath()
        started = time.monotonic()
        gcu.update_aircraft(**path.state_at(0.0))
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(_first_info(gcu), CONNECT_TIMEOUT)
        model = gcu.pod_model
        if model is None:
            pod = "pod unknown (no sub frame yet)"
        else:
            info = gcu.info
            pod = (f"pod {pod_name(model)}, hardware {info.hardware_version:g}, "
                   f"firmware {info.firmware_version:g}")  # fmt: skip
        console.line(f"connected in {(time.monotonic() - t0) * 1000:.0f} ms: {pod}")
        console.line(f"aircraft: {path.speed:g} m/s, turning {path.turn_rate:g} deg/s, "
                     f"{path.height:g} m up (INS + GNSS sent in every packet)")  # fmt: skip
        demo = Demo(gcu, console, opts.speed, path, started)
        demo.pod = model
        report.demo = demo
        flight = asyncio.create_task(fly(gcu, path, started), name="demo-aircraft")
        try:
            async with LiveView(gcu, console):
                await demo.run()
        finally:
            flight.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await flight
            gcu.release_control()


async def _first_info(gcu: GcuClient) -> None:
    stream = gcu.telemetry()
    async with contextlib.aclosing(stream) as samples:
        async for sample in samples:
            if sample.info is not None:
                return


def summary_lines(report: Report, interrupted: bool) -> list[str]:
    """The closing summary."""
    lines = ["", "summary"]
    demo = report.demo
    tally = demo.tally if demo is not None else Tally()
    if demo is None:
        lines.append("  steps:              none run (no session)")
    else:
        lines.append(
            f"  steps:              {tally.steps_ok} ok, {tally.steps_failed} failed, "
            f"{tally.steps_skipped} skipped, "
            f"{tally.steps_total - tally.steps_ok - tally.steps_failed - tally.steps_skipped} "
            f"not run (of {tally.steps_total})"
        )
    lines.append(f"  commands:           {tally.commands_run} run, "
                 f"{tally.commands_failed} failed")  # fmt: skip
    if tally.latencies:
        p50 = statistics.median(tally.latencies) * 1000
        lines.append(f"  latency:            p50 {p50:.1f} ms, max "
                     f"{max(tally.latencies) * 1000:.1f} ms")  # fmt: skip
    else:
        lines.append("  latency:            -")
    if report.gcu is not None:
        link = report.gcu.link
        lines.append(f"  packets:            {link.packets_sent} sent, "
                     f"{link.packets_received} received")  # fmt: skip
        lines.append(f"  crc errors:         {link.crc_errors}")
        lines.append(f"  unmatched feedback: {link.unmatched_feedback}")
        lines.append(f"  link lost:          {link.lost_count} times")
    if report.sim is not None:
        executions = report.sim.model.executions
        detail = ", ".join(f"{opcode_name(op).lower()} {n}" for op, n in sorted(executions.items()))
        lines.append(f"  sim executions:     {sum(executions.values())} ({detail or 'none'})")
    else:
        lines.append("  sim executions:     n/a (external GCU)")
    lines.append(f"  duration:           {time.monotonic() - report.started:.1f} s")
    if interrupted:
        result = "INTERRUPTED"
    elif report.error is not None:
        result = f"FAILED ({report.error})"
    elif not tally.ok:
        result = "FAILED" + (f" ({tally.aborted})" if tally.aborted else "")
    else:
        result = "OK"
    lines.append(f"result: {result}")
    return lines


async def _main(opts: DemoOptions) -> int:
    console = Console(sys.stdout, opts.live)
    report = Report()
    interrupted = False
    try:
        await interruptible(_session(opts, console, report))
    except Interrupted:
        interrupted = True
    except BrokenPipeError:
        raise
    except (LinkLost, GcuError, OSError) as exc:
        report.error = str(exc) or type(exc).__name__
        console.finish()
        print(f"{PROG}: {report.error}", file=sys.stderr)
    console.finish()
    if interrupted:
        console.line("interrupted: session closed")
    for line in summary_lines(report, interrupted):
        console.line(line)
    if interrupted:
        return EXIT_INTERRUPTED
    tally = report.demo.tally if report.demo is not None else Tally()
    return EXIT_OK if report.error is None and tally.ok and report.demo else EXIT_FAILED


def run(args: argparse.Namespace) -> int:
    try:
        opts = parse_options(args, isatty=sys.stdout.isatty())
    except ValueError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return asyncio.run(_main(opts))
    except KeyboardInterrupt:  # platforms without loop signal handlers
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # e.g. `gcu-async demo | head`: stop quietly
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_FAILED
