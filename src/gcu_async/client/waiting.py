"""Waiting for the physical world: telemetry predicates, closed-loop moves, the link
(docs/client.md, "Waiting for the gimbal, the zoom and the link").

A command's feedback says the GCU *took* it; the gimbal then needs time to slew and the
lens to zoom. These methods wait on telemetry for the result, always with a timeout, and
raise :class:`~gcu_async.errors.WaitTimeout` naming what was awaited and the last value
seen. They keep waiting through a link outage (no telemetry arrives, the timeout runs on)
and raise :class:`~gcu_async.errors.LinkLost` when the client closes or fails.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import deque
from collections.abc import AsyncGenerator, Callable

from gcu_async._checks import check_bool, check_positive, check_real, type_error
from gcu_async.client.driver import ENDED, Driver
from gcu_async.client.telemetry import Callbacks, Telemetry
from gcu_async.errors import LinkLost, WaitTimeout
from gcu_async.protocol.builder import build
from gcu_async.protocol.catalogue import BY_METHOD
from gcu_async.protocol.fields import CAMERA_ZOOM
from gcu_async.protocol.host_frame_tables import ZOOM_MAX
from gcu_async.protocol.units import wrap_degrees_180
from gcu_async.session import SessionState, TelemetrySample
from gcu_async.transport.base import LinkEvent

Predicate = Callable[[TelemetrySample], bool]

WAIT_TIMEOUT = 10.0
"""Default seconds for a wait (a full slew of a large pod takes a few seconds)."""
ANGLE_TOLERANCE = 0.5
"""Default degrees between the reported and the target angle that count as there."""
ZOOM_TOLERANCE = CAMERA_ZOOM.from_raw(1) / 2
"""Default zoom-ratio difference that counts as there: half the step the sub frame reports
its zoom in."""
LINK_EVENTS_MAX = 256
"""Link events kept for a slow ``link_events()`` consumer (the oldest go first)."""


def angle_error(a: float, b: float) -> float:
    """Absolute difference of two angles in degrees, the short way round (0…180)."""
    return abs(wrap_degrees_180(a - b))


def _attitude_targets(roll: float | None, pitch: float | None,
                      yaw: float | None) -> dict[str, float]:  # fmt: skip
    """The angles given, checked against the ranges :meth:`enter_euler_control` takes (the
    command catalogue's)."""
    euler = BY_METHOD["enter_euler_control"]
    given = {"roll": roll, "pitch": pitch, "yaw": yaw}
    out = {}
    for name, value in given.items():
        if value is None:
            continue
        p = euler.parameter(name)
        assert p.low is not None
        assert p.high is not None
        out[name] = check_real(name, value, p.low, p.high, p.unit, high_open=p.high_open)
    return out


class Waiting:
    """Waits on telemetry and the link (the client's waiting part): it reads the driver's
    session, subscribes to its telemetry and link events, and sends the closed-loop moves'
    commands through the driver."""

    def __init__(self, driver: Driver, telemetry: Telemetry, links: Callbacks[LinkEvent]) -> None:
        self._driver = driver
        self._telemetry = telemetry
        self._links = links

    def _closed(self) -> asyncio.Event | None:
        return self._driver.closed()

    def _latest(self) -> TelemetrySample | None:
        return self._driver.session.latest

    def _link_up(self) -> bool:
        return self._driver.session.state is SessionState.UP

    def _ended(self, what: str) -> str:
        """Why a wait for ``what`` ended without it: the client closed, or failed."""
        failure = self._driver.failure
        if failure is not None:
            return f"the client failed ({failure}) while waiting for {what}"
        return f"the client closed while waiting for {what}"

    # -- telemetry -------------------------------------------------------------------------
    async def wait_for(self, predicate: Predicate, *, timeout: float = WAIT_TIMEOUT,
                       what: str = "the condition") -> TelemetrySample:  # fmt: skip
        """See :meth:`GcuClient.wait_for <gcu_async.client.GcuClient.wait_for>`."""
        if not callable(predicate):
            raise type_error("predicate", "a callable taking a TelemetrySample", predicate)
        timeout = check_positive("timeout", timeout)
        if not isinstance(what, str):
            raise type_error("what", "a str", what)
        closed = self._closed()
        if closed is None or closed.is_set():
            raise LinkLost(self._driver.not_open())
        latest = self._latest()  # a reply from before an outage is no evidence of now
        if latest is not None and self._link_up() and predicate(latest):
            return latest
        last: list[TelemetrySample | None] = [latest]

        async def first() -> TelemetrySample:
            samples_ = self._telemetry.samples(1, self._driver.state in ENDED)
            async with contextlib.aclosing(samples_) as samples:
                async for sample in samples:
                    last[0] = sample
                    if predicate(sample):
                        return sample
            raise LinkLost(self._ended(what))

        try:
            return await asyncio.wait_for(first(), timeout)
        except asyncio.TimeoutError:
            raise WaitTimeout(what, timeout, last[0]) from None

    async def wait_attitude(self, *, roll: float | None = None, pitch: float | None = None,
                            yaw: float | None = None, tolerance: float = ANGLE_TOLERANCE,
                            timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """See :meth:`GcuClient.wait_attitude <gcu_async.client.GcuClient.wait_attitude>`."""
        given = _attitude_targets(roll, pitch, yaw)
        tol = check_positive("tolerance", tolerance, unit="deg")
        if not given:
            raise ValueError("wait_attitude: give at least one of roll, pitch, yaw")

        def there(sample: TelemetrySample) -> bool:
            attitude = sample.status.attitude._asdict()
            return all(angle_error(attitude[k], v) <= tol for k, v in given.items())

        what = "attitude " + ", ".join(f"{k} {v:g}" for k, v in given.items())
        return await self.wait_for(there, timeout=timeout, what=f"{what} (±{tol:g} deg)")

    async def wait_zoom(self, ratio: float, *, tolerance: float = ZOOM_TOLERANCE,
                        timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """See :meth:`GcuClient.wait_zoom <gcu_async.client.GcuClient.wait_zoom>`."""
        target = check_real("ratio", ratio, 1.0, ZOOM_MAX, "x")
        tol = check_positive("tolerance", tolerance, unit="x")

        def there(sample: TelemetrySample) -> bool:
            info = sample.info
            return info is not None and abs(info.camera1_zoom - target) <= tol

        return await self.wait_for(there, timeout=timeout,
                                   what=f"zoom {target:g}x (±{tol:g})")  # fmt: skip

    # -- closed-loop moves -----------------------------------------------------------------
    async def reach_attitude(self, *, roll: float | None = None, pitch: float | None = None,
                             yaw: float | None = None, tolerance: float = ANGLE_TOLERANCE,
                             timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """See :meth:`GcuClient.reach_attitude <gcu_async.client.GcuClient.reach_attitude>`."""
        _attitude_targets(roll, pitch, yaw)  # all checked before anything is sent
        check_positive("timeout", timeout)
        check_positive("tolerance", tolerance, unit="deg")
        current = self._driver.status().attitude
        r = current.roll if roll is None else roll
        p = current.pitch if pitch is None else pitch
        y = current.yaw if yaw is None else yaw
        driver = self._driver
        await driver.run(build("enter_euler_control", driver.context(), roll=r, pitch=p, yaw=y))
        return await self.wait_attitude(roll=r, pitch=p, yaw=y, tolerance=tolerance,
                                        timeout=timeout)  # fmt: skip

    async def reach_zoom(self, ratio: float, *, tolerance: float = ZOOM_TOLERANCE,
                         timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """See :meth:`GcuClient.reach_zoom <gcu_async.client.GcuClient.reach_zoom>`."""
        check_positive("timeout", timeout)
        check_positive("tolerance", tolerance, unit="x")
        await self._driver.run(build("zoom_to", self._driver.context(), ratio=ratio))
        try:
            return await self.wait_zoom(ratio, tolerance=tolerance, timeout=timeout)
        except WaitTimeout as exc:
            info = getattr(exc.last, "info", None)
            if info is None or info.camera1_zoom >= ratio:
                raise
            hint = (f"zoom {ratio:g}x (±{tolerance:g}; camera 1 last reported "
                    f"{info.camera1_zoom:g}x: its maximum may be lower than {ratio:g}x; "
                    "GcuClient(max_zoom=...) refuses such ratios before sending)")  # fmt: skip
            raise WaitTimeout(hint, exc.timeout, exc.last) from None

    # -- the link --------------------------------------------------------------------------
    async def wait_link(self, up: bool = True, *, timeout: float = WAIT_TIMEOUT) -> None:
        """See :meth:`GcuClient.wait_link <gcu_async.client.GcuClient.wait_link>`."""
        want = check_bool("up", up)
        timeout = check_positive("timeout", timeout)
        closed = self._closed()
        if closed is None or closed.is_set():
            raise LinkLost(self._driver.not_open())
        what = "the link up" if want else "the link down"
        changed = asyncio.Event()
        unsubscribe = self._links.add(lambda event: changed.set())
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        try:
            while True:
                if closed.is_set():
                    raise LinkLost(self._ended(what))
                if self._link_up() is want:
                    return
                left = deadline - loop.time()
                if left <= 0:
                    raise WaitTimeout(what, timeout, self._latest())
                changed.clear()
                await _either(changed, closed, left)
        finally:
            unsubscribe()

    async def link_events(self) -> AsyncGenerator[LinkEvent, None]:
        """See :meth:`GcuClient.link_events <gcu_async.client.GcuClient.link_events>`."""
        closed = self._closed()
        if closed is None or closed.is_set():
            raise LinkLost(self._driver.not_open())
        events: deque[LinkEvent] = deque(maxlen=LINK_EVENTS_MAX)
        ready = asyncio.Event()

        def put(event: LinkEvent) -> None:
            events.append(event)
            ready.set()

        unsubscribe = self._links.add(put)
        try:
            while True:
                while events:
                    yield events.popleft()
                if closed.is_set():
                    return
                ready.clear()
                await _either(ready, closed, None)
        finally:
            unsubscribe()


async def _either(a: asyncio.Event, b: asyncio.Event, timeout: float | None) -> None:
    """Wait until ``a`` or ``b`` is set, or ``timeout`` seconds pass."""
    waiters = {asyncio.ensure_future(a.wait()), asyncio.ensure_future(b.wait())}
    try:
        await asyncio.wait(waiters, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for waiter in waiters:
            waiter.cancel()


__all__ = ["ANGLE_TOLERANCE", "WAIT_TIMEOUT", "ZOOM_TOLERANCE", "Waiting", "angle_error"]
