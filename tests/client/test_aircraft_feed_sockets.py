"""The aircraft feed over a real UDP socket (loopback) against the simulator: the GCU sees
INS valid while the updates come, sees it cleared once they stop for ``aircraft_timeout``,
and valid again after the next update; GNSS time advances on the wire in between
(docs/client.md, "Aircraft data: what the packets claim")."""

from __future__ import annotations

import asyncio
import logging
import re
import subprocess
import sys
import time
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path

import pytest

from gcu_async import connect
from gcu_async.protocol import gps_to_utc
from gcu_async.protocol.gpstime import MS_PER_WEEK
from gcu_async.sim import GcuSimulator

TIMEOUT = 0.3
"""The client's aircraft_timeout in this test, seconds."""
STILL = (0.0, 0.0, 0.0)
FULL = {"attitude": (2.0, -1.0, 123.0), "acceleration": STILL, "velocity": (4.0, 3.0, 0.0),
        "position": (22.5, 113.9, 50.0)}  # fmt: skip


async def until(predicate: Callable[[], bool], limit: float, what: str) -> float:
    """Wait (polling every 2 ms, at most ``limit`` s) until ``predicate()``; the time then."""
    deadline = time.monotonic() + limit
    while not predicate():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0.002)
    return time.monotonic()


async def test_udp_ins_valid_goes_off_after_the_timeout_and_back_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="gcu_async.session")
    sim = GcuSimulator(pod="D-90Pro(TA)")
    seen = sim.model.state.aircraft
    async with (
        sim.serve_udp("127.0.0.1", 0) as server,
        connect(server.url, local_port=0, aircraft_timeout=TIMEOUT) as gcu,
    ):
        assert gcu.aircraft_timeout == TIMEOUT
        await until(lambda: seen.packets > 0, 2.0, "the first host packet")
        assert not seen.ins_valid  # nothing given: nothing claimed
        # a feed at 20 Hz for half a second: INS valid all along
        utc = datetime.now(timezone.utc)
        gcu.update_aircraft(**FULL, gnss_time=utc)
        given = gcu.aircraft.gnss_week * MS_PER_WEEK + gcu.aircraft.gnss_ms
        await until(lambda: seen.ins_valid, 2.0, "INS valid at the GCU")
        started = time.monotonic()
        while time.monotonic() - started < 0.5:
            gcu.update_aircraft(**FULL)  # no new time: it advances on its own
            await asyncio.sleep(0.05)
            assert seen.ins_valid and seen.has_sub_frame
        assert seen.attitude == FULL["attitude"] and seen.velocity == FULL["velocity"]
        # the GNSS time on the wire moved on with the clock since it was given
        advanced = seen.gnss_week * MS_PER_WEEK + seen.gnss_ms - given
        assert 450 <= advanced <= 2000, advanced
        assert gps_to_utc(seen.gnss_week, seen.gnss_ms) > utc
        # the feed stops: cleared after the timeout, not before
        last_update = time.monotonic()
        gcu.update_aircraft(**FULL)
        off = await until(lambda: not seen.ins_valid, TIMEOUT + 2.0, "INS cleared")
        assert TIMEOUT <= off - last_update <= TIMEOUT + 0.35, off - last_update
        assert not seen.has_sub_frame  # the position is as old: no sub frame either
        assert seen.ins_changes == 2  # invalid → valid → stale, nothing in between
        await asyncio.sleep(0.2)
        assert not seen.ins_valid and not gcu.ins_valid
        stats = gcu.session.stats
        assert stats.aircraft_stale == 1
        # the next update restores it
        gcu.update_aircraft(**FULL)
        assert gcu.ins_valid
        await until(lambda: seen.ins_valid and seen.has_sub_frame, 2.0, "INS valid again")
        assert seen.ins_changes == 3
        assert stats.aircraft_stale == 1
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING
                and r.name == "gcu_async.session"]  # fmt: skip
    assert len(warnings) == 1, warnings
    assert f"not updated for {TIMEOUT:g} s" in warnings[0] and server.url in warnings[0]


def test_the_client_guide_example_runs(tmp_path: Path) -> None:
    guide = (Path(__file__).resolve().parents[2] / "docs" / "client.md").read_text("utf-8")
    start = guide.index("<!-- aircraft-feed-example -->")
    match = re.compile(r"```python\n(.*?)```", re.DOTALL).search(guide, start)
    assert match is not None
    script = tmp_path / "feed.py"
    script.write_text(match.group(1), encoding="utf-8")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=30, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "stale episodes: 1"
    assert "aircraft data stale: attitude, acceleration, velocity, position" in done.stderr
