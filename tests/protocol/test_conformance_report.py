"""The host conformance report (gcu_async.conformance.host): each check on hosts built
to break exactly one rule, a conforming host that breaks none, and this library's own client
over a real TCP socket against the simulator: no deviation."""

from __future__ import annotations

import asyncio
import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async import connect
from gcu_async.conformance import GAP_S, HostConformance, yaw_reading
from gcu_async.protocol import (
    AngleControl,
    CameraMask,
    Command,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    NullCommand,
    Record,
    TakePhoto,
    ZoomIn,
)
from gcu_async.protocol.packets import HOST_HEADER
from gcu_async.sim import GcuSimulator
from helpers.protocol.strategies import seal
from helpers.scale import scaled

LAT0, LON0, ALT0 = 35.0, 139.0, 100.0
M_PER_DEG = math.pi / 180 * 6_371_000.0


def packet(t: float, *, command: Command | None = None, yaw: float = 90.0,
           velocity: tuple[float, float, float] = (0.0, 0.0, 0.0),
           moved: tuple[float, float, float] | None = None, ins: bool = True) -> bytes:  # fmt: skip
    """A correct host packet at time ``t``: the aircraft moves with ``velocity`` (m/s, N/E/U)
    unless ``moved`` (the velocity its position really changes with) says otherwise."""
    vn, ve, vu = moved if moved is not None else velocity
    still = (0.0, 0.0, 0.0)
    main = HostMainFrame.build(
        attitude=(0.0, 0.0, yaw) if ins else None, acceleration=still if ins else None,
        velocity=velocity if ins else None)  # fmt: skip
    sub = HostSubFrame.build(
        latitude=LAT0 + vn * t / M_PER_DEG,
        longitude=LON0 + ve * t / (M_PER_DEG * math.cos(math.radians(LAT0))),
        altitude=ALT0 + vu * t, satellites=12)  # fmt: skip
    return HostPacket(main, sub, command or NullCommand()).encode()


def feed(packets: list[tuple[float, bytes]]) -> HostConformance:
    c = HostConformance()
    for t, data in packets:
        c.add(data, t)
    return c


def at_50hz(seconds: float, make) -> list[tuple[float, bytes]]:  # type: ignore[no-untyped-def]
    return [(i / 50, make(i, i / 50)) for i in range(round(seconds * 50))]


def with_yaw_raw(data: bytes, raw: int) -> bytes:
    body = bytearray(data[5:-2])
    body[11:13] = raw.to_bytes(2, "little")  # bytes 16–17 of the packet
    return seal(HOST_HEADER, bytes(body), data[4])


def test_a_conforming_host_shows_no_deviation_and_a_consistent_velocity() -> None:
    def make(i: int, t: float) -> bytes:
        cmd = TakePhoto() if i % 50 == 10 else None  # one photo a second, nulls between
        return packet(t, command=cmd, velocity=(3.0, -4.0, 1.0))

    report = feed(at_50hz(6, make)).report()
    assert report.deviations == (), report.text()
    assert any("consistent" in n for n in report.notes), report.notes
    assert "no deviation found" in report.text()
    assert report.as_dict()["conforms"] is True


def test_signed_yaw_is_recognised() -> None:
    report = feed(at_50hz(2, lambda i, t: with_yaw_raw(packet(t), 65536 - 11000))).report()
    yaw = report.get("main.aircraft_yaw_raw")
    assert yaw is not None and yaw.count == yaw.total == 100
    assert "100 % of packets" in yaw.diagnosis and "signed ±18000" in yaw.diagnosis
    assert yaw.examples[0].raw_hex.startswith("a8 e5")
    assert "-110.00°" in yaw.examples[0].decoded
    assert "not wrapped" in yaw_reading(40000)


def test_velocity_ten_times_too_small_is_recognised_as_dm_per_s() -> None:
    def make(i: int, t: float) -> bytes:  # moving 2.1 m/s up, velocity sent in dm/s
        return packet(t, velocity=(0.0, 0.0, 0.21), moved=(0.0, 0.0, 2.1))

    report = feed(at_50hz(5, make)).report()
    v = report.get("velocity.scale")
    assert v is not None and "(dm/s)" in v.diagnosis and "≈10×" in v.diagnosis, report.text()


def test_velocity_of_the_wrong_sign_and_no_motion() -> None:
    report = feed(at_50hz(5, lambda i, t: packet(t, velocity=(0, 0, -2.0), moved=(0, 0, 2.0))))
    v = report.report().get("velocity.scale")
    assert v is not None and "opposite sign" in v.diagnosis
    still = feed(at_50hz(5, lambda i, t: packet(t))).report()
    assert still.deviations == ()
    assert any("velocity scale not checked" in n for n in still.notes)


def test_a_mode_command_standing_instead_of_the_null_command() -> None:
    def make(i: int, t: float) -> bytes:
        return packet(t, command=TakePhoto() if i == 60 else AngleControl())

    report = feed(at_50hz(3, make)).report()
    d = report.get("opcode.standing.ANGLE_CONTROL")
    assert d is not None and d.count == 149, report.text()  # every 0x10 packet
    assert "never sends the null command" in d.diagnosis


def test_repeating_a_command_until_its_feedback_is_no_deviation() -> None:
    def make(i: int, t: float) -> bytes:  # photo in 3 consecutive packets, then nulls
        return packet(t, command=TakePhoto() if i % 25 in (5, 6, 7) else None)

    assert feed(at_50hz(2, make)).report().deviations == ()


def test_the_same_opcode_with_other_parameters_and_no_null_between() -> None:
    cmds = [ZoomIn(CameraMask.CAMERA_1), ZoomIn(CameraMask.CAMERA_2)]
    report = feed([(i / 50, packet(i / 50, command=c)) for i, c in enumerate(cmds)]).report()
    d = report.get("opcode.repeat_changed.ZOOM_IN")
    assert d is not None and d.count == 1
    assert "never runs" in d.diagnosis


def test_command_packets_with_an_all_zero_main_frame_and_ins_toggling() -> None:
    empty = HostPacket(HostMainFrame(subframe_request=1), None, Record()).encode()

    def make(i: int, t: float) -> bytes:
        return empty if i % 50 == 25 else packet(t)

    report = feed(at_50hz(4, make)).report()
    zero = report.get("main.all_zero")
    toggles = report.get("ins_valid.toggles")
    assert zero is not None and zero.count == 4
    assert toggles is not None and toggles.count == 4
    assert "toggles 8 times" in toggles.title
    assert "all-zero main frame" in toggles.diagnosis


def test_record_with_parameter_zero_is_diagnosed_as_start_stop() -> None:
    record_zero = seal(HOST_HEADER, packet(0.0)[5:69] + b"\x21\x00", 2)
    report = feed([(0.0, packet(0.0)), (0.02, record_zero)]).report()
    d = report.get("command.RECORD.cameras")
    assert d is not None and d.count == 1 and "0x00 stop" in d.diagnosis


def test_version_unknown_opcode_low_rate_and_gaps() -> None:
    v3 = seal(HOST_HEADER, packet(0.0)[5:69] + b"\x00", 3)
    unknown = seal(HOST_HEADER, packet(0.0)[5:69] + b"\x42\x01", 2)
    rows = [(i / 10, packet(i / 10)) for i in range(30)]  # 10 Hz for 3 s
    rows += [(3.0 + GAP_S + 0.3, v3), (3.9, unknown)]
    report = feed(rows).report()
    assert {"version", "opcode.unknown.0x42", "rate.low", "rate.gaps"} <= set(report.keys)
    gaps = report.get("rate.gaps")
    assert gaps is not None and (gaps.count, gaps.total) == (1, 31)  # of the 31 intervals
    assert "- rate.low: packet rate below 30 Hz\n" in report.text()


def test_examples_are_few_and_distinct_and_the_report_is_json() -> None:
    rows = [(i / 50, with_yaw_raw(packet(i / 50), 65536 - 100 * (i % 7 + 1))) for i in range(500)]
    report = feed(rows).report()
    d = report.get("main.aircraft_yaw_raw")
    assert d is not None and len(d.examples) == 3
    assert len({e.decoded for e in d.examples}) == 3
    document = json.loads(json.dumps(report.as_dict()))
    assert document["deviations"][0]["key"] == "main.aircraft_yaw_raw"
    assert document["packets"] == 500


def test_undecodable_bytes_are_counted() -> None:
    c = HostConformance()
    c.add(b"\xa8\xe5\x48\x00garbage", 0.0)
    assert c.report().undecodable == 1


@pytest.mark.realtime
async def test_this_librarys_client_conforms() -> None:
    """The client over real TCP, flying north-east and climbing, running the commands
    ArduPilot sends: the simulator's report finds nothing."""
    sim = GcuSimulator()
    async with (
        sim.serve_tcp("127.0.0.1", 0) as server,
        connect(f"tcp://127.0.0.1:{server.address[1]}") as gcu,
    ):
        loop = asyncio.get_running_loop()
        t0 = loop.time()
        velocity = (3.0, 4.0, 2.0)

        async def fly() -> None:
            while True:
                t = loop.time() - t0
                gcu.update_aircraft(
                    attitude=(0.0, 0.0, 250.0), acceleration=(0.0, 0.0, 0.0),
                    velocity=velocity, satellites=12,
                    position=(LAT0 + 3.0 * t / M_PER_DEG,
                              LON0 + 4.0 * t / (M_PER_DEG * math.cos(math.radians(LAT0))),
                              ALT0 + 2.0 * t))  # fmt: skip
                await asyncio.sleep(0.02)

        flying = asyncio.create_task(fly())
        try:
            await gcu.enter_angle_control(pitch=-30.0, yaw=40.0)
            await gcu.take_photo()
            await gcu.take_photo()
            await gcu.start_recording()
            await gcu.stop_recording()
            for step in (gcu.zoom_in, gcu.stop_zoom, gcu.zoom_out, gcu.stop_zoom, gcu.focus):
                await step()
            while loop.time() - t0 < 5.5:  # the velocity check needs ≥ 3 s of motion
                await asyncio.sleep(0.1)
        finally:
            flying.cancel()
    report = sim.model.conformance.report()
    assert report.deviations == (), report.text()
    assert any("consistent" in n for n in report.notes), report.notes
    assert sim.model.stats.frame_anomalies == sim.model.stats.anomalous == 0


@pytest.mark.parametrize("examples", [-1, 101])
def test_examples_argument_is_checked(examples: int) -> None:
    with pytest.raises(ValueError, match="examples"):
        HostConformance(examples=examples)


@settings(max_examples=scaled(200, 25), suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(
    bodies=st.lists(
        st.tuples(st.binary(min_size=64, max_size=64), st.integers(0, 255),
                  st.binary(max_size=16), st.integers(0, 255),
                  st.floats(0.0, 2.0, allow_nan=False)),
        min_size=1, max_size=30),
)  # fmt: skip
def test_any_crc_valid_host_packets_never_break_the_report(
    bodies: list[tuple[bytes, int, bytes, int, float]],
) -> None:
    """Hostile hosts: any frame bytes, opcode, parameters, version and timing."""
    c = HostConformance()
    t = 0.0
    for body, opcode, params, version, dt in bodies:
        t += dt
        c.add(seal(HOST_HEADER, body + bytes([opcode]) + params, version), t)
    report = c.report()
    assert report.packets == len(bodies)
    assert all(d.count >= 1 and len(d.examples) <= 3 for d in report.deviations)
    json.dumps(report.as_dict())
    assert report.text().startswith("Host conformance to V2.0.6")
    assert c.report().keys == report.keys  # reporting does not change the state
