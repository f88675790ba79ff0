"""Two hosts on one LAN, in network namespaces a test creates and removes.

Host A (the GCU: the simulator) has 10.213.0.1/24, host B (the user's computer) 10.213.0.2/24,
joined by a veth pair created directly inside the two namespaces (nothing is ever added to
the machine's own namespace). Names carry the test process's pid and a random token, so
concurrent runs never collide; :meth:`Lan.close` kills every process started through the
``Lan`` and deletes both namespaces (which deletes the veth pair), then checks they are
gone. Needs Linux, root and iproute2's ``ip``; :func:`unavailable` says why not.

Run as a script (inside a namespace), this file is a passive listener on a port:
``python lan.py sniff PORT OPTION N`` binds N sockets to ``0.0.0.0:PORT``, each with
OPTION (``reuseport``: SO_REUSEPORT, ``reuseaddr``: SO_REUSEADDR) and IP_PKTINFO, prints
``ready``, then one JSON object per datagram received (which socket, source address and
port, destination address, payload in hex) until SIGTERM. It never sends.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import selectors
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

GCU_ADDRESS = "10.213.0.1"
"""Host A: where the simulator runs."""
HOST_ADDRESS = "10.213.0.2"
"""Host B: where the client runs."""
BROADCAST = "10.213.0.255"
"""The subnet's broadcast address (10.213.0.0/24)."""
PREFIX = 24
CLI = [sys.executable, "-c", "import sys; from gcu_async.cli import main; sys.exit(main())"]
SNIFFER = [sys.executable, str(Path(__file__).resolve()), "sniff"]
IP_TIMEOUT = 10.0
"""Bound on every ``ip`` command."""
_IP_PKTINFO = 8  # Linux <netinet/in.h>; the socket module does not export it
SHARE_OPTIONS = {"reuseport": getattr(socket, "SO_REUSEPORT", -1), "reuseaddr": socket.SO_REUSEADDR}


def unavailable() -> str | None:
    """Why network-namespace tests cannot run here, or None when they can."""
    if not sys.platform.startswith("linux"):
        return "network namespaces are a Linux feature"
    if os.geteuid() != 0:
        return "creating network namespaces needs root (ip netns add)"
    if shutil.which("ip") is None:
        return "iproute2's `ip` is missing (apt-get install iproute2; `make iproute2` in CI)"
    return None


def ip(*args: str) -> subprocess.CompletedProcess[str]:
    """Run ``ip ARGS`` (bounded); raise with its stderr when it fails."""
    done = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=IP_TIMEOUT)
    if done.returncode != 0:
        raise OSError(f"ip {' '.join(args)}: {done.stderr.strip() or done.returncode}")
    return done


def namespaces() -> set[str]:
    """Names of the network namespaces that exist now."""
    return {line.split()[0] for line in ip("netns", "list").stdout.splitlines() if line.strip()}


class Lan:
    """Namespaces ``gcu`` (host A) and ``host`` (host B) on 10.213.0.0/24."""

    def __init__(self) -> None:
        tag = f"{os.getpid() % 100000}{secrets.token_hex(2)}"
        self.gcu = f"gcu-async-{tag}-a"
        self.host = f"gcu-async-{tag}-b"
        self.links = (f"vg{tag}a", f"vg{tag}b")  # at most 15 characters
        self._procs: list[subprocess.Popen[bytes]] = []
        self._created: list[str] = []

    def create(self) -> None:
        """Create both namespaces and the veth pair, addresses up. On failure, everything
        created so far is removed before the error propagates."""
        try:
            for ns in (self.gcu, self.host):
                ip("netns", "add", ns)
                self._created.append(ns)
            a, b = self.links
            ip("link", "add", a, "netns", self.gcu, "type", "veth", "peer", "name", b,
               "netns", self.host)  # fmt: skip
            for ns, link, address in ((self.gcu, a, GCU_ADDRESS), (self.host, b, HOST_ADDRESS)):
                ip("-n", ns, "addr", "add", f"{address}/{PREFIX}", "brd", "+", "dev", link)
                ip("-n", ns, "link", "set", link, "up")
                ip("-n", ns, "link", "set", "lo", "up")
        except BaseException:
            self.close()
            raise

    def argv(self, ns: str, *argv: str) -> list[str]:
        """``argv`` run inside namespace ``ns``."""
        return ["ip", "netns", "exec", ns, *argv]

    def start(self, ns: str, *argv: str) -> subprocess.Popen[bytes]:
        """Start ``argv`` in ``ns``; killed by :meth:`close`. ``ip netns exec`` execs the
        command, so the process *is* the command. Its stdout and stderr are unbuffered
        pipes: :func:`line` reads exactly one line, leaving the rest in the pipe."""
        proc = subprocess.Popen(self.argv(ns, *argv), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, bufsize=0)  # fmt: skip
        self._procs.append(proc)
        return proc

    def run(self, ns: str, *argv: str, timeout: float = 30.0) -> subprocess.CompletedProcess[str]:
        """Run ``argv`` in ``ns`` to completion, at most ``timeout`` seconds."""
        return subprocess.run(self.argv(ns, *argv), capture_output=True, text=True,
                              timeout=timeout)  # fmt: skip

    def cli(self, ns: str, *args: str, timeout: float = 30.0) -> subprocess.CompletedProcess[str]:
        """``gcu-async ARGS`` in ``ns``, to completion."""
        return self.run(ns, *CLI, *args, timeout=timeout)

    def sim(self, *args: str, timeout: float = 15.0) -> tuple[subprocess.Popen[bytes], str]:
        """``gcu-async sim ARGS`` on host A; returns the process and its "listening" line."""
        proc = self.start(self.gcu, *CLI, "sim", *args)
        return proc, line(proc, timeout, "the simulator")

    def sniffer(self, port: int, option: str = "reuseport", sockets: int = 1,
                timeout: float = 15.0) -> subprocess.Popen[bytes]:  # fmt: skip
        """Passive listeners on host B's ``port`` (see the module docstring), ready."""
        proc = self.start(self.host, *SNIFFER, str(port), option, str(sockets))
        first = line(proc, timeout, "the sniffer")
        assert first.strip() == "ready", first
        return proc

    def close(self) -> None:
        """Kill the processes, delete the namespaces (and so the veths), check they are
        gone. Idempotent."""
        for proc in self._procs:
            if proc.poll() is None:
                proc.kill()
            proc.communicate(timeout=IP_TIMEOUT)
        self._procs.clear()
        errors = []
        for ns in self._created:
            try:
                ip("netns", "del", ns)
            except OSError as exc:
                errors.append(str(exc))
        left = set(self._created) & namespaces()
        self._created.clear()
        if errors or left:
            raise AssertionError(f"namespaces not removed: {sorted(left)} {errors}")


def line(proc: subprocess.Popen[bytes], timeout: float, what: str = "the process") -> str:
    """The next line ``proc`` prints, waiting at most ``timeout`` seconds for it to begin.
    (The unbuffered pipe is read byte by byte: nothing after the line is taken.)"""
    assert proc.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            raise TimeoutError(f"{what} printed nothing within {timeout:g} s")
    text = proc.stdout.readline().decode()
    if not text:
        _, err = finish(proc, IP_TIMEOUT)
        raise AssertionError(f"{what} exited ({proc.returncode}): {err}")
    return text


def finish(proc: subprocess.Popen[bytes], timeout: float = 15.0) -> tuple[str, str]:
    """Wait at most ``timeout`` s for ``proc`` to end; its remaining stdout and stderr."""
    out, err = proc.communicate(timeout=timeout)
    return out.decode(), err.decode()


def stop(proc: subprocess.Popen[bytes], timeout: float = 15.0) -> tuple[str, str]:
    """SIGTERM ``proc``, wait at most ``timeout`` s; its remaining stdout and stderr."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    return finish(proc, timeout)


def listening_url(line: str) -> str:
    """The URL in the simulator's "listening on URL" line."""
    match = re.search(r"listening on (\S+)", line)
    assert match, line
    return match.group(1)


def collect(proc: subprocess.Popen[bytes], count: int,
            timeout: float = 10.0) -> list[dict[str, Any]]:  # fmt: skip
    """Stop the sniffer ``proc`` once it reported ``count`` datagrams (or after ``timeout``
    seconds); every datagram it reported, extra ones included."""
    lines: list[str] = []
    deadline = time.monotonic() + timeout
    while len(lines) < count and (left := deadline - time.monotonic()) > 0:
        try:
            lines.append(line(proc, left, "the sniffer"))
        except TimeoutError:
            break
    out, _ = stop(proc)
    return datagrams("".join(lines) + out)


def datagrams(output: str) -> list[dict[str, Any]]:
    """The sniffer's records."""
    return [json.loads(line) for line in output.splitlines() if line.startswith("{")]


def _sniff(port: int, option: str, count: int) -> None:
    socks = []
    for _ in range(count):
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.setsockopt(socket.SOL_SOCKET, SHARE_OPTIONS[option], 1)
        sock.setsockopt(socket.IPPROTO_IP, _IP_PKTINFO, 1)
        sock.bind(("0.0.0.0", port))
        sock.setblocking(False)
        socks.append(sock)
    stopped = []
    signal.signal(signal.SIGTERM, lambda *_: stopped.append(True))
    print("ready", flush=True)
    with selectors.DefaultSelector() as sel:
        for index, sock in enumerate(socks):
            sel.register(sock, selectors.EVENT_READ, index)
        while not stopped:
            for key, _ in sel.select(0.1):
                _report(key.data, socks[key.data])
    for index, sock in enumerate(socks):  # what arrived before SIGTERM
        _report(index, sock)


def _report(index: int, sock: socket.socket) -> None:
    """Print every datagram waiting in ``sock``."""
    while True:
        try:
            data, ancillary, _, source = sock.recvmsg(65536, socket.CMSG_SPACE(12))
        except BlockingIOError:
            return
        destination = None
        for level, kind, payload in ancillary:
            if level == socket.IPPROTO_IP and kind == _IP_PKTINFO:
                _, _, dst = struct.unpack("i4s4s", payload[:12])
                destination = socket.inet_ntoa(dst)
        record = {"socket": index, "source": list(source), "destination": destination,
                  "data": data.hex()}  # fmt: skip
        print(json.dumps(record), flush=True)


def lan_fixture() -> Iterator[Lan]:
    """Body of a ``lan`` fixture: skips (saying why) where namespaces cannot be made."""
    reason = unavailable()
    if reason is not None:
        pytest.skip(reason)
    lan = Lan()
    try:
        lan.create()
    except (OSError, subprocess.TimeoutExpired) as exc:
        pytest.skip(f"cannot create network namespaces here: {exc}")
    try:
        yield lan
    finally:
        lan.close()


if __name__ == "__main__" and sys.argv[1:2] == ["sniff"]:
    _sniff(int(sys.argv[2]), sys.argv[3], int(sys.argv[4]))
