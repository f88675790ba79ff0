"""Run ArduPilot SITL (a real, hardware-tested XF host: ``AP_Mount_XFRobot``) against the
simulator and drive it with pymavlink like a ground station.

:func:`run_session` starts the simulator (TCP, a free port, in a background thread), the
``arducopter`` binary in a temporary directory on a free ``--base-port`` block with its
SERIAL2 as a TCP client of the simulator, then sends the gimbal and camera commands, waits
for GPS, arms and climbs (the velocity check of the conformance report needs motion) and
returns what it measured. Every wait is bounded; SITL is terminated in ``finally``.
"""

from __future__ import annotations

import asyncio
import contextlib
import gzip
import math
import random
import socket
import subprocess
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gcu_async.sim import GcuSimulator, MonotonicClock, SimulatorModel

XF_PARAMS = {"MNT1_TYPE": 14, "SERIAL2_PROTOCOL": 8, "SERIAL2_BAUD": 115, "CAM1_TYPE": 4}
"""XF Robot mount on SERIAL2 at 115200 baud; the camera library drives the mount's camera."""
HOME = "35.0,139.0,10,250"
"""Heading 250°: west of north, so ArduPilot's signed yaw shows in every attitude packet."""
BOOT_TIMEOUT = 30.0
GPS_TIMEOUT = 75.0
SETTLE_TIMEOUT = 6.0
AGREE_WAIT = 1.5
ANGLE_TOLERANCE = 0.5
"""Degrees: the simulator slews at 180 °/s and holds the target exactly; ArduPilot sends
0.01° steps."""

# MAVLink numbers (pymavlink's common dialect names them too; kept here for readability)
MOUNT_CONTROL = 205
GIMBAL_PITCHYAW = 1000
IMAGE_START = 2000
VIDEO_START, VIDEO_STOP = 2500, 2501
CAMERA_ZOOM, CAMERA_FOCUS = 531, 532
SET_MESSAGE_INTERVAL = 511
GIMBAL_DEVICE_ATTITUDE_STATUS = 285
YAW_IN_VEHICLE_FRAME, YAW_IN_EARTH_FRAME, YAW_LOCK = 32, 64, 16


def free_block() -> int:
    """A base port P with TCP P…P+2 and UDP P+10, P+11 free right now (SITL's ports),
    tried in random order so that SITL sessions in parallel workers rarely pick the same."""
    starts = list(range(21000, 60000, 97))
    random.SystemRandom().shuffle(starts)
    for start in starts:
        ok = True
        with contextlib.ExitStack() as stack:
            for offset, kind in [(0, socket.SOCK_STREAM), (1, socket.SOCK_STREAM),
                                 (2, socket.SOCK_STREAM), (10, socket.SOCK_DGRAM),
                                 (11, socket.SOCK_DGRAM)]:  # fmt: skip
                s = stack.enter_context(socket.socket(socket.AF_INET, kind))
                try:
                    s.bind(("127.0.0.1", start + offset))
                except OSError:
                    ok = False
                    break
        if ok:
            return start
    raise RuntimeError("no free port block for SITL")


class TappedClock(MonotonicClock):
    """The monotonic clock, remembering the last time it told."""

    last = 0.0

    def now(self) -> float:
        self.last = super().now()
        return self.last



def end_process(proc: subprocess.Popen[Any]) -> None:
    """SIGTERM ``proc``; SIGKILL if it is still there after 10 s (SITL, the bridge)."""
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(10)

class RecordingModel(SimulatorModel):
    """The simulator's model, keeping every (time, host packet, reply) it handled; the
    time is the one the model used for the packet (a replay on these times repeats it)."""

    def __init__(self, **kwargs: Any) -> None:
        self.tapped = TappedClock()
        super().__init__(record_executions=True, clock=self.tapped, **kwargs)
        self.conversation: list[tuple[float, bytes, bytes]] = []
        self.lock = threading.Lock()

    def handle_bytes(self, packet: bytes) -> bytes | None:
        with self.lock:
            reply = super().handle_bytes(packet)
            self.conversation.append((self.tapped.last, packet, reply or b""))
            return reply


class SimThread:
    """The simulator on a TCP port of 127.0.0.1, served by an event loop in a thread."""

    def __init__(self, model: SimulatorModel) -> None:
        self.sim = GcuSimulator(model)
        self.port = 0
        self._loop = asyncio.new_event_loop()
        self._stop: asyncio.Event | None = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)

        async def main() -> None:
            self._stop = asyncio.Event()
            async with self.sim.serve_tcp("127.0.0.1", 0) as server:
                self.port = server.address[1]
                self._ready.set()
                await self._stop.wait()

        self._loop.run_until_complete(main())

    def __enter__(self) -> SimThread:
        self._thread.start()
        if not self._ready.wait(10):
            raise RuntimeError("the simulator did not start")
        return self

    def __exit__(self, *exc: object) -> None:
        if self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(10)
        if not self._thread.is_alive():
            self._loop.close()


@dataclass
class AngleCheck:
    """One angle command: what was asked, what the simulator reached, what ArduPilot says."""

    how: str
    target: tuple[float, float]
    """(pitch, yaw) as the check compares them (yaw relative or absolute, per ``frame``)."""
    frame: str
    sim: tuple[float, float] = (math.nan, math.nan)
    ardupilot: tuple[float, float] = (math.nan, math.nan)
    """Pitch and yaw of ArduPilot's GIMBAL_DEVICE_ATTITUDE_STATUS (yaw relative to the
    vehicle, as the driver reports it)."""
    sim_relative_yaw: float = math.nan
    settle_s: float = math.nan


@dataclass
class Session:
    angles: list[AngleCheck] = field(default_factory=list)
    texts: list[str] = field(default_factory=list)
    acks: list[tuple[int, int]] = field(default_factory=list)
    """(command, MAV_RESULT) of every COMMAND_ACK."""
    recording_after_start: bool | None = None
    recording_after_stop: bool | None = None
    zoom: dict[str, float] = field(default_factory=dict)
    photos: int = 0
    focus: int = 0
    armed: bool = False
    climb_m: float = 0.0
    model: RecordingModel | None = None
    boot_s: float = 0.0
    total_s: float = 0.0


def euler_to_quaternion(roll: float, pitch: float, yaw: float) -> list[float]:
    cr, sr = math.cos(math.radians(roll) / 2), math.sin(math.radians(roll) / 2)
    cp, sp = math.cos(math.radians(pitch) / 2), math.sin(math.radians(pitch) / 2)
    cy, sy = math.cos(math.radians(yaw) / 2), math.sin(math.radians(yaw) / 2)
    return [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]  # fmt: skip


def quaternion_to_euler(q: list[float]) -> tuple[float, float, float]:
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return math.degrees(roll), math.degrees(pitch), math.degrees(yaw)


def wrap180(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0


class Driver:
    """A ground station on SITL's MAVLink port (pymavlink), reading as it waits."""

    def __init__(self, port: int, model: RecordingModel, session: Session) -> None:
        from pymavlink import mavutil

        self.mavutil = mavutil
        self.model = model
        self.session = session
        self.last: dict[str, Any] = {}
        deadline = time.monotonic() + BOOT_TIMEOUT
        while True:
            try:
                self.m = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=255,
                                                    retries=0)  # fmt: skip
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        if self.m.wait_heartbeat(timeout=BOOT_TIMEOUT) is None:
            raise RuntimeError("no heartbeat from SITL")
        self.m.mav.request_data_stream_send(1, 1, mavutil.mavlink.MAV_DATA_STREAM_ALL, 10, 1)
        self.command(SET_MESSAGE_INTERVAL, GIMBAL_DEVICE_ATTITUDE_STATUS, 100_000)

    def command(self, number: int, *params: float) -> None:
        p = [float(x) for x in params] + [0.0] * (7 - len(params))
        self.m.mav.command_long_send(1, 1, number, 0, *p)

    def pump(self, seconds: float, until: Any = None) -> bool:
        """Read MAVLink for up to ``seconds``; True as soon as ``until()`` holds."""
        end = time.monotonic() + seconds
        while True:
            if until is not None and until():
                return True
            left = end - time.monotonic()
            if left <= 0:
                return False
            msg = self.m.recv_match(blocking=True, timeout=min(0.1, left))
            if msg is None:
                continue
            kind = msg.get_type()
            self.last[kind] = msg
            if kind == "STATUSTEXT":
                self.session.texts.append(msg.text)
            elif kind == "COMMAND_ACK":
                self.session.acks.append((msg.command, msg.result))

    def said(self, text: str) -> bool:
        return any(text in t for t in self.session.texts)

    def sim_state(self) -> tuple[float, float, float]:
        """(relative pitch, relative yaw, absolute yaw) of the simulated camera."""
        with self.model.lock:
            rel = self.model.state.relative
            att = self.model.state.attitude
        return rel.pitch, rel.yaw, att.yaw % 360.0

    def vehicle_yaw(self) -> float:
        att = self.last.get("ATTITUDE")
        return math.degrees(att.yaw) % 360.0 if att is not None else math.nan

    def check_angle(self, check: AngleCheck, send: Any) -> None:
        start = time.monotonic()
        send()
        pitch, yaw = check.target

        def reached() -> bool:
            p, rel_yaw, abs_yaw = self.sim_state()
            y = rel_yaw if check.frame == "vehicle" else abs_yaw
            return abs(p - pitch) < ANGLE_TOLERANCE and abs(wrap180(y - yaw)) < ANGLE_TOLERANCE

        self.pump(SETTLE_TIMEOUT, reached)
        check.settle_s = time.monotonic() - start
        # MAVLink messages queue up in the socket: read on for a while, then take the
        # newest status (ArduPilot sends it at 10 Hz from the GCU's latest reply) and the
        # simulator's settled angles
        self.last.pop("GIMBAL_DEVICE_ATTITUDE_STATUS", None)
        self.pump(AGREE_WAIT)
        p, rel_yaw, abs_yaw = self.sim_state()
        check.sim = (p, rel_yaw if check.frame == "vehicle" else abs_yaw)
        check.sim_relative_yaw = rel_yaw
        status = self.last.get("GIMBAL_DEVICE_ATTITUDE_STATUS")
        if status is not None:
            _, ap_pitch, ap_yaw = quaternion_to_euler(list(status.q))
            check.ardupilot = (ap_pitch, ap_yaw)
        self.session.angles.append(check)


def run_session(binary: Path, workdir: Path, *, fly: bool = True) -> Session:
    """The whole conversation; see the module docstring."""
    session = Session()
    model = RecordingModel()
    session.model = model
    t0 = time.monotonic()
    with SimThread(model) as sim:
        base = free_block()
        params = workdir / "xfrobot.parm"
        params.write_text("".join(f"{k} {v}\n" for k, v in XF_PARAMS.items()))
        defaults = [str(params)]
        copter = binary.parent / "copter.parm"  # ArduPilot's default copter parameters
        if copter.exists():
            defaults.insert(0, str(copter))
        cmd = [str(binary), "-w", "--model", "+", "--speedup", "1", "--home", HOME,
               "--defaults", ",".join(defaults), "--base-port", str(base),
               "--rc-in-port", str(base + 10), "--irlock-port", str(base + 11),
               "--serial2", f"tcpclient:127.0.0.1:{sim.port}"]  # fmt: skip
        log = (workdir / "sitl.log").open("wb")
        proc = subprocess.Popen(cmd, cwd=workdir, stdout=log, stderr=subprocess.STDOUT)
        driver = None
        try:
            driver = Driver(base, model, session)
            drive(driver, session, fly=fly, t0=t0)
        finally:
            if driver is not None:
                driver.m.close()
            end_process(proc)
            log.close()
    session.total_s = time.monotonic() - t0
    return session


def drive(d: Driver, s: Session, *, fly: bool, t0: float) -> None:
    if not d.pump(BOOT_TIMEOUT, lambda: d.said("XFRobot: hw:")):
        raise RuntimeError(f"ArduPilot never heard the gimbal; it said {s.texts}")
    s.boot_s = time.monotonic() - t0
    d.pump(1.0)
    mav = d.mavutil.mavlink
    # 1. angles, in every form ArduPilot takes them
    d.check_angle(AngleCheck("DO_MOUNT_CONTROL", (-30.0, 40.0), "vehicle"),
                  lambda: d.command(MOUNT_CONTROL, -30, 0, 40, 0, 0, 0,
                                    mav.MAV_MOUNT_MODE_MAVLINK_TARGETING))  # fmt: skip
    d.check_angle(AngleCheck("DO_GIMBAL_MANAGER_PITCHYAW vehicle frame", (-20.0, -25.0),
                             "vehicle"),
                  lambda: d.command(GIMBAL_PITCHYAW, -20, -25, math.nan, math.nan,
                                    YAW_IN_VEHICLE_FRAME))  # fmt: skip
    earth_yaw = 200.0
    d.check_angle(AngleCheck("DO_GIMBAL_MANAGER_PITCHYAW earth frame", (-10.0, earth_yaw),
                             "earth"),
                  lambda: d.command(GIMBAL_PITCHYAW, -10, earth_yaw, math.nan, math.nan,
                                    YAW_LOCK | YAW_IN_EARTH_FRAME))  # fmt: skip

    def set_attitude() -> None:
        d.m.mav.gimbal_manager_set_attitude_send(1, 1, YAW_IN_VEHICLE_FRAME, 0,
                                                 euler_to_quaternion(0, -45, 30),
                                                 math.nan, math.nan, math.nan)  # fmt: skip

    d.check_angle(AngleCheck("GIMBAL_MANAGER_SET_ATTITUDE", (-45.0, 30.0), "vehicle"),
                  set_attitude)  # fmt: skip
    state = d.model.state
    # 2. photo twice, record start and stop, zoom in/stop/out/stop, focus
    for _ in range(2):
        before = sum(state.camera.photos.values())
        d.command(IMAGE_START, 0, 0, 1)
        d.pump(3.0, lambda b=before: sum(state.camera.photos.values()) > b)
        d.pump(0.5)
    s.photos = sum(state.camera.photos.values())
    d.command(VIDEO_START, 0)
    d.pump(3.0, lambda: d.said("recording ON"))
    s.recording_after_start = state.camera.recording
    d.pump(0.5)
    d.command(VIDEO_STOP, 0)
    d.pump(3.0, lambda: d.said("recording OFF") or d.said("failed to stop"))
    s.recording_after_stop = state.camera.recording
    s.zoom["start"] = state.zoom[1]
    for rate, name in ((1, "in"), (0, "stop_in"), (-1, "out"), (0, "stop_out")):
        d.command(CAMERA_ZOOM, mav.ZOOM_TYPE_CONTINUOUS, rate)
        d.pump(1.0)
        s.zoom[name] = state.zoom[1]
    d.pump(0.5)
    s.zoom["after_stop"] = state.zoom[1]
    d.command(CAMERA_FOCUS, mav.FOCUS_TYPE_AUTO, 0)
    d.pump(2.0, lambda: state.camera.focus_count > 0)
    s.focus = state.camera.focus_count
    if not fly:
        return
    # 3. fly: GPS, guided, arm, take off (a climb for the velocity check)
    deadline = time.monotonic() + GPS_TIMEOUT
    while time.monotonic() < deadline and not s.armed:
        d.m.set_mode("GUIDED")
        d.command(400, 1)  # MAV_CMD_COMPONENT_ARM_DISARM
        s.armed = d.pump(2.0, lambda: bool(d.last.get("HEARTBEAT") and
                                           d.last["HEARTBEAT"].base_mode & 128))  # fmt: skip
    if not s.armed:
        return
    d.command(22, 0, 0, 0, 0, 0, 0, 10)  # MAV_CMD_NAV_TAKEOFF to 10 m
    d.pump(9.0)  # ≥ 4 windows of 1 s climbing for the velocity check
    pos = d.last.get("GLOBAL_POSITION_INT")
    s.climb_m = pos.relative_alt / 1000 if pos is not None else 0.0


# -- the recorded conversation (tests/data) ----------------------------------------------------
HEADER = """\
A conversation between ArduPilot SITL 4.7.0 (arducopter, commit 1511f27, built unmodified;
its AP_Mount_XFRobot driver is the host) and the gcu_async simulator (D-90Pro(TA)), recorded
by tests/helpers/sitl/ardupilot.py (GCU_SITL_RECORD=FILE with tests/sitl/test_sitl_ardupilot.py):
boot, DO_MOUNT_CONTROL, DO_GIMBAL_MANAGER_PITCHYAW (vehicle and earth frame),
GIMBAL_MANAGER_SET_ATTITUDE, photo x2, record start/stop, zoom in/stop/out/stop, focus,
GPS lock, arm, take-off to 10 m. Home 35.0 N 139.0 E heading 250 deg.
One line per host packet: milliseconds since the first, host packet hex, simulator reply hex."""


def save_conversation(path: Path, rows: list[tuple[float, bytes, bytes]], header: str) -> None:
    """``# header`` lines, then one line per host packet: ``milliseconds host-hex reply-hex``
    (time since the first packet), gzip-compressed."""
    t0 = rows[0][0]
    lines = [f"# {line}" for line in header.splitlines()]
    lines += [f"{(t - t0) * 1000:.1f} {p.hex()} {r.hex()}" for t, p, r in rows]
    with gzip.open(path, "wt", encoding="ascii", compresslevel=9) as f:
        f.write("\n".join(lines) + "\n")


def load_conversation(path: Path) -> list[tuple[float, bytes, bytes]]:
    """What :func:`save_conversation` wrote: (seconds, host packet, reply)."""
    rows = []
    with gzip.open(path, "rt", encoding="ascii") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            ms, host, reply = line.split()
            rows.append((float(ms) / 1000, bytes.fromhex(host), bytes.fromhex(reply)))
    return rows
