"""The MAVLink bridge fed by a real autopilot: ArduPilot SITL on the bridge's MAVLink link
(SITL's SERIAL1, a TCP server on base port + 2), the simulator as the bridge's GCU, and a
ground station on SITL's own port that drives the gimbal through ArduPilot's MAVLink routing
(docs/ardupilot-sitl.md, "The bridge with ArduPilot as the autopilot").

Runs the ``arducopter`` binary named by ``GCU_ARDUPILOT_SITL`` (skipped when unset). The
aircraft state the bridge puts into its host packets (attitude, velocity, position, GNSS
time, INS valid) is compared with ArduPilot's own ATTITUDE, GLOBAL_POSITION_INT and
SYSTEM_TIME as the ground station receives them, at rest and climbing.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from datetime import datetime, timedelta, timezone
from pathlib import Path
from typing import Any

import pytest

from gcu_async.protocol import decode_host_packet
from gcu_async.protocol.host_frames import HostSubFrame
from helpers.sitl.ardupilot import (
    HOME,
    Driver,
    RecordingModel,
    Session,
    SimThread,
    end_process,
    free_block,
    wrap180,
)

ENV = "GCU_ARDUPILOT_SITL"
STREAMS = {"MAV2_EXTRA1": 20, "MAV2_POSITION": 10, "MAV2_EXT_STAT": 5, "MAV2_EXTRA3": 5}
"""SERIAL1's stream rates (ArduPilot 4.7 names; SR1_* before): ATTITUDE, GLOBAL_POSITION_INT
and LOCAL_POSITION_NED, GPS_RAW_INT, SYSTEM_TIME."""
INS_TIMEOUT = 90.0
TOLERANCE = {"position_m": 1.0, "time_s": 0.5}
RECENT_S = 1.0
"""The attitude in the bridge's host packet must be one ArduPilot reported: per axis within
the range of the ATTITUDE messages the ground station received in the last second (+0.05°
rounding). A window, not a staleness bound: ArduPilot, the bridge and this test are three
processes, and a loaded machine delays either copy. Velocity may differ by three times the
change between two GLOBAL_POSITION_INT (+0.05 m/s: the bridge's copy at most three 10 Hz
messages old)."""


@dataclass
class Comparison:
    """Worst differences between the bridge's host packets and ArduPilot's messages."""

    samples: int = 0
    attitude_deg: float = 0.0
    attitude_excess_deg: float = -math.inf
    """Worst distance of the bridge's attitude outside what ArduPilot reported within
    :data:`RECENT_S`, less 0.05° (≤ 0: within)."""
    velocity_m_s: float = 0.0
    velocity_excess_m_s: float = -math.inf
    position_m: float = 0.0
    time_s: float = 0.0
    climb_m_s: list[float] = field(default_factory=list)


@dataclass
class BridgeRun:
    ins_valid_after_s: float = math.nan
    compared: Comparison = field(default_factory=Comparison)
    gimbal: tuple[float, float] = (math.nan, math.nan)
    acks: list[tuple[int, int]] = field(default_factory=list)
    bridge_log: str = ""
    host_packets: int = 0


def latest_host(model: RecordingModel) -> Any:
    with model.lock:
        return decode_host_packet(model.conversation[-1][1]) if model.conversation else None


def compare(d: Driver, model: RecordingModel, out: Comparison, seconds: float) -> None:
    """At each ATTITUDE / GLOBAL_POSITION_INT / SYSTEM_TIME the ground station receives, the
    simulator's latest host packet from the bridge (sent within the last 20 ms)."""
    end = time.monotonic() + seconds
    previous_velocity: tuple[float, float, float] | None = None
    recent: deque[tuple[float, tuple[float, float, float]]] = deque()
    while time.monotonic() < end:
        msg = d.m.recv_match(blocking=True, timeout=0.1)
        if msg is None:
            continue
        d.last[msg.get_type()] = msg
        host = latest_host(model)
        if host is None or not host.main.ins_valid:
            continue
        kind = msg.get_type()
        if kind == "ATTITUDE":
            a = (host.main.aircraft_attitude.roll, host.main.aircraft_attitude.pitch,
                 host.main.aircraft_attitude.yaw)  # fmt: skip
            now = time.monotonic()
            recent.append((now, (math.degrees(msg.roll), math.degrees(msg.pitch),
                                 math.degrees(msg.yaw))))  # fmt: skip
            while recent[0][0] < now - RECENT_S:
                recent.popleft()
            errors = [wrap180(a[axis] - recent[-1][1][axis]) for axis in range(3)]
            out.attitude_deg = max(out.attitude_deg, *map(abs, errors))
            for axis in range(3):  # how far outside the recent reports' range, per axis
                offsets = [wrap180(a[axis] - seen[axis]) for _, seen in recent]
                outside = max(min(offsets), -max(offsets), 0.0)
                out.attitude_excess_deg = max(out.attitude_excess_deg, outside - 0.05)
            out.samples += 1
        elif kind == "GLOBAL_POSITION_INT" and isinstance(host.sub, HostSubFrame):
            v = host.main.velocity
            now_v = (msg.vx / 100, msg.vy / 100, -msg.vz / 100)
            worst = max(abs(a - b) for a, b in zip(v, now_v, strict=True))
            change = 0.0 if previous_velocity is None else max(
                abs(a - b) for a, b in zip(now_v, previous_velocity, strict=True))  # fmt: skip
            previous_velocity = now_v
            out.velocity_m_s = max(out.velocity_m_s, worst)
            out.velocity_excess_m_s = max(out.velocity_excess_m_s, worst - 3 * change - 0.05)
            if msg.vz < -50:
                out.climb_m_s.append(-msg.vz / 100)
            sub = host.sub
            north = (sub.latitude - msg.lat / 1e7) * 111_195
            east = (sub.longitude - msg.lon / 1e7) * 111_195 * math.cos(math.radians(sub.latitude))
            up = sub.altitude - msg.alt / 1000
            out.position_m = max(out.position_m, math.hypot(north, east, up))
        elif kind == "SYSTEM_TIME" and msg.time_unix_usec and isinstance(host.sub, HostSubFrame):
            epoch = datetime(1970, 1, 1, tzinfo=timezone.utc)
            utc = epoch + timedelta(microseconds=msg.time_unix_usec)
            out.time_s = max(out.time_s, abs((host.sub.gnss_time() - utc).total_seconds()))


def run_bridge(binary: Path, workdir: Path) -> BridgeRun:
    run = BridgeRun()
    model = RecordingModel()
    session = Session()
    with SimThread(model) as sim:
        base = free_block()
        params = workdir / "streams.parm"
        params.write_text("".join(f"{k} {v}\n" for k, v in STREAMS.items()))
        defaults = [str(params)]
        if (binary.parent / "copter.parm").exists():
            defaults.insert(0, str(binary.parent / "copter.parm"))
        sitl = subprocess.Popen(
            [str(binary), "-w", "--model", "+", "--speedup", "1", "--home", HOME,
             "--defaults", ",".join(defaults), "--base-port", str(base),
             "--rc-in-port", str(base + 10), "--irlock-port", str(base + 11)],
            cwd=workdir, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)  # fmt: skip
        bridge = None
        d = None
        t0 = time.monotonic()
        try:
            d = Driver(base, model, session)
            bridge = subprocess.Popen(
                [sys.executable, "-m", "gcu_async.cli", "mavlink-bridge",
                 f"tcp://127.0.0.1:{sim.port}", "--mavlink", f"tcp:127.0.0.1:{base + 2}"],
                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)  # fmt: skip

            def ins_valid() -> bool:
                host = latest_host(model)
                return bool(host is not None and host.main.ins_valid)

            if not d.pump(INS_TIMEOUT, ins_valid):
                return run
            run.ins_valid_after_s = time.monotonic() - t0
            compare(d, model, run.compared, 4.0)  # at rest
            # the gimbal, through ArduPilot's routing to the bridge (component 154)
            d.m.mav.command_long_send(1, 154, 1000, 0, -20, 30, math.nan, math.nan, 0, 0, 0)
            d.pump(3.0)
            rel = model.state.relative
            run.gimbal = (rel.pitch, rel.yaw)
            # climb: arm in GUIDED and take off, comparing as it goes
            for _ in range(10):
                d.m.set_mode("GUIDED")
                d.command(400, 1)
                if d.pump(2.0, lambda: bool(d.last.get("HEARTBEAT") and
                                            d.last["HEARTBEAT"].base_mode & 128)):  # fmt: skip
                    break
            d.command(22, 0, 0, 0, 0, 0, 0, 10)
            compare(d, model, run.compared, 7.0)
        finally:
            run.acks = list(session.acks)
            run.host_packets = len(model.conversation)
            if bridge is not None:
                bridge.terminate()
                try:
                    run.bridge_log = bridge.communicate(timeout=15)[0]
                except subprocess.TimeoutExpired:
                    bridge.kill()
                    run.bridge_log = bridge.communicate(timeout=15)[0]
            if d is not None:
                d.m.close()
            end_process(sitl)
    return run


@pytest.fixture(scope="module")
def bridge_run(tmp_path_factory: pytest.TempPathFactory) -> BridgeRun:
    binary = os.environ.get(ENV)
    if not binary:
        pytest.skip(f"{ENV} is not set: no ArduPilot SITL binary (arducopter) to run")
    pytest.importorskip("pymavlink", reason="pymavlink (the mavlink extra) drives SITL")
    result = run_bridge(Path(binary).resolve(), tmp_path_factory.mktemp("sitl-bridge"))
    c = result.compared
    print(f"\nbridge: INS valid after {result.ins_valid_after_s:.1f} s, {c.samples} attitude "
          f"samples; worst: attitude {c.attitude_deg:.2f}° (excess {c.attitude_excess_deg:+.2f}), "
          f"velocity {c.velocity_m_s:.2f} m/s (excess {c.velocity_excess_m_s:+.2f}), "
          f"position {c.position_m:.2f} m, GNSS time {c.time_s:.3f} s; climb samples "
          f"{len(c.climb_m_s)} (up to {max(c.climb_m_s, default=0):.1f} m/s); gimbal "
          f"{result.gimbal}")  # fmt: skip
    return result


def test_the_bridge_sends_ins_valid_with_ardupilots_state(bridge_run: BridgeRun) -> None:
    assert not math.isnan(bridge_run.ins_valid_after_s), bridge_run.bridge_log[-2000:]
    c = bridge_run.compared
    assert c.samples > 50
    assert c.attitude_excess_deg <= 0  # an attitude ArduPilot reported (RECENT_S)
    assert c.position_m < TOLERANCE["position_m"]
    assert c.time_s < TOLERANCE["time_s"]


def test_the_velocity_agrees_while_climbing(bridge_run: BridgeRun) -> None:
    c = bridge_run.compared
    assert len(c.climb_m_s) >= 5 and max(c.climb_m_s) > 1.0  # it did climb
    assert c.velocity_excess_m_s <= 0  # equal but for up to three messages' change


def test_a_ground_station_drives_the_gimbal_through_ardupilot(bridge_run: BridgeRun) -> None:
    assert (1000, 0) in bridge_run.acks  # MAV_RESULT_ACCEPTED, from the bridge
    pitch, yaw = bridge_run.gimbal
    assert abs(pitch + 20) < 0.5 and abs(wrap180(yaw - 30)) < 0.5
