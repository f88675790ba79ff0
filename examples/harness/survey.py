"""A user's app: a photo survey with the camera looking straight down.

:func:`run_survey` takes an open :class:`~gcu_async.GcuClient` and

1. switches the pod to top-down mode (0x13) and waits for the camera to reach −90° pitch;
2. zooms to ``zoom`` (0x25) and waits for the ratio — a pod that cannot (its GCU answers
   with a failure, or the client refuses with ``check_support=True``) shoots at 1×;
3. takes ``photos`` photos (0x20), one every ``interval`` seconds;

and returns a :class:`SurveyReport`. The link is expected to be imperfect: a command that
times out is repeated, and when the link to the GCU is lost the survey waits (up to
``reconnect_timeout`` s) for it to come back and carries on; if it does not, the survey
stops and says so in the report instead of raising. Only *confirmed* photos are counted.

Run it against the simulator or a real GCU::

    python examples/harness/survey.py --gcu udp://127.0.0.1:2337?local_port=0 --photos 5
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TypeVar

from gcu_async import (
    CommandFailed,
    CommandLinkLost,
    CommandTimeout,
    GcuClient,
    LinkLost,
    Mode,
    Outcome,
    UnsupportedCommandError,
    connect,
)
from gcu_async.transport import LinkEvent, LinkEventKind

log = logging.getLogger("survey")

T = TypeVar("T")
SETTLED_PITCH = -89.0
"""Top-down is reached when the camera's absolute pitch is below this, degrees."""
ZOOM_TOLERANCE = 0.1


class SurveyAborted(Exception):
    """The link did not come back in time (internal: turned into the report)."""


@dataclass
class SurveyReport:
    """What a survey achieved."""

    photos_requested: int
    photos_taken: int = 0
    """Photos the GCU confirmed."""
    zoom: float | None = None
    """Zoom ratio the photos were taken at (``None``: the pod could not zoom; 1×)."""
    link_losses: int = 0
    """Times the link was lost and the survey waited for it."""
    retries: int = 0
    """Commands repeated after a timeout."""
    repeated_unknown: int = 0
    """Times the link was lost while a command was on the wire (outcome unknown): it may have
    run, and the survey runs it again, so a photo more than asked is possible."""
    completed: bool = False
    notes: list[str] = field(default_factory=list)


async def run_survey(
    gcu: GcuClient,
    *,
    photos: int = 5,
    interval: float = 0.5,
    zoom: float = 2.0,
    attempts: int = 3,
    reconnect_timeout: float = 5.0,
    settle_timeout: float = 5.0,
) -> SurveyReport:
    """Fly a survey with ``gcu`` (see the module docstring); never raises for link or
    command trouble — the report tells what happened."""
    if photos < 0 or interval < 0 or attempts < 1:
        raise ValueError("photos and interval must be >= 0, attempts >= 1")
    report = SurveyReport(photos_requested=photos)
    step = _Steps(gcu, report, attempts, reconnect_timeout)
    try:
        await step.run("top-down", gcu.enter_top_down)
        if not await _settle(gcu, lambda: _looking_down(gcu), settle_timeout):
            report.notes.append("camera did not reach -90° pitch in time")
        try:
            await step.run("zoom", lambda: gcu.zoom_to(zoom))
        except (CommandFailed, UnsupportedCommandError) as exc:
            report.notes.append(f"zoom not available on this pod ({exc}): photos at 1x")
        else:
            report.zoom = zoom
            if not await _settle(gcu, lambda: _zoomed(gcu, zoom), settle_timeout):
                report.notes.append(f"zoom did not reach {zoom:g}x in time")
        for n in range(photos):
            if n:
                await asyncio.sleep(interval)
            await step.run(f"photo {n + 1}", gcu.take_photo)
            report.photos_taken += 1
    except SurveyAborted as exc:
        report.notes.append(str(exc))
        return report
    except CommandFailed as exc:
        report.notes.append(f"GCU refused: {exc}")
        return report
    report.completed = True
    return report


class _Steps:
    """Runs one command with the survey's link/timeout policy."""

    def __init__(
        self, gcu: GcuClient, report: SurveyReport, attempts: int, reconnect_timeout: float
    ) -> None:
        self.gcu = gcu
        self.report = report
        self.attempts = attempts
        self.reconnect_timeout = reconnect_timeout

    async def run(self, name: str, call: Callable[[], Awaitable[T]]) -> T:
        for attempt in range(1, self.attempts + 1):
            try:
                return await call()
            except CommandTimeout:
                log.warning("%s: no answer (attempt %d of %d)", name, attempt, self.attempts)
                self.report.retries += 1
            except LinkLost as exc:
                self.report.link_losses += 1
                if isinstance(exc, CommandLinkLost) and exc.outcome is Outcome.UNKNOWN:
                    self.report.repeated_unknown += 1
                log.warning("%s: link lost (%s); waiting for the GCU", name, exc)
                if not await wait_for_link(self.gcu, self.reconnect_timeout):
                    raise SurveyAborted(
                        f"{name}: link lost and not back within {self.reconnect_timeout:g} s"
                    ) from exc
        raise SurveyAborted(f"{name}: no answer after {self.attempts} attempts")


async def wait_for_link(gcu: GcuClient, timeout: float) -> bool:
    """Wait until the link to the GCU is up again; False after ``timeout`` seconds."""
    restored = asyncio.Event()

    def on_change(event: LinkEvent) -> None:
        if event.kind is LinkEventKind.RESTORED:
            restored.set()

    unsubscribe = gcu.on_link_change(on_change)
    try:
        if gcu.link.up:
            return True
        await asyncio.wait_for(restored.wait(), timeout)
        return True
    except asyncio.TimeoutError:
        return False
    finally:
        unsubscribe()


def _looking_down(gcu: GcuClient) -> bool:
    return gcu.status is not None and gcu.status.attitude.pitch < SETTLED_PITCH


def _zoomed(gcu: GcuClient, zoom: float) -> bool:
    return gcu.info is not None and abs(gcu.info.camera1_zoom - zoom) < ZOOM_TOLERANCE


async def _settle(gcu: GcuClient, reached: Callable[[], bool], timeout: float) -> bool:
    """Poll the GCU's telemetry until ``reached()``; False after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while not reached():
        if time.monotonic() > deadline:
            return False
        await asyncio.sleep(0.05)
    return True


async def _main(args: argparse.Namespace) -> int:
    async with connect(args.gcu) as gcu:
        report = await run_survey(gcu, photos=args.photos, interval=args.interval, zoom=args.zoom)
        mode = gcu.status.mode if gcu.status is not None else Mode.UNKNOWN
    print(report)
    print(f"pod mode at the end: {mode.name}")
    return 0 if report.completed and mode is Mode.TOP_DOWN else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Photo survey, camera looking down.")
    parser.add_argument("--gcu", default="udp://127.0.0.1:2337", help="GCU URL")
    parser.add_argument("--photos", type=int, default=5)
    parser.add_argument("--interval", type=float, default=0.5, help="seconds between photos")
    parser.add_argument("--zoom", type=float, default=2.0, help="zoom ratio")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    try:
        return asyncio.run(_main(args))
    except LinkLost as exc:
        print(f"cannot reach the GCU: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
