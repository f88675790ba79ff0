"""A small MAVLink source: plays a circling aircraft as an autopilot would stream it.

    python examples/autopilot/mavlink_source.py --out udpout:127.0.0.1:14550 --duration 30

Messages (MAVLink 2, common dialect, encoded by pymavlink), at the rates a PX4/ArduPilot
stream typically uses:

====================  =======  ==========================================================
message               rate     carries
====================  =======  ==========================================================
ATTITUDE              50 Hz    roll, pitch, yaw (rad), body rates
SCALED_IMU            50 Hz    accelerometer specific force (mG, body frame, with gravity)
GLOBAL_POSITION_INT   10 Hz    lat/lon (1e-7 °), alt MSL / relative (mm), NED speed (cm/s)
LOCAL_POSITION_NED    10 Hz    position and velocity (m, m/s) NED from home
HEARTBEAT             1 Hz     a fixed-wing autopilot
GPS_RAW_INT           1 Hz     3D fix, 14 satellites
SYSTEM_TIME           1 Hz     UTC (µs since 1970), boot time
====================  =======  ==========================================================

The truth comes from :class:`flight.CirclingFlight` (a steady clockwise circle), so the
numbers are plausible and consistent: e.g. the acceleration derived from consecutive
LOCAL_POSITION_NED velocities is the centripetal v²/r, and the IMU's specific force minus
gravity gives the same. Defaults are loopback only; stops after ``--duration`` s or Ctrl-C.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

sys.path.insert(0, str(Path(__file__).resolve().parent))
from flight import STANDARD_GRAVITY, CirclingFlight, FlightSample

log = logging.getLogger("mavlink_source")

DEFAULT_OUT = "udpout:127.0.0.1:14550"
BOOT_OFFSET_MS = 60_000
"""The simulated autopilot booted a minute before the stream starts."""
SATELLITES = 14
ATTITUDE_DIVIDER = 1  # of the base rate (50 Hz)
POSITION_DIVIDER = 5  # 10 Hz
SLOW_DIVIDER = 50  # 1 Hz


def messages(mav: Any, s: FlightSample, tick: int, boot_ms: int, unix_us: int) -> list[Any]:
    """The MAVLink messages for one tick of the base rate (50 Hz), built with ``mav``'s
    encoders (a ``pymavlink`` ``MAVLink`` instance)."""
    out: list[Any] = []
    vn, ve, vd = s.velocity_ned
    if tick % ATTITUDE_DIVIDER == 0:
        p, q, r = s.body_rates
        out.append(
            mav.attitude_encode(
                boot_ms,
                math.radians(s.roll),
                math.radians(s.pitch),
                math.radians((s.yaw + 180.0) % 360.0 - 180.0),  # MAVLink yaw is [-pi, pi]
                p,
                q,
                r,
            )
        )
        fx, fy, fz = (round(f / STANDARD_GRAVITY * 1000) for f in s.specific_force_body())
        out.append(mav.scaled_imu_encode(boot_ms, fx, fy, fz, 0, 0, 0, 0, 0, 0))
    if tick % POSITION_DIVIDER == 0:
        out.append(
            mav.global_position_int_encode(
                boot_ms,
                round(s.latitude * 1e7),
                round(s.longitude * 1e7),
                round(s.altitude * 1000),
                round(s.relative_altitude * 1000),
                round(vn * 100),
                round(ve * 100),
                round(vd * 100),
                round(s.yaw * 100) % 36000,
            )
        )
        x, y, z = s.position_ned
        out.append(mav.local_position_ned_encode(boot_ms, x, y, z, vn, ve, vd))
    if tick % SLOW_DIVIDER == 0:
        out.append(
            mav.heartbeat_encode(
                mavlink.MAV_TYPE_FIXED_WING,
                mavlink.MAV_AUTOPILOT_GENERIC,
                mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
                0,
                mavlink.MAV_STATE_ACTIVE,
            )
        )
        out.append(
            mav.gps_raw_int_encode(
                unix_us,
                3,
                round(s.latitude * 1e7),
                round(s.longitude * 1e7),
                round(s.altitude * 1000),
                80,
                120,
                round(math.hypot(vn, ve) * 100),
                round(s.yaw * 100) % 36000,
                SATELLITES,
            )
        )
        out.append(mav.system_time_encode(unix_us, boot_ms))
    return out


def run(connection: Any, flight: CirclingFlight, rate_hz: float, duration: float | None) -> int:
    """Stream ``flight`` on ``connection`` (a pymavlink ``mavfile``) until ``duration``
    seconds have passed (``None``: forever). Returns the number of messages sent."""
    period = 1.0 / rate_hz
    start = time.monotonic()
    sent = errors = tick = 0
    deadline = start
    while duration is None or time.monotonic() - start < duration:
        # one clock for every field of a tick: the flight at exactly time_boot_ms
        boot_ms = BOOT_OFFSET_MS + round((time.monotonic() - start) * 1000)
        sample = flight.sample((boot_ms - BOOT_OFFSET_MS) / 1000)
        for msg in messages(connection.mav, sample, tick, boot_ms, time.time_ns() // 1000):
            try:
                connection.mav.send(msg)
                sent += 1
            except OSError as exc:  # nobody listening yet is not fatal for a stream
                errors += 1
                if errors == 1:
                    log.warning("send failed: %s (further failures are counted)", exc)
        if tick % (SLOW_DIVIDER * 5) == 0:
            log.info("t=%5.1f s  %s  sent %d  errors %d", sample.t, _describe(sample), sent, errors)
        tick += 1
        deadline += period
        time.sleep(max(0.0, deadline - time.monotonic()))
    return sent


def _describe(s: FlightSample) -> str:
    return (
        f"{s.latitude:.6f},{s.longitude:.6f} {s.altitude:.0f} m  "
        f"roll {s.roll:.1f} pitch {s.pitch:.1f} yaw {s.yaw:.1f}"
    )


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out",
        default=DEFAULT_OUT,
        help=f"pymavlink connection string to send to (default {DEFAULT_OUT})",
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        help="stop after this many seconds (default: until Ctrl-C)",
    )
    parser.add_argument("--rate", type=float, default=50.0, help="ATTITUDE rate, Hz")
    parser.add_argument("--system-id", type=int, default=1, help="MAVLink system id")
    defaults = CirclingFlight()
    parser.add_argument(
        "--centre",
        default=f"{defaults.centre_latitude},{defaults.centre_longitude}",
        help="circle centre LAT,LON (degrees)",
    )
    parser.add_argument(
        "--home-alt",
        type=float,
        default=defaults.home_altitude,
        help="home (ground) altitude, m MSL",
    )
    parser.add_argument(
        "--height", type=float, default=defaults.height, help="flight height above home, m"
    )
    parser.add_argument("--radius", type=float, default=defaults.radius, help="m")
    parser.add_argument("--speed", type=float, default=defaults.speed, help="m/s")
    parser.add_argument("-v", "--verbose", action="store_true")
    args = parser.parse_args(argv)
    try:
        lat, lon = (float(x) for x in args.centre.split(","))
    except ValueError:
        parser.error(f"--centre: {args.centre!r} is not LAT,LON")
    if args.rate <= 0 or (args.duration is not None and args.duration <= 0):
        parser.error("--rate and --duration must be > 0")
    args.flight = CirclingFlight(lat, lon, args.home_alt, args.height, args.radius, args.speed)
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(asctime)s %(name)s: %(message)s",
    )
    os.environ.setdefault("MAVLINK20", "1")  # MAVLink 2 framing, as current autopilots send
    from pymavlink import mavutil

    connection = mavutil.mavlink_connection(
        args.out, dialect="common", source_system=args.system_id, source_component=1
    )
    log.info(
        "streaming a %.0f m circle at %.0f m/s to %s",
        args.flight.radius,
        args.flight.speed,
        args.out,
    )
    try:
        sent = run(connection, args.flight, args.rate, args.duration)
    except KeyboardInterrupt:
        sent = -1
    finally:
        connection.close()
    log.info("stopped%s", "" if sent < 0 else f" after {sent} messages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
