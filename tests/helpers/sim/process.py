"""``gcu-async sim`` in a process of its own, for tests over real sockets whose faults must
not be skewed by the test's own event loop (a reorder hold is a timer: in the test's loop,
the client's work would stretch it). Its log tells which commands it executed."""

from __future__ import annotations

import os
import re
import selectors
import signal
import subprocess
import sys
import time
from collections import Counter

CLI = [sys.executable, "-c", "import sys; from gcu_async.cli import main; sys.exit(main())"]
EXECUTED = re.compile(r" executed (\w+) ([0-9a-f -]*?) -> status 0x([0-9A-F]{2})")


class SimProcess:
    """A running simulator: ``url`` to connect to; :meth:`stop` returns its log."""

    def __init__(self, *args: str, timeout: float = 15.0) -> None:
        self.proc = subprocess.Popen(
            [*CLI, "sim", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        assert self.proc.stdout is not None
        with selectors.DefaultSelector() as sel:
            sel.register(self.proc.stdout, selectors.EVENT_READ)
            if not sel.select(timeout):
                self.kill()
                raise TimeoutError("the simulator printed nothing")
        line = self.proc.stdout.readline()
        self.banner = line
        """Its first line: ``gcu-async sim: POD listening on URL``."""
        match = re.search(r"listening on (\S+)", line)
        if not match:
            self.kill()
            raise AssertionError(line)
        self.url = match.group(1)
        self.log = ""
        self._early = b""
        """What :meth:`wait_for` read of the log before :meth:`stop`."""

    def wait_for(self, text: str, timeout: float = 30.0) -> None:
        """Block until the log shows ``text`` (a readiness signal: the simulator executed a
        command, say), so a test acts on the event, not after a guessed sleep."""
        assert self.proc.stderr is not None
        fd = self.proc.stderr.fileno()
        deadline = time.monotonic() + timeout
        with selectors.DefaultSelector() as sel:
            sel.register(fd, selectors.EVENT_READ)
            while text.encode() not in self._early:
                left = deadline - time.monotonic()
                if left <= 0 or not sel.select(left):
                    raise TimeoutError(f"the simulator did not log {text!r} in {timeout} s")
                chunk = os.read(fd, 65536)
                if not chunk:
                    raise AssertionError(f"the simulator ended before logging {text!r}")
                self._early += chunk

    def stop(self) -> str:
        """SIGTERM, wait, return everything it logged (once)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            _, rest = self.proc.communicate(timeout=15)
            self.log = self._early.decode() + rest
        return self.log

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate(timeout=15)

    def executions(self) -> Counter[tuple[str, str]]:
        """(opcode name, parameter bytes in hex) → times executed, from its log."""
        return Counter((m.group(1), m.group(2)) for m in EXECUTED.finditer(self.stop()))
