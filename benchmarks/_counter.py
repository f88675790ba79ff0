"""The counting side of the capacity benchmark (bench_capacity.py): a child process, standard
library only (it starts fast and has no library code to cost), pinned to its own CPU.

Two roles, one UDP socket on loopback each (its buffers raised so that a scheduling hiccup
drops nothing; drops are reported all the same):

responder (``--reply HEX``)
    Answers every datagram with the canned reply, counts datagrams per source port and
    those whose bytes are not ``--packet``.
hosts (no ``--reply``)
    The first stdin line lists the gimbals' ports (``{"ports": [...]}``); sends each of them
    ``--packet`` every ``--period`` seconds on an absolute schedule (gimbal i's phase
    ``i / N`` of a period; late sends are caught up, and the latest is reported), counts
    replies per source port and those that do not start with ``--expect``.

Every ``mark`` line on stdin is answered with one JSON line: this process's clock, CPU time
and time spent waiting for a CPU, the counts so far, the kernel's drops at the socket. It
ends when stdin closes.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import select
import socket
import sys
import time
from collections.abc import Sequence

LOOPBACK = "127.0.0.1"
SOCKET_BUFFER = 32 * 1024 * 1024
"""Receive and send buffer asked for: tens of thousands of datagrams, a second or more of the
largest loads. Beyond net.core.rmem_max / wmem_max only with CAP_NET_ADMIN (SO_RCVBUFFORCE);
else the kernel caps it there."""
_SO_SNDBUFFORCE, _SO_RCVBUFFORCE = 32, 33  # <asm-generic/socket.h>; Python defines neither
DRAIN = 512
"""Most datagrams read per wake-up before the send schedule is looked at again."""
FIRST_LINE_WAIT = 15.0
"""Seconds the hosts role waits for its list of ports."""


def emit(obj: object) -> None:
    """One JSON line to the controller."""
    with contextlib.suppress(BrokenPipeError):
        sys.stdout.write(json.dumps(obj, separators=(",", ":")) + "\n")
        sys.stdout.flush()


def pin(cpu: int | None) -> None:
    """Run this process on ``cpu`` only (None: wherever the OS likes)."""
    if cpu is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {cpu})


def run_delay() -> float | None:
    """Seconds this process's main thread has waited on a run queue, runnable but not
    running (Linux /proc/self/schedstat), else None: what other processes took from it."""
    try:
        with open("/proc/self/schedstat", encoding="ascii") as f:
            return int(f.read().split()[1]) / 1e9
    except (OSError, ValueError, IndexError):
        return None


def big_buffers(sock: socket.socket) -> None:
    """Ask for :data:`SOCKET_BUFFER` both ways, past the sysctl caps where allowed."""
    for force, option in ((_SO_RCVBUFFORCE, socket.SO_RCVBUF),
                          (_SO_SNDBUFFORCE, socket.SO_SNDBUF)):  # fmt: skip
        try:
            if not sys.platform.startswith("linux"):
                raise OSError
            sock.setsockopt(socket.SOL_SOCKET, force, SOCKET_BUFFER)
        except OSError:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, option, SOCKET_BUFFER)


def socket_drops(port: int) -> int | None:
    """Datagrams the kernel dropped at the IPv4 UDP socket bound to ``port`` (Linux
    /proc/net/udp), else None."""
    suffix = f":{port:04X}"
    try:
        with open("/proc/net/udp", encoding="ascii") as f:
            for line in f:
                fields = line.split()
                if len(fields) > 12 and fields[1].endswith(suffix):
                    return int(fields[-1])
    except (OSError, ValueError):
        pass
    return None


class Lines:
    """Lines from a file descriptor, read only when it is readable."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.buffer = b""
        self.eof = False

    def read(self) -> list[str]:
        chunk = os.read(self.fd, 1 << 16)
        if not chunk:
            self.eof = True
        self.buffer += chunk
        *lines, self.buffer = self.buffer.split(b"\n")
        return [line.decode() for line in lines]


def first_line(stdin: Lines) -> str | None:
    deadline = time.monotonic() + FIRST_LINE_WAIT
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0 or stdin.eof:
            return None
        if select.select([stdin.fd], [], [], remaining)[0]:
            lines = stdin.read()
            if lines:
                return lines[0]


def run(reply: bytes | None, packet: bytes, expect: bytes, period: float) -> int:
    """The responder (``reply`` given) or the hosts (``reply`` None); see the module."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    big_buffers(sock)
    sock.bind((LOOPBACK, 0))
    sock.setblocking(False)
    port = sock.getsockname()[1]
    emit({"port": port, "rcvbuf": sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)})
    stdin = Lines(sys.stdin.fileno())
    targets: list[tuple[str, int]] = []
    if reply is None:
        line = first_line(stdin)
        if line is None:
            return 2
        targets = [(LOOPBACK, int(p)) for p in json.loads(line)["ports"]]
    poller = select.epoll()
    poller.register(sock.fileno(), select.EPOLLIN)
    poller.register(stdin.fd, select.EPOLLIN)
    received: dict[int, int] = {}
    count = len(targets)
    sent = [0] * count
    other = 0
    late = 0.0
    step = period / count if count else math.inf
    start = time.monotonic() + period
    j = 0
    recvfrom, sendto, monotonic = sock.recvfrom, sock.sendto, time.monotonic
    size = len(expect)
    while True:
        timeout = 1.0
        if count:
            now = monotonic()
            due = start + j * step
            if due <= now:
                late = max(late, now - due)
                while due <= now:
                    i = j % count
                    with contextlib.suppress(BlockingIOError):
                        sendto(packet, targets[i])
                        sent[i] += 1
                    j += 1
                    due = start + j * step
            timeout = max(0.0, due - monotonic())
        for fd, _ in poller.poll(timeout):
            if fd == stdin.fd:
                for line in stdin.read():
                    if line.strip() == "mark":
                        emit({"t": monotonic(), "cpu": time.process_time(),
                              "waited": run_delay(), "received": received, "sent": sent,
                              "other": other, "late": late,
                              "drops": socket_drops(port)})  # fmt: skip
                        late = 0.0
                if stdin.eof:
                    sock.close()
                    return 0
                continue
            for _ in range(DRAIN):
                try:
                    data, addr = recvfrom(2048)
                except BlockingIOError:
                    break
                source = addr[1]
                received[source] = received.get(source, 0) + 1
                if reply is None:
                    if data[:size] != expect:
                        other += 1
                    continue
                if data != packet:
                    other += 1
                with contextlib.suppress(BlockingIOError):
                    sendto(reply, addr)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--reply", help="responder: the canned reply (hex)")
    ap.add_argument("--packet", required=True, help="the host packet (hex)")
    ap.add_argument("--expect", default="", help="hosts: how every reply starts (hex)")
    ap.add_argument("--period", type=float, required=True, help="hosts: seconds per packet")
    ap.add_argument("--cpu", type=int, help="the CPU to run on")
    args = ap.parse_args(argv)
    pin(args.cpu)
    reply = bytes.fromhex(args.reply) if args.reply else None
    return run(reply, bytes.fromhex(args.packet), bytes.fromhex(args.expect), args.period)


if __name__ == "__main__":
    sys.exit(main())
