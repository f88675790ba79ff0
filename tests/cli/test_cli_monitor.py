"""`gcu-async monitor` through the real entry point against `gcu-async sim` (another
process): JSON lines, lines during an outage, a clean end on SIGTERM and Ctrl-C."""

from __future__ import annotations

import json
import re
import selectors
import signal
import subprocess
import time
from collections.abc import Iterator

import pytest

from helpers.sim.process import CLI, SimProcess


def read_lines(proc: subprocess.Popen[str], n: int, timeout: float) -> list[str]:
    """The next ``n`` lines of ``proc``'s stdout (bounded)."""
    assert proc.stdout is not None
    lines: list[str] = []
    deadline = time.monotonic() + timeout
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        while len(lines) < n:
            left = deadline - time.monotonic()
            if left <= 0 or not sel.select(left):
                raise AssertionError(f"only {len(lines)} of {n} lines: {lines}")
            line = proc.stdout.readline()
            if not line:
                raise AssertionError(f"monitor ended after {lines}")
            lines.append(line.rstrip("\n"))
    return lines


@pytest.fixture
def sim() -> Iterator[SimProcess]:
    process = SimProcess("--listen", "udp://127.0.0.1:0", "--silence", "1.5")
    yield process
    process.stop()


def monitor(sim: SimProcess, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([*CLI, "monitor", f"{sim.url}?local_port=0", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip


def test_json_lines_follow_the_decode_shape(sim: SimProcess) -> None:
    done = subprocess.run([*CLI, "monitor", f"{sim.url}?local_port=0", "--json", "--count",
                           "3", "--interval", "0.1"], capture_output=True, text=True,
                          timeout=30, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    objects = [json.loads(line) for line in done.stdout.splitlines()]
    assert len(objects) == 3
    for obj in objects:
        assert obj["status"]["mode"] and "attitude_deg" in obj["status"]
        assert obj["link"]["up"] is True and obj["link"]["packets_received"] > 0
        assert obj["info"] is None or "camera1_zoom" in json.dumps(obj["info"])
    assert objects[0]["time"] < objects[1]["time"] < objects[2]["time"]


@pytest.mark.parametrize("as_json", [False, True])
def test_an_outage_prints_lines_and_sigterm_ends_it_cleanly(sim: SimProcess,
                                                            as_json: bool) -> None:
    proc = monitor(sim, "--interval", "0.2", *(["--json"] if as_json else []))
    try:
        read_lines(proc, 2, 10.0)  # live
        sim.proc.send_signal(signal.SIGUSR2)  # the GCU goes silent for 1.5 s
        lines = read_lines(proc, 12, 10.0)
        if as_json:
            objects = [json.loads(line) for line in lines]
            quiet = [o for o in objects if o["status"] is None]
            assert quiet and quiet[-1]["link"]["up"] is False  # silence_timeout 1 s
            assert objects[-1]["status"] is not None  # back after the outage
        else:
            quiet = [line for line in lines if line.startswith("link ")]
            assert any(line.startswith("link DOWN: no reply for ") for line in quiet), lines
            assert not lines[-1].startswith("link ")  # telemetry again
    finally:
        ended_cleanly_by(proc, signal.SIGTERM)


def test_ctrl_c_ends_it_with_130(sim: SimProcess) -> None:
    proc = monitor(sim, "--interval", "0.1")
    try:
        read_lines(proc, 1, 10.0)
    finally:
        ended_cleanly_by(proc, signal.SIGINT)


def ended_cleanly_by(proc: subprocess.Popen[str], sig: signal.Signals) -> None:
    """Send ``sig``; the process must end with 130 and no traceback (killed otherwise)."""
    try:
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130
    assert "Traceback" not in err, err


def test_a_negative_count_is_a_usage_error() -> None:
    done = subprocess.run([*CLI, "monitor", "udp://127.0.0.1:9", "--count", "-1"],
                          capture_output=True, text=True, timeout=30, check=False)  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.startswith("gcu-async monitor: --count: -1")


def test_no_rate_while_its_window_is_still_filling(sim: SimProcess) -> None:
    """The reply rate counts the replies of the last second: the lines less than a second
    after the first reply show none (``-/s``, JSON ``null``) rather than a low figure."""
    for as_json in (False, True):
        done = subprocess.run([*CLI, "monitor", f"{sim.url}?local_port=0", "--count", "4",
                               "--interval", "0.4", *(["--json"] if as_json else [])],
                              capture_output=True, text=True, timeout=30, check=False)  # fmt: skip
        assert done.returncode == 0, done.stderr
        lines = done.stdout.splitlines()
        assert len(lines) == 4
        if as_json:
            rates = [json.loads(line)["link"]["reply_rate"] for line in lines]
        else:
            rates = [re.search(r"link up (\S+)/s", line)[1] for line in lines]  # type: ignore[index]
        # lines at about 0, 0.4, 0.8, 1.2 s after the first reply: the last one past 1 s
        assert rates[0] in (None, "-"), lines
        assert rates[-1] not in (None, "-") and float(rates[-1]) > 10, lines
        known = [r not in (None, "-") for r in rates]
        assert known == sorted(known), lines  # once known, it stays known


def test_a_reader_that_leaves_ends_it_quietly(sim: SimProcess) -> None:
    """``gcu-async monitor URL | head -n 1``: once the reader has gone, it stops with
    status 0 and says nothing (no "Broken pipe", no traceback)."""
    proc = monitor(sim, "--interval", "0.1")
    read_lines(proc, 1, 10.0)
    assert proc.stdout is not None
    proc.stdout.close()
    try:
        _, err = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert (proc.returncode, err) == (0, "")


def test_help_says_what_its_heartbeat_does_and_points_to_passive() -> None:
    done = subprocess.run([*CLI, "monitor", "--help"], capture_output=True, text=True,
                          timeout=30, check=False)  # fmt: skip
    text = " ".join(done.stdout.split())
    assert "sends its own heartbeat (50 packets/s, no aircraft data, control values invalid)" \
        in text  # fmt: skip
    assert "a 20 °/s pointing-lock rate came out at 4-16 °/s" in text
    assert "use --passive (UDP): it sends nothing" in text
    assert "--passive listen only (udp://)" in text
    assert "Not for tcp:// or serial://" in text
