"""The demo's script: the steps it runs on the GCU, each a few commands and the effect
they must show in the telemetry."""

from __future__ import annotations

import time

from gcu_async.cli.demo.engine import Step, StepEngine, StepFailed, angle_between, zoom_of
from gcu_async.cli.liveview import relative_attitude
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.client.waiting import ZOOM_TOLERANCE
from gcu_async.protocol.catalogue import RATE_LIMIT
from gcu_async.protocol.enums import Mode, Opcode
from gcu_async.protocol.units import wrap_degrees_180, wrap_degrees_360

TRACK_BOX = (0.56, 0.40, 0.66, 0.52)
"""Image box (left, top, right, bottom fractions) the demo tracks: right of centre."""


class Demo(StepEngine):
    """The scripted session on an open client; progress goes to ``console``."""

    async def step_follow(self) -> None:
        gcu = self.gcu
        await self.cmd("enter_pointing_follow()", gcu.enter_pointing_follow)
        await self.cmd("centre()", gcu.centre)

        def following(s: TelemetrySample) -> bool:
            att = s.status.attitude
            return (
                s.status.mode == Mode.POINTING_FOLLOW
                and abs(att.pitch) <= 1.0
                and angle_between(att.yaw, self.heading()) <= 3.0
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
        await self.cmd("enter_euler_control(pitch=-45)", lambda: self.gcu.enter_euler_control(
            pitch=-45.0, yaw=yaw))  # fmt: skip
        await self.expect_pose(Mode.EULER_CONTROL, pitch=-45.0, yaw=yaw)
        z0, h0 = relative_attitude(self.status()).yaw, self.heading()
        await self.hold(3.0, "holding the Euler angles while the aircraft turns")
        s = self.status()
        self.say(
            f"aircraft turned {wrap_degrees_180(self.heading() - h0):+.1f} deg, camera yaw "
            f"{s.attitude.yaw:.1f}, yaw relative to the aircraft {z0:+.1f} -> "
            f"{relative_attitude(s).yaw:+.1f}"
        )

    async def step_pan(self) -> None:
        # the rate limit shrinks with the zoom (150 / zoom deg/s): stay inside it
        info = self.gcu.info
        zoom = max(info.camera1_zoom, 1.0) if info is not None else 1.0
        rate = round(min(15.0 * self.speed, 90.0, 0.9 * RATE_LIMIT / zoom), 1)
        await self.cmd(f"enter_pointing_lock(yaw_rate={rate:g})",
                       lambda: self.gcu.enter_pointing_lock(yaw_rate=rate))  # fmt: skip
        yaw0 = self.status().attitude.yaw
        await self.expect(
            "a 30 deg pan",
            lambda s: (
                s.status.mode == Mode.POINTING_LOCK
                and angle_between(s.status.attitude.yaw, yaw0) >= 30.0
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
        await self.cmd("enter_top_down()", self.gcu.enter_top_down)
        await self.expect_pose(Mode.TOP_DOWN, pitch=-90.0, tolerance=0.5,
                               what="camera looking down")  # fmt: skip
        await self.hold(1.5, "looking straight down")

    async def _zoom_to(self, ratio: float) -> None:
        gcu = self.gcu
        start = self.info().camera1_zoom
        continuous = not self.supported(Opcode.ZOOM_TO)
        if continuous:
            call = gcu.zoom_in if ratio > start else gcu.zoom_out
            await self.cmd(f"{call.__name__}() (this pod has no zoom-to)", call)
        else:
            await self.cmd(f"zoom_to({ratio:g})", lambda: gcu.zoom_to(ratio))
        changed = [time.monotonic(), start]

        def settled(s: TelemetrySample) -> bool:
            zoom, now = zoom_of(s), time.monotonic()
            if abs(zoom - ratio) <= ZOOM_TOLERANCE:  # within the sub frame's step
                return True
            if zoom != changed[1]:
                changed[:] = [now, zoom]
            return zoom != start and now - changed[0] >= 1.0  # stopped at the camera's limit

        await self.expect(f"zoom {ratio:g}x", settled, lambda s: f"{zoom_of(s):.1f}x",
                          trace=lambda s: f"{zoom_of(s):.1f}x")  # fmt: skip
        if continuous:
            await self.cmd("stop_zoom()", gcu.stop_zoom)

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
        await self.cmd("enter_euler_control(pitch=-30)",
                       lambda: gcu.enter_euler_control(pitch=-30.0, yaw=yaw))  # fmt: skip
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
        await self.cmd("enter_pointing_follow()", gcu.enter_pointing_follow)
        await self.cmd("centre()", gcu.centre)
        await self.expect_pose(Mode.POINTING_FOLLOW, pitch=0.0, what="back to the start")

    def steps(self) -> list[Step]:
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
