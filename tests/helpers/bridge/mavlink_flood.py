"""A MAVLink flood from another process: ``python mavlink_flood.py PORT KIND RATE SECONDS
PAIRS [--sockets N] [--heartbeats] [--ids SYS:COMP]`` sends ``RATE`` datagrams/s for
``SECONDS`` to 127.0.0.1:PORT, each a MAVLink 2 message from one of ``PAIRS`` (system,
component) pairs in turn. KIND: ``command`` (photo and autofocus COMMAND_LONGs to the
camera), ``attitude`` (GIMBAL_MANAGER_SET_ATTITUDE to the gimbal, yaw lock and follow
alternating, so each message asks for the other mode).

``--sockets N``: from N sockets (N source addresses) in turn; ``--heartbeats``: every
tenth datagram of each socket is a HEARTBEAT (a flood that passes for ground stations);
``--ids SYS:COMP``: every message carries these ids (e.g. a ground station's own).
Prints the number sent. Messages are packed before the clock starts."""

from __future__ import annotations

import argparse
import math
import os
import socket
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink

BATCH = 50
"""Datagrams per pacing step (the rate is kept per batch)."""
HEARTBEAT_EVERY = 10
"""With ``--heartbeats``: one datagram in this many is a HEARTBEAT."""


def packets(kind: str, pairs: int, count: int, *, heartbeats: bool = False,
            ids: tuple[int, int] | None = None) -> list[bytes]:  # fmt: skip
    out = []
    mav = mavlink.MAVLink(None)
    for i in range(count):
        pair = i % pairs
        mav.srcSystem, mav.srcComponent = ids or (2 + pair % 250, 1 + pair // 250 % 254)
        if heartbeats and i % HEARTBEAT_EVERY == 0:
            msg = mavlink.MAVLink_heartbeat_message(
                mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3)
        elif kind == "command":
            if i % 2:
                msg = mavlink.MAVLink_command_long_message(
                    1, mavlink.MAV_COMP_ID_CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0,
                    0, 0, 1, 0, 0, 0, 0)
            else:
                msg = mavlink.MAVLink_command_long_message(
                    1, mavlink.MAV_COMP_ID_CAMERA, mavlink.MAV_CMD_SET_CAMERA_FOCUS, 0,
                    mavlink.FOCUS_TYPE_AUTO, 0, 0, 0, 0, 0, 0)
        else:
            flags = mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK if i % 2 else 0
            nan = math.nan
            msg = mavlink.MAVLink_gimbal_manager_set_attitude_message(
                1, mavlink.MAV_COMP_ID_GIMBAL, flags, 0, [nan] * 4, nan, 0.05 * (i % 7), nan)
        out.append(msg.pack(mav))
        mav.seq = (mav.seq + 1) % 256
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("port", type=int)
    parser.add_argument("kind", choices=["command", "attitude"])
    parser.add_argument("rate", type=float)
    parser.add_argument("seconds", type=float)
    parser.add_argument("pairs", type=int)
    parser.add_argument("--sockets", type=int, default=1)
    parser.add_argument("--heartbeats", action="store_true")
    parser.add_argument("--ids", type=lambda s: tuple(int(x) for x in s.split(":")))
    args = parser.parse_args()
    rate = args.rate
    data = packets(args.kind, args.pairs, max(1, int(rate * args.seconds)),
                   heartbeats=args.heartbeats, ids=args.ids)  # fmt: skip
    socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(args.sockets)]
    start = time.monotonic()
    sent = 0
    for i in range(0, len(data), BATCH):
        for n, datagram in enumerate(data[i:i + BATCH], i):
            # a socket's datagrams in runs of HEARTBEAT_EVERY, so each one's heartbeats
            # come from it
            sock = socks[n // HEARTBEAT_EVERY % len(socks)]
            try:
                sock.sendto(datagram, ("127.0.0.1", args.port))
                sent += 1
            except OSError:
                pass
        due = start + (i + BATCH) / rate
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
    print(sent, flush=True)


if __name__ == "__main__":
    main()
