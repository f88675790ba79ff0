"""A GCU that goes away and comes back, for outage tests over real sockets and ptys: the
simulator as a process (``gcu-async sim``) on a fixed address, which a test stops, starts and
restarts (a power cycle) while a client, a bridge or an application runs in the test's event
loop; and what each run of the simulator executed (its log).

    gcu = OutageRig("tcp", tmp_path)   # "udp", "tcp" or "serial"; nothing runs yet
    gcu.url                            # where to connect: the same across restarts
    await gcu.start()                  # a GCU at power-on; returns once it listens
    gcu.silence()                      # it stops answering for ``silence`` s, keeping its state
    await gcu.stop()                   # power off (what it executed is kept)
    await gcu.restart(30.0)            # stop, 30 s off, start; returns once it listens again
    gcu.executed()                     # Counter: opcode name -> executions over every run
    gcu.runs                           # the same, one Counter per run (per start)
    await gcu.close()                  # stop it if it runs, remove what the rig made

Every wait is bounded (the process start by :data:`START_TIMEOUT`); starting and stopping run
in a thread, so the test's event loop keeps its timers (a client's heartbeat) meanwhile.
Serial: each start serves a new pty; ``url`` names a symlink in the test's directory that
each start points at the new pty (atomically) and each stop removes, as a USB adapter
reappears under its udev name (``/dev/serial/by-id/…``). UDP and TCP: a loopback port chosen
free once, below the ephemeral range, which every start listens on again.
"""

from __future__ import annotations

import asyncio
import os
import random
import signal
import socket
import time
from collections import Counter
from pathlib import Path

from helpers.sim.process import SimProcess

START_TIMEOUT = 30.0
"""Seconds a simulator process may take to listen (an interpreter start on a loaded machine)."""
SCHEMES = ("udp", "tcp", "serial")


EPHEMERAL = Path("/proc/sys/net/ipv4/ip_local_port_range")
"""Where Linux keeps the range it picks ephemeral ports from (32768-60999 by default)."""


def _fixed_port(kind: int) -> int:
    """A loopback port free now and below the ephemeral range: while the simulator is off
    for minutes, no other process's ``bind(0)`` or outgoing connection can be handed it
    (the other processes of a parallel test run bind thousands of ephemeral ports)."""
    try:
        low = int(EPHEMERAL.read_text().split()[0])
    except (OSError, ValueError, IndexError):  # not Linux: any free port
        low = 0
    rng = random.Random()
    for _ in range(200):
        port = rng.randrange(10000, low) if low > 10000 else 0
        with socket.socket(socket.AF_INET, kind) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            found: int = s.getsockname()[1]
            return found
    raise RuntimeError(f"no free loopback port below {low}")


class OutageRig:
    """One simulated GCU on a fixed address (see the module docstring).

    ``pod``: the pod model each start simulates (a restart may change it: ``pod=``);
    ``silence``: how long :meth:`silence` silences it; ``args``: more ``gcu-async sim``
    options for every start."""

    def __init__(self, scheme: str, directory: Path, *, pod: str = "D-90Pro(TA)",
                 silence: float = 2.0, args: tuple[str, ...] = ()) -> None:  # fmt: skip
        if scheme not in SCHEMES:
            raise ValueError(f"scheme: {scheme!r} is not one of {SCHEMES}")
        self.scheme = scheme
        self.pod = pod
        self.silence_seconds = silence
        self.args = args
        self.runs: list[Counter[str]] = []
        """What each run executed, by opcode name (the running one's once it stopped)."""
        self.started_at: list[float] = []
        """``time.monotonic()`` at which each run was listening."""
        self.logs: list[str] = []
        """Each stopped run's log (stderr), for a failure's message."""
        self._process: SimProcess | None = None
        if scheme == "serial":
            self.link = directory / "ttyGCU"
            self.listen = "pty"
            self.url = f"serial://{self.link}"
        else:
            port = _fixed_port(socket.SOCK_DGRAM if scheme == "udp" else socket.SOCK_STREAM)
            self.listen = self.url = f"{scheme}://127.0.0.1:{port}"

    @property
    def running(self) -> bool:
        return self._process is not None

    async def start(self, *, pod: str | None = None) -> None:
        """Start a GCU at power-on (``pod``: this run's model, else the rig's)."""
        if self._process is not None:
            raise RuntimeError("OutageRig.start: the simulator runs already")
        args = ("--listen", self.listen, "--pod", pod or self.pod,
                "--silence", str(self.silence_seconds), *self.args)  # fmt: skip
        process = await asyncio.to_thread(SimProcess, *args, timeout=START_TIMEOUT)
        self._process = process
        if self.scheme == "serial":
            device = process.url.removeprefix("serial://")
            temporary = self.link.with_name(self.link.name + ".new")
            temporary.unlink(missing_ok=True)
            temporary.symlink_to(device)
            os.replace(temporary, self.link)
        self.started_at.append(time.monotonic())

    async def stop(self) -> None:
        """Power off: SIGTERM, wait, keep what it executed. Nothing if not running."""
        process, self._process = self._process, None
        if process is None:
            return
        if self.scheme == "serial":
            self.link.unlink(missing_ok=True)  # the adapter is gone
        executed = await asyncio.to_thread(process.executions)
        self.logs.append(process.log)
        by_name: Counter[str] = Counter()
        for (name, _), n in executed.items():
            by_name[name] += n
        self.runs.append(by_name)

    async def restart(self, down: float, *, pod: str | None = None) -> None:
        """Stop, stay off ``down`` seconds, start (a power cycle)."""
        await self.stop()
        await asyncio.sleep(down)
        await self.start(pod=pod)

    def silence(self) -> None:
        """The running GCU stops answering (and executing) for ``silence`` seconds, keeping
        its state: an outage that is no restart."""
        if self._process is None:
            raise RuntimeError("OutageRig.silence: the simulator is not running")
        self._process.proc.send_signal(signal.SIGUSR2)

    def executed(self) -> Counter[str]:
        """Executions by opcode name over every run that has stopped."""
        return sum(self.runs, Counter())

    async def close(self) -> None:
        """Stop the simulator if it runs; remove the symlink."""
        await self.stop()
        if self.scheme == "serial":
            self.link.unlink(missing_ok=True)
