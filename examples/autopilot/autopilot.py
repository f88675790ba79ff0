"""Autopilot loop: feed the GCU the aircraft state from MAVLink and point the camera.

    python examples/autopilot/autopilot.py --mavlink udpin:127.0.0.1:14550 \\
        --gcu udp://127.0.0.1:2337 --target 47.397742,8.545594,488

Every MAVLink message (any pymavlink connection string: ``udpin:``, ``tcp:``, a serial
device …) goes through :class:`gcu_async.mavlink.MavlinkAircraftState` — ATTITUDE,
GLOBAL_POSITION_INT, LOCAL_POSITION_NED (or an IMU message) for gravity-free acceleration,
GPS_RAW_INT, SYSTEM_TIME — and the resulting aircraft state replaces the one the client's
50 Hz heartbeat carries (host main frame bytes 11–29, sub frame bytes 38–60). Once
attitude, acceleration, velocity and position are known, the camera is told to gaze at
``--target`` (0x15); the command is retried until the GCU accepts it, and again after the
link to the GCU comes back.
A status line is logged every ``--status-interval`` seconds. Runs until Ctrl-C / SIGTERM
or ``--duration`` seconds; exits 0 if the camera was pointed, 1 if not.

pymavlink's ``recv_match`` blocks, so a reader thread receives (with a short timeout, so it
stops promptly) and hands each message to the event loop with ``call_soon_threadsafe``:
all state lives in the event loop's thread, nothing is shared between threads.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import signal
import sys
import threading
from collections import Counter
from collections.abc import Callable
from typing import Any

from gcu_async import CommandFailed, CommandTimeout, GcuClient, LinkLost, connect
from gcu_async.mavlink import ACCELERATION_SOURCES, MILLI_G, MavlinkAircraftState
from gcu_async.protocol import GazeAtCoordinates
from gcu_async.transport import LinkEvent, LinkEventKind

log = logging.getLogger("autopilot")

DEFAULT_MAVLINK = "udpin:127.0.0.1:14550"
DEFAULT_GCU = "udp://127.0.0.1:2337"
RETRY_SECONDS = 1.0
"""Wait between attempts to point the camera."""


class MavlinkReader:
    """Receives from a pymavlink connection in a thread; calls ``on_message(msg)`` in the
    event loop's thread for every message. ``with MavlinkReader(...):`` opens the connection
    (binding a ``udpin:`` port at once) and stops the thread and closes it on exit."""

    def __init__(
        self,
        url: str,
        on_message: Callable[[Any], None],
        loop: asyncio.AbstractEventLoop,
        *,
        poll: float = 0.1,
    ) -> None:
        from pymavlink import mavutil

        self.url = url
        self.error: BaseException | None = None
        """What ended the reader thread early (a closed serial port …), if anything."""
        self.bad_data = 0
        self._on_message = on_message
        self._loop = loop
        self._poll = poll
        self._stop = threading.Event()
        self._connection = mavutil.mavlink_connection(url, source_system=255)
        self._thread = threading.Thread(target=self._run, name="mavlink-reader", daemon=True)

    def __enter__(self) -> MavlinkReader:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5 * self._poll + 1.0)
        self._connection.close()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                msg = self._connection.recv_match(blocking=True, timeout=self._poll)
                if msg is None:
                    continue
                if msg.get_type() == "BAD_DATA":
                    self.bad_data += 1
                    continue
                self._loop.call_soon_threadsafe(self._on_message, msg)
        except Exception as exc:  # reported by the main loop, which then stops
            self.error = exc


class Autopilot:
    """Keeps the GCU's aircraft state current and the camera on the target."""

    def __init__(
        self,
        gcu: GcuClient,
        target: tuple[float, float, float],
        mapper: MavlinkAircraftState,
        *,
        system_id: int | None = None,
    ) -> None:
        self.gcu = gcu
        self.target = target
        self.mapper = mapper
        self.system_id = system_id
        self.used: Counter[str] = Counter()
        self.rejected: Counter[str] = Counter()
        self.pointed = False
        """The GCU accepted the gaze command (reset when the link comes back)."""
        self.pointed_count = 0

    @property
    def ready(self) -> bool:
        """Attitude, acceleration, velocity and position known: the GCU has what gazing
        needs (INS valid takes all three INS parts)."""
        state = self.mapper.state
        return state.ins_complete and state.position is not None

    def on_message(self, msg: Any) -> None:
        """One MAVLink message: update the mapping, then the heartbeat's aircraft state."""
        if self.system_id is not None and msg.get_srcSystem() != self.system_id:
            return
        kind = msg.get_type()
        try:
            used = self.mapper.update(msg)
        except ValueError as exc:  # FieldRangeError: not sendable; the state stays as it was
            self.rejected[kind] += 1
            if self.rejected[kind] == 1:
                log.warning("%s rejected: %s (further rejections are counted)", kind, exc)
            return
        if used:
            self.used[kind] += 1
            self.gcu.set_aircraft(self.mapper.state)

    def on_link(self, event: LinkEvent) -> None:
        if event.kind is LinkEventKind.RESTORED:
            log.info("link to the GCU restored: pointing the camera again")
            self.pointed = False
        elif event.kind is LinkEventKind.LOST:
            log.warning("link to the GCU lost: %s", event.detail)

    async def point_camera(self) -> bool:
        """Send "gaze at coordinates" (0x15); True once the GCU confirmed it."""
        lat, lon, alt = self.target
        try:
            await self.gcu.gaze_at(lat, lon, alt)
        except (CommandFailed, CommandTimeout, LinkLost) as exc:
            log.warning("gaze at %.6f,%.6f %.1f m not accepted: %s", lat, lon, alt, exc)
            return False
        self.pointed = True
        self.pointed_count += 1
        log.info("camera gazing at %.6f,%.6f %.1f m MSL", lat, lon, alt)
        return True

    def status_line(self) -> str:
        s = self.mapper.state
        parts = []
        if s.position is not None:
            p = s.position
            parts.append(
                f"aircraft {p.latitude:.6f},{p.longitude:.6f} {p.altitude:.1f} m "
                f"(+{s.relative_altitude:.1f})"
            )
        if s.attitude is not None:
            a = s.attitude
            parts.append(f"att {a.roll:.1f}/{a.pitch:.1f}/{a.yaw:.1f}")
        if s.acceleration is not None:
            parts.append("acc N/E/U {:.2f}/{:.2f}/{:.2f}".format(*s.acceleration))
        parts.append(f"sats {s.satellites} week {s.gnss_week} ms {s.gnss_ms}")
        link, st = self.gcu.link, self.gcu.status
        if link.up and st is not None:
            parts.append(
                f"GCU {st.mode.name} cam pitch {st.attitude.pitch:.1f} "
                f"yaw {st.attitude.yaw:.1f} ({link.reply_rate:.0f} Hz)"
            )
        else:
            parts.append("GCU link DOWN")
        parts.append(f"msgs {sum(self.used.values())} rejected {sum(self.rejected.values())}")
        return " | ".join(parts)


async def run(args: argparse.Namespace) -> int:
    """The loop; returns the exit status."""
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):  # Windows: no handlers
            loop.add_signal_handler(sig, stop.set)
    end = None if args.duration is None else loop.time() + args.duration
    mapper = MavlinkAircraftState(
        acceleration_source=args.accel_source,
        raw_imu_scale=MILLI_G if args.accel_source == "RAW_IMU" else None,
    )
    gcu = connect(args.gcu)
    try:
        await gcu.open()  # heartbeat running, first reply received
    except (LinkLost, OSError) as exc:
        log.error("cannot reach the GCU at %s: %s", args.gcu, exc)
        return 1
    try:
        pilot = Autopilot(gcu, args.target, mapper, system_id=args.system_id)
        gcu.on_link_change(pilot.on_link)
        try:
            reader = MavlinkReader(args.mavlink, pilot.on_message, loop)
        except (OSError, ValueError) as exc:  # port in use, no such device, bad string
            log.error("cannot open the MAVLink connection %s: %s", args.mavlink, exc)
            return 1
        with reader:
            log.info("reading MAVLink from %s, GCU at %s", args.mavlink, args.gcu)
            await _loop(pilot, reader, stop, end, args.status_interval)
    finally:
        await gcu.close()
    log.info(
        "done: messages used %s, rejected %s, MAVLink bad data %d, camera pointed %d time(s)",
        dict(pilot.used),
        dict(pilot.rejected),
        reader.bad_data,
        pilot.pointed_count,
    )
    return 0 if pilot.pointed_count and reader.error is None else 1


async def _loop(
    pilot: Autopilot,
    reader: MavlinkReader,
    stop: asyncio.Event,
    end: float | None,
    status_interval: float,
) -> None:
    """Point the camera when possible, log the status; until ``stop`` or ``end``."""
    loop = asyncio.get_running_loop()
    next_try = next_status = loop.time()
    while not stop.is_set() and (end is None or loop.time() < end):
        if reader.error is not None:
            log.error("MAVLink connection failed: %s", reader.error)
            return
        now = loop.time()
        if pilot.ready and not pilot.pointed and pilot.gcu.link.up and now >= next_try:
            next_try = now + RETRY_SECONDS
            await pilot.point_camera()
        if now >= next_status:
            next_status = now + status_interval
            log.info("%s", pilot.status_line())
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(stop.wait(), 0.05)


def _target(text: str) -> tuple[float, float, float]:
    try:
        lat, lon, alt = (float(x) for x in text.split(","))
        GazeAtCoordinates(latitude=lat, longitude=lon, altitude=alt)  # the wire's ranges
    except ValueError as exc:  # FieldRangeError names the field, range and value
        raise argparse.ArgumentTypeError(f"{text!r} is not LAT,LON,ALT: {exc}") from None
    return lat, lon, alt


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--mavlink",
        default=DEFAULT_MAVLINK,
        help=f"pymavlink connection string (default {DEFAULT_MAVLINK})",
    )
    parser.add_argument(
        "--gcu", default=DEFAULT_GCU, help=f"GCU URL (default {DEFAULT_GCU}; e.g. ?local_port=0)"
    )
    parser.add_argument(
        "--target",
        type=_target,
        required=True,
        help="point the camera at LAT,LON,ALT (degrees, degrees, m MSL); "
        "a negative latitude needs --target=LAT,LON,ALT",
    )
    parser.add_argument(
        "--accel-source",
        default="LOCAL_POSITION_NED",
        choices=ACCELERATION_SOURCES,
        help="message acceleration is derived from (gravity removed)",
    )
    parser.add_argument(
        "--system-id",
        type=int,
        default=None,
        help="only use messages from this MAVLink system (default: any)",
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        help="stop after this many seconds (default: until Ctrl-C)",
    )
    parser.add_argument("--status-interval", type=float, default=1.0, help="seconds")
    parser.add_argument("-v", "--verbose", action="store_true")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(asctime)s %(name)s: %(message)s",
    )
    try:
        return asyncio.run(run(args))
    except KeyboardInterrupt:  # where signal handlers are unavailable
        return 130


if __name__ == "__main__":
    sys.exit(main())
