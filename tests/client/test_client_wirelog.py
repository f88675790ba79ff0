"""The wire logger (docs/client.md, "Logging"): every packet in and out at DEBUG on
``gcu_async.wire`` with its hex and a one-line decode; lifecycle at INFO; nothing while off."""

from __future__ import annotations

import asyncio
import logging
import subprocess

import pytest

from gcu_async import GcuClient
from gcu_async.client.wirelog import describe_gcu, describe_host
from gcu_async.protocol import (
    AircraftState,
    ControlValues,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostPacket,
    TakePhoto,
    TimeZone,
    ZoomTo,
)
from gcu_async.pytest_plugin import SimHandle
from helpers.protocol.strategies import seal
from helpers.sim.process import CLI, SimProcess


def test_describe_host_names_the_command_its_parameters_and_the_flags() -> None:
    main = AircraftState(attitude=(0.0, 0.0, 90.0)).main_frame(ControlValues(100, -200, 300))
    line = describe_host(HostPacket(main, None, ZoomTo(ratio=2.5)).encode())
    assert line.startswith("ZOOM_TO ")
    assert "(0x25)" in line and "control valid 100 -200 300" in line and line.endswith("v2")
    idle = describe_host(HostPacket(AircraftState().main_frame(), None).encode())
    assert idle.startswith("NULL (0x00) | control invalid")


def test_describe_gcu_names_the_feedback_mode_attitude_and_zoom() -> None:
    main = GcuMainFrame(mode_raw=0x14, pitch_raw=-3000, yaw_raw=4500)
    sub = GcuSubFrame.build(camera1_zoom=4.0)
    line = describe_gcu(GcuPacket(main, sub, Feedback(0x20, 0)).encode())
    assert line == ("fb TAKE_PHOTO SUCCESS | mode EULER_CONTROL | att r+0.00 p-30.00 y45.00"
                    " | zoom 4.0x | v2")  # fmt: skip
    assert describe_gcu(b"\x8a\x5e\x00").startswith("undecodable: ")


def test_describe_shows_the_anomalies_of_a_packet() -> None:
    """Liberal receive (docs/client.md, "Liberal receive, strict send"): the line names what
    is flagged, and an anomalous command shows its raw bytes instead of raising."""
    reply = GcuPacket(GcuMainFrame(), None, Feedback(0x20, 0x05, b"\x01"), 3).encode()
    line = describe_gcu(reply)
    assert line.startswith("fb TAKE_PHOTO FAILED | ")
    assert line.endswith(" | v3 | flagged: version: 3 is outside the allowed range [1, 2] (V2.0.6 "
                         "defines versions 1 and 2; decoded with its layout) | flagged: status: 5 "
                         "is outside the allowed range [0, 1] (0x00 = success, 0x01 = failure) | "
                         "flagged: status length: 2 is outside the allowed range [1, 1] bytes "
                         "(V2.0.6 defines one status byte; extra 01)")  # fmt: skip
    host = bytearray(HostPacket(AircraftState().main_frame(), None, TimeZone(8)).encode())
    host[70] = 15
    line = describe_host(seal(bytes(host[:2]), bytes(host[5:-2])))
    assert line.startswith("TIME_ZONE 0f (0x08) | ")
    assert line.endswith(" | flagged: offset_hours: 15 is outside the allowed range [-12, 14] h")


async def test_every_packet_in_and_out_is_logged_at_debug_and_nothing_at_info(
    gcu_sim: SimHandle, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.INFO, logger="gcu_async"):
        async with gcu_sim.client() as gcu:
            await gcu.take_photo()
            await asyncio.sleep(0.1)
            assert not [r for r in caplog.records if r.name == "gcu_async.wire"]
            caplog.set_level(logging.DEBUG, logger="gcu_async.wire")
            sent0 = gcu.link.packets_sent
            received0 = gcu.link.packets_received
            await gcu.execute(TakePhoto())
            await asyncio.sleep(0.2)
            sent, received = gcu.link.packets_sent, gcu.link.packets_received
            caplog.set_level(logging.INFO, logger="gcu_async.wire")
            await asyncio.sleep(0.1)
    wire = [r.getMessage() for r in caplog.records if r.name == "gcu_async.wire"]
    out = [m for m in wire if " > " in m]
    inn = [m for m in wire if " < " in m]
    # every packet between the level changes (the tick that noticed the change may differ by one)
    assert abs(len(out) - (sent - sent0)) <= 1, (len(out), sent - sent0)
    assert abs(len(inn) - (received - received0)) <= 1, (len(inn), received - received0)
    assert any("| TAKE_PHOTO 01 (0x20) |" in m for m in out)
    assert any("fb TAKE_PHOTO SUCCESS" in m for m in inn)
    for m in wire:
        url, arrow, hex_, rest = m.split(" ", 3)
        assert url == gcu.transport.url and arrow in "<>"
        assert bytes.fromhex(hex_)[:2] == (b"\xa8\xe5" if arrow == ">" else b"\x8a\x5e")
        assert rest.startswith("| ")
    lifecycle = [r.getMessage() for r in caplog.records if r.name == "gcu_async.client"]
    assert any(m.startswith("opening ") for m in lifecycle)
    assert any(m.endswith(" up") for m in lifecycle)
    assert any(m.startswith("closed ") for m in lifecycle)


def test_the_client_module_logs_under_the_package_logger() -> None:
    assert logging.getLogger("gcu_async.wire").parent is logging.getLogger("gcu_async")
    assert GcuClient.__module__ == "gcu_async.client.client"


@pytest.mark.parametrize("verbose", [(), ("-v",), ("-vv",)])
def test_the_cli_verbose_flag_shows_the_lifecycle_and_the_wire(verbose: tuple[str, ...]) -> None:
    """The real entry point: ``gcu-async send URL take-photo`` against ``gcu-async sim``."""
    sim = SimProcess("--listen", "udp://127.0.0.1:0")
    try:
        done = subprocess.run([*CLI, "send", *verbose, sim.url, "take-photo"],
                              capture_output=True, text=True, timeout=30, check=False)  # fmt: skip
    finally:
        sim.stop()
    assert done.returncode == 0, done.stderr
    wire = [line for line in done.stderr.splitlines() if " gcu_async.wire DEBUG " in line]
    lifecycle = [line for line in done.stderr.splitlines() if " gcu_async.client INFO " in line]
    if not verbose:
        assert done.stderr == ""
    elif verbose == ("-v",):
        assert not wire and any(line.endswith(" up") for line in lifecycle), done.stderr
    else:
        assert any(" > " in line and "| TAKE_PHOTO 01 (0x20) |" in line for line in wire)
        assert any(" < " in line and "fb TAKE_PHOTO SUCCESS" in line for line in wire)
        assert lifecycle
