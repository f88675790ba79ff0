"""The demo's step engine: run steps in order, time and count their commands, wait for
their effects in the telemetry, and keep the tally the summary reports."""

from __future__ import annotations

import abc
import asyncio
import contextlib
import math
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field

from gcu_async.cli.demo.flight import FlightPath
from gcu_async.cli.liveview import Console
from gcu_async.client.client import GcuClient
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.errors import CommandFailed, CommandTimeout, LinkLost
from gcu_async.protocol.enums import Mode, Opcode, PodModel
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.pods import POD_NAMES, pod_name, supports
from gcu_async.protocol.units import wrap_degrees_180

EXPECT_TIMEOUT = 10.0
"""Seconds an expected effect may take to show in the telemetry (physical, not scaled)."""

Step = tuple[str, tuple[Opcode, ...], Callable[[], Awaitable[None]]]
"""(title, opcodes the pod must support, the step)."""


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


def angle_between(a: float, b: float) -> float:
    """Absolute difference of two angles, degrees (wrapped)."""
    return abs(wrap_degrees_180(a - b))


def zoom_of(sample: TelemetrySample) -> float:
    return sample.info.camera1_zoom if sample.info is not None else 0.0


Predicate = Callable[[TelemetrySample], bool]
Describe = Callable[[TelemetrySample], str]

class StepEngine(abc.ABC):
    """Runs a script of steps on an open client: each step's commands are timed and
    counted, each expected effect is waited for in the telemetry, progress goes to
    ``console`` and the counts to :attr:`tally`. A subclass gives the steps."""

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

    def say(self, text: str) -> None:
        self.console.line(f"        {text}")

    def heading(self) -> float:
        return self.path.heading_at(time.monotonic() - self.started)

    def status(self) -> GcuMainFrame:
        """The latest main frame (:class:`StepFailed` before the first reply)."""
        status = self.gcu.status
        if status is None:
            raise StepFailed("no reply from the GCU yet")
        return status

    def info(self) -> GcuSubFrame:
        """The latest sub frame (:class:`StepFailed` before the first one)."""
        info = self.gcu.info
        if info is None:
            raise StepFailed("no sub frame from the GCU yet")
        return info

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
                and (yaw is None or angle_between(att.yaw, yaw) <= tolerance)
            )

        return await self.expect(what, there, self._pose)

    @abc.abstractmethod
    def steps(self) -> list[Step]:
        """(title, opcodes the pod must support, step) in order."""

    @abc.abstractmethod
    async def prepare(self) -> None:
        """Bring the GCU to the state the steps assume (reported; a failure does not end
        the run)."""

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

