"""A UDP flood from many source ports, run as its own process (so it does not share the
bridge's interpreter): ``python udp_flood.py HOST PORT SECONDS RATE SOURCES MODE``.

MODE ``junk`` sends junk (one random byte, ``FD FF``, a truncated frame, random bytes),
``valid`` sends a valid MAVLink HEARTBEAT from a different system id per source, ``mixed``
alternates. Sockets are opened in batches of 200 and closed after their turn, so SOURCES
distinct source ports send without holding SOURCES descriptors. Prints the datagrams sent.
"""

from __future__ import annotations

import os
import random
import socket
import sys
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink

BATCH = 200


def junk(rng: random.Random) -> bytes:
    kind = rng.randrange(4)
    if kind == 0:
        return bytes([rng.randrange(256)])
    if kind == 1:
        return b"\xfd\xff"
    if kind == 2:
        return b"\xfd\x09\x00\x00\x00\x01\x01\x00\x00\x00"  # a HEARTBEAT header, cut short
    return rng.randbytes(rng.randrange(1, 300))


def valid(system: int) -> bytes:
    packer = mavlink.MAVLink(None, srcSystem=system, srcComponent=190)
    msg = mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                            0, 0, 0, 3)  # fmt: skip
    return bytes(msg.pack(packer))


def main() -> None:
    host, port, seconds, rate, sources, mode = sys.argv[1:7]
    target = (host, int(port))
    rng = random.Random(1)
    end = time.monotonic() + float(seconds)
    interval = 1.0 / float(rate)
    sent = 0
    index = 0
    next_send = time.monotonic()
    packed = [valid(2 + i) for i in range(250)]
    while time.monotonic() < end:
        batch = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(BATCH)]
        try:
            for sock in batch:
                sock.bind(("127.0.0.1", 0))
            for _ in range(2):  # each source sends twice per turn
                for sock in batch:
                    index += 1
                    if index > int(sources):
                        index = 1
                    is_valid = mode == "valid" or (mode == "mixed" and index % 2 == 0)
                    data = packed[index % 250] if is_valid else junk(rng)
                    try:
                        sock.sendto(data, target)
                        sent += 1
                    except OSError:
                        pass
                    next_send += interval
                    delay = next_send - time.monotonic()
                    if delay > 0:
                        time.sleep(delay)
                    if time.monotonic() >= end:
                        break
        finally:
            for sock in batch:
                sock.close()
    print(sent, flush=True)


if __name__ == "__main__":
    main()
