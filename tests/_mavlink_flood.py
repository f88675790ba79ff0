"""A MAVLink flood from another process: ``python _mavlink_flood.py PORT KIND RATE SECONDS
PAIRS`` sends ``RATE`` datagrams/s for ``SECONDS`` to 127.0.0.1:PORT, each a MAVLink 2
message from one of ``PAIRS`` (system, component) pairs in turn. KIND: ``command`` (photo
and autofocus COMMAND_LONGs to the camera), ``attitude`` (GIMBAL_MANAGER_SET_ATTITUDE to the
gimbal, yaw lock and follow alternating, so each message asks for the other mode).
Prints the number sent. Messages are packed before the clock starts."""

from __future__ import annotations

import math
import os
import socket
import sys
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink

BATCH = 50
"""Datagrams per pacing step (the rate is kept per batch)."""


def packets(kind: str, pairs: int, count: int) -> list[bytes]:
    out = []
    packers = [mavlink.MAVLink(None, srcSystem=2 + i % 250, srcComponent=1 + i // 250 % 254)
               for i in range(pairs)]  # fmt: skip
    for i in range(count):
        mav = packers[i % pairs]
        if kind == "command":
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
    port, kind, rate, seconds, pairs = (int(sys.argv[1]), sys.argv[2], float(sys.argv[3]),
                                        float(sys.argv[4]), int(sys.argv[5]))  # fmt: skip
    data = packets(kind, pairs, max(1, int(rate * seconds)))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    start = time.monotonic()
    sent = 0
    for i in range(0, len(data), BATCH):
        for datagram in data[i:i + BATCH]:
            try:
                sock.sendto(datagram, ("127.0.0.1", port))
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
