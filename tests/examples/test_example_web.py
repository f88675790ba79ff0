"""The web example (examples/web) end to end: the real app under uvicorn on 127.0.0.1 (an
ephemeral port), connected to the simulator, driven by an HTTP client (httpx) and a
WebSocket client (websockets); the page in a browser is tests/examples/test_example_web_browser.py.
Needs the ``web`` extra (starlette, uvicorn, websockets) and httpx; skips without.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import sys
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from gcu_async import GcuClient, Opcode
from gcu_async.client import ClientState
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.pods import supports
from gcu_async.pytest_plugin import SimHandle
from gcu_async.sim import DEFAULT_POD, GcuSimulator
from helpers.examples.web_deps import require_web
from helpers.protocol.catalogue_samples import required_samples

require_web()
from websockets.asyncio.client import ClientConnection  # noqa: E402
from websockets.asyncio.client import connect as ws_connect  # noqa: E402
from websockets.exceptions import ConnectionClosed  # noqa: E402

from helpers.examples.web import (  # noqa: E402
    Web,
    aircraft_heading,
    angle_near,
    eventually,
    free_udp_port,
    next_message,
    page_button,
    running_web,
)

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # the examples live beside src/, not inside the package
    sys.path.insert(0, str(ROOT))

from examples.web.app import create_app  # noqa: E402
from examples.web.commands import COMMANDS  # noqa: E402


@pytest.fixture
def gcu_sim_model_options() -> dict[str, Any]:
    return {"calibration_seconds": 0.2}


@pytest.fixture
def web_options() -> dict[str, Any]:
    """Keyword arguments for ``create_app`` besides the URL (override per test)."""
    return {}


@pytest.fixture
async def web(gcu_sim: SimHandle, web_options: dict[str, Any]) -> AsyncIterator[Web]:
    async with running_web(gcu_sim.url, gcu_sim, **web_options) as running:
        yield running


# -- status and the page ------------------------------------------------------------------
async def test_status_reports_the_simulated_gimbal(web: Web) -> None:
    state = web.sim.simulator.model.state
    status = await web.status()
    assert status["mode"] == state.mode.name == "POINTING_FOLLOW"
    assert status["mode_raw"] == int(state.mode)
    assert status["pod"]["model"] == "D-90Pro(TA)"
    assert status["pod"]["code"] == 45
    assert status["zoom"]["camera1"] == pytest.approx(state.zoom[1])
    assert status["recording"] is False
    link = status["link"]
    assert link["up"] is True
    assert link["packets_received"] > 0
    assert link["crc_errors"] == 0
    connection = status["connection"]
    assert (connection["state"], connection["url"]) == ("open", web.sim.url)
    assert (connection["attempts"], connection["last_error"]) == (0, None)
    assert status["aircraft_heading"] is None  # the app sends no aircraft state of its own
    # raw wire integers beside the units
    assert status["raw"]["main"]["mode_raw"] == status["mode_raw"]
    assert status["raw"]["sub"]["camera1_zoom_raw"] == round(status["zoom"]["camera1"] * 10)

    response = await web.command("enter_euler_control", {"pitch": -30.0, "yaw": 120.0})
    assert response.status_code == 200

    async def pointed() -> bool:
        s = await web.status()
        a = s["attitude"]
        return (
            s["mode"] == "EULER_CONTROL"
            and angle_near(a["pitch"], -30.0)
            and angle_near(a["yaw"], 120.0)
        )

    await eventually(pointed, what="status at pitch -30, yaw 120")
    status = await web.status()
    assert status["raw"]["main"]["attitude_raw"][2] == round(status["attitude"]["yaw"] * 100)
    assert status["relative"]["z"] == pytest.approx(state.relative_axes.z, abs=0.5)


async def test_page_and_assets_are_served_locally(web: Web) -> None:
    page = await web.http.get("/")
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    html = page.text
    for element in ('id="zoom"', 'id="horizon"', 'id="compass"', 'data-command="take_photo"'):
        assert element in html
    for forbidden in ('src="http', "src='http", 'href="http', "href='http", "//cdn"):
        assert forbidden not in html  # everything comes from this server
    for asset in ("/static/app.js", "/static/style.css"):
        assert f'"{asset}"' in html
        response = await web.http.get(asset)
        assert response.status_code == 200, asset
        assert len(response.content) > 500
    script = (await web.http.get("/static/app.js")).text
    assert "/ws/telemetry" in script and "/api/commands/" in script
    # every command a button names exists in the API
    for name in {part.split('"')[0] for part in html.split('data-command="')[1:]}:
        assert name in COMMANDS, name


async def test_command_listing_matches_the_client(web: Web) -> None:
    response = await web.http.get("/api/commands")
    assert response.status_code == 200
    listed = {c["name"]: c for c in response.json()["commands"]}
    assert set(listed) == set(COMMANDS)
    assert listed["zoom_to"]["params"]["ratio"] == {"type": "float", "required": True}
    assert listed["take_photo"]["params"]["cameras"] == {"type": "int", "default": 1}
    for spec in COMMANDS.values():
        assert callable(getattr(GcuClient, spec.method)), spec.method


# -- commands -----------------------------------------------------------------------------
# name -> (parameters, opcode the simulator must execute)
EVERY_COMMAND: dict[str, tuple[dict[str, Any], Opcode]] = {
    "take_photo": ({}, Opcode.TAKE_PHOTO),
    "start_recording": ({}, Opcode.RECORD),
    "stop_recording": ({}, Opcode.RECORD),
    "toggle_recording": ({}, Opcode.RECORD),
    "zoom_in": ({}, Opcode.ZOOM_IN),
    "stop_zoom": ({}, Opcode.ZOOM_STOP),
    "zoom_out": ({"cameras": 1}, Opcode.ZOOM_OUT),
    "zoom_to": ({"ratio": 4.0}, Opcode.ZOOM_TO),
    "zoom_to_fraction": ({"fraction": 0.5}, Opcode.ZOOM_TO),
    "focus": ({}, Opcode.FOCUS),
    "enter_euler_control": ({"pitch": -10.0, "yaw": 350.0}, Opcode.EULER_CONTROL),
    "enter_angle_control": ({"pitch": -5.0, "yaw": 5.0}, Opcode.ANGLE_CONTROL),
    "enter_fpv": ({"pitch": -5.0}, Opcode.FPV),
    "enter_pointing_lock": ({"pitch_rate": 0.0, "yaw_rate": 2.0}, Opcode.POINTING_LOCK),
    "enter_pointing_follow": ({}, Opcode.POINTING_FOLLOW),
    "enter_top_down": ({"yaw_rate": 1.0}, Opcode.TOP_DOWN),
    "centre": ({}, Opcode.CENTRE),
    "calibrate": ({"timeout": 5.0}, Opcode.CALIBRATION),
    "track": ({"box": [0.45, 0.45, 0.55, 0.55]}, Opcode.TRACK),
    "stop_tracking": ({}, Opcode.TRACK),
    "click_to_pan": ({"x": 0.7, "y": 0.3}, Opcode.CLICK_TO_PAN),
    "set_palette": ({"palette": 3}, Opcode.PALETTE),
    "set_night_vision": ({"mode": 2}, Opcode.NIGHT_VISION),
    "set_ranging": ({"enabled": True}, Opcode.RANGING),
    "set_osd": ({"enabled": True}, Opcode.OSD),
    "set_digital_zoom": ({}, Opcode.DIGITAL_ZOOM),
    "set_target_detection": ({"enabled": True}, Opcode.TARGET_DETECTION),
    "set_picture_in_picture": ({"mode": 2}, Opcode.PICTURE_IN_PICTURE),
    "set_area_temperature": ({"box": [0.1, 0.1, 0.5, 0.5]}, Opcode.AREA_TEMPERATURE),
    "set_temperature_alarm": ({"high": 80.0, "low": -10.0}, Opcode.TEMPERATURE_ALARM),
    "set_isotherm": ({"enabled": False}, Opcode.ISOTHERM),
    "set_spot_temperature": ({"x": 0.25, "y": 0.75}, Opcode.SPOT_TEMPERATURE),
    "set_osd_coordinates": ({"coordinates": 1}, Opcode.OSD_COORDINATES),
    "set_image_auto_flip": ({"enabled": False}, Opcode.IMAGE_AUTO_FLIP),
    "set_time_zone": ({"offset_hours": 2}, Opcode.TIME_ZONE),
}
EVERY_COMMAND.update({  # the rest of the catalogue (a new command runs here unlisted)
    e.method: (required_samples(e), e.opcode) for e in CATALOGUE
    if e.method not in EVERY_COMMAND and not e.needs_ins and supports(DEFAULT_POD, e.opcode)
})  # fmt: skip
FAILS_ON_D90PRO_TA = {
    e.method: (required_samples(e), e.opcode)
    for e in CATALOGUE if not supports(DEFAULT_POD, e.opcode)
}  # fmt: skip
"""Appendix 8: the default simulated pod lacks these."""
FAIL_WITHOUT_INS: dict[str, tuple[dict[str, Any], Opcode]] = {
    e.method: (required_samples(e), e.opcode) for e in CATALOGUE if e.needs_ins
}
"""The web app sends no aircraft INS data: the simulated GCU refuses the gaze commands."""


def test_every_exposed_command_is_covered() -> None:
    covered = set(EVERY_COMMAND) | set(FAILS_ON_D90PRO_TA) | set(FAIL_WITHOUT_INS)
    assert covered == set(COMMANDS) == {e.method for e in CATALOGUE}
    assert not set(EVERY_COMMAND) & (set(FAILS_ON_D90PRO_TA) | set(FAIL_WITHOUT_INS))
    assert FAILS_ON_D90PRO_TA and FAIL_WITHOUT_INS


async def test_gaze_commands_reach_the_gcu_and_fail_without_ins(web: Web) -> None:
    for name, (params, opcode) in FAIL_WITHOUT_INS.items():
        response = await web.command(name, params)
        assert response.status_code == 409, (name, response.text)
        assert response.json()["opcode"] == opcode
        assert web.sim.simulator.model.executions[opcode] == 1


async def test_every_command_runs_on_the_simulator(web: Web) -> None:
    model = web.sim.simulator.model
    expected: dict[int, int] = {}
    for name, (params, opcode) in EVERY_COMMAND.items():
        if name == "stop_recording":  # the client decides from the flags it has seen
            await eventually(lambda: _recording(web, True), what="recording flag")
        response = await web.command(name, params)
        assert response.status_code == 200, (name, response.text)
        body = response.json()
        assert body["command"] == name
        assert body["feedback"]["opcode"] == opcode, name
        assert body["feedback"]["status"] == "SUCCESS", name
        expected[opcode] = expected.get(opcode, 0) + 1
    assert {op: model.executions[op] for op in expected} == expected
    state = model.state
    assert state.camera.photos == {1: 1}
    assert state.camera.palette == 3
    assert state.camera.pip_mode == 2
    assert state.rangefinder.on is True
    assert state.camera.osd_on is True
    assert state.camera.recording is True  # start, stop, toggle


async def _recording(web: Web, value: bool) -> bool:
    return (await web.status())["recording"] is value


async def test_record_start_when_recording_sends_nothing(web: Web) -> None:
    executions = web.sim.simulator.model.executions
    assert (await web.command("start_recording")).status_code == 200
    await eventually(lambda: _recording(web, True), what="recording flag")
    response = await web.command("start_recording")
    assert response.status_code == 200
    assert response.json() == {"command": "start_recording", "feedback": None}
    assert executions[Opcode.RECORD] == 1


async def test_zoom_to_moves_the_zoom_in_status(web: Web) -> None:
    assert (await web.command("zoom_to", {"ratio": 6.0})).status_code == 200

    async def zoomed() -> bool:
        return bool((await web.status())["zoom"]["camera1"] == pytest.approx(6.0, abs=0.05))

    await eventually(zoomed, what="zoom 6x")
    assert web.sim.simulator.model.state.zoom[1] == pytest.approx(6.0, abs=0.05)


async def test_ahead_points_ahead_of_the_aircraft(web: Web) -> None:
    """The page's "Ahead" points the camera along the aircraft's heading (angle control:
    yaw relative to the aircraft), not north, and keeps it there when the aircraft turns."""
    html = (await web.http.get("/")).text
    ahead, east, down = (page_button(html, label) for label in ("Ahead", "East", "Down 45°"))
    assert ahead == ("enter_angle_control", {"pitch": 0, "yaw": 0})
    model = web.sim.simulator.model

    async def pointing(mode: str, pitch: float, yaw: float) -> bool:
        s = await web.status()
        a = s["attitude"]
        return s["mode"] == mode and angle_near(a["pitch"], pitch) and angle_near(a["yaw"], yaw)

    async with aircraft_heading(web.gcu, 120.0):
        await eventually(lambda: _sim_heading(web, 120.0), what="the simulator got heading 120")
        assert (await web.command(*east)).status_code == 200  # somewhere else first
        await eventually(lambda: pointing("EULER_CONTROL", -20.0, 90.0), what="east")
        response = await web.command(*ahead)
        assert response.status_code == 200, response.text
        assert response.json()["feedback"]["command"] == "ANGLE_CONTROL"
        await eventually(lambda: pointing("ANGLE_CONTROL", 0.0, 120.0), what="ahead at 120")
        assert angle_near(model.state.relative.yaw, 0.0)  # along the aircraft's nose
        status = await web.status()
        assert status["aircraft_heading"] == pytest.approx(120.0)
        assert (await web.command(*down)).status_code == 200
        await eventually(lambda: pointing("ANGLE_CONTROL", -45.0, 120.0), what="down ahead")
        assert (await web.command(*ahead)).status_code == 200
        await eventually(lambda: pointing("ANGLE_CONTROL", 0.0, 120.0), what="ahead again")
    async with aircraft_heading(web.gcu, 200.0):  # the aircraft turns: "ahead" turns with it
        await eventually(lambda: pointing("ANGLE_CONTROL", 0.0, 200.0), what="ahead at 200")
    assert angle_near(model.state.relative.yaw, 0.0)


async def _sim_heading(web: Web, heading: float) -> bool:
    aircraft = web.sim.simulator.model.state.aircraft
    return aircraft.ins_valid and angle_near(aircraft.attitude.yaw, heading, 0.01)


BAD_PARAMETERS: list[tuple[str, Any, str]] = [
    ("zoom_to", {"ratio": 5000}, "ratio: 5000 is outside the allowed range [1, 3276.8] x"),
    ("zoom_to", {}, "ratio: required parameter of zoom_to is missing"),
    ("zoom_to", {"ratio": "ten"}, "ratio: expected a number, got string 'ten'"),
    ("zoom_to", {"ratio": True}, "ratio: expected a number"),
    ("zoom_to_fraction", {"fraction": 1.5}, "fraction"),
    ("take_photo", {"camera": 1}, "unknown parameter(s) camera (allowed: cameras)"),
    ("take_photo", {"cameras": 1.5}, "cameras: expected an integer"),
    ("take_photo", [1, 2], "the body must be a JSON object, got array"),
    ("enter_euler_control", {"pitch": -200.0}, "pitch"),
    ("enter_pointing_lock", {"yaw_rate": math.inf}, "yaw_rate: inf is not a finite number"),
    ("track", {"box": [0.1, 0.2, 0.3]}, "box: expected [left, top, right, bottom]"),
    ("track", {"box": [0.6, 0.6, 0.4, 0.4]}, "box"),
    ("click_to_pan", {"x": 0.5}, "y: required parameter"),
    ("set_night_vision", {"mode": 7}, "7"),
    ("set_palette", {"palette": 11}, "palette"),
    ("set_ranging", {"enabled": 1}, "enabled: expected true or false"),
    ("set_fill_light", {"brightness": 256}, "brightness"),
    ("calibrate", {"timeout": -1.0}, "timeout"),
    ("centre", {"now": True}, "unknown parameter(s) now (allowed: none)"),
]


async def test_bad_parameters_are_422_and_send_nothing(web: Web) -> None:
    executions = web.sim.simulator.model.executions
    for name, params, message in BAD_PARAMETERS:
        response = await web.command(name, params)
        assert response.status_code == 422, (name, params, response.text)
        body = response.json()
        assert message in body["error"], (name, params, body)
    assert sum(executions.values()) == 0  # nothing reached the GCU
    # a FieldRangeError names the field and range in the body
    body = (await web.command("zoom_to", {"ratio": 0.5})).json()
    assert body["kind"] == "FieldRangeError"
    assert body["field"] == "ratio"
    assert (body["low"], body["high"]) == (1.0, pytest.approx(3276.8))


async def test_unknown_command_malformed_body_and_wrong_method(web: Web) -> None:
    response = await web.command("self_destruct")
    assert response.status_code == 404
    assert "self_destruct" in response.json()["error"]
    assert "take_photo" in response.json()["commands"]
    response = await web.http.post(
        "/api/commands/take_photo", content=b"{not json",
        headers={"content-type": "application/json"},
    )
    assert response.status_code == 400
    assert "not valid JSON" in response.json()["error"]
    assert (await web.http.get("/api/commands/take_photo")).status_code == 405
    # an empty body means "all defaults" (still declared JSON)
    response = await web.http.post("/api/commands/take_photo", content=b"",
                                   headers={"content-type": "application/json"})  # fmt: skip
    assert response.status_code == 200
    assert web.sim.simulator.model.state.camera.photos == {1: 1}


async def test_gcu_failure_is_409_with_opcode_and_status(web: Web) -> None:
    response = await web.command("set_fill_light", {"brightness": 100})
    assert response.status_code == 409
    body = response.json()
    assert body["kind"] == "CommandFailed"
    assert (body["opcode"], body["command"], body["status"]) == (0x80, "FILL_LIGHT", 0x01)
    assert web.sim.simulator.model.executions[Opcode.FILL_LIGHT] == 1


@pytest.mark.parametrize("gcu_sim_pod", ["Z-6A"])
async def test_commands_a_z6a_lacks_are_409(web: Web) -> None:
    status = await web.status()
    assert status["pod"]["model"] == "Z-6A"
    response = await web.command("zoom_to", {"ratio": 4.0})
    assert response.status_code == 409
    body = response.json()
    assert (body["opcode"], body["status"], body["failed_cameras"]) == (0x25, 0x01, 0x01)
    response = await web.command("set_palette", {"palette": 2})
    assert response.status_code == 409
    assert (response.json()["opcode"], response.json()["status"]) == (0x2A, 0x02)
    # what the Z-6A does support still works
    assert (await web.command("track", {"box": [0.4, 0.4, 0.6, 0.6]})).status_code == 200
    assert (await web.command("zoom_in")).status_code == 200


@pytest.mark.parametrize("gcu_sim_pod", ["Z-6A"])
@pytest.mark.parametrize("web_options", [{"check_support": True}])
async def test_check_support_refuses_before_sending(web: Web) -> None:
    response = await web.command("zoom_to", {"ratio": 4.0})
    assert response.status_code == 409
    body = response.json()
    assert body["kind"] == "UnsupportedCommandError"
    assert (body["command"], body["pod_model"]) == ("ZOOM_TO", "Z-6A")
    assert web.sim.simulator.model.executions[Opcode.ZOOM_TO] == 0


async def test_no_feedback_in_time_is_504(web: Web) -> None:
    # calibration runs 0.2 s on this simulator: a 0.1 s timeout cannot be met
    response = await web.command("calibrate", {"timeout": 0.1})
    assert response.status_code == 504
    body = response.json()
    assert body["kind"] == "CommandTimeout"
    assert "in progress" in body["error"]


@pytest.mark.parametrize("web_options", [{"silence_timeout": 0.3}])
async def test_link_lost_is_503_and_reported_live(web: Web) -> None:
    async with ws_connect(web.ws_url) as ws:
        assert (await next_message(ws))["type"] == "telemetry"
        web.sim.silence(10.0)

        async def link_down() -> bool:
            return (await web.status())["link"]["up"] is False

        await eventually(link_down, what="link down in /api/status")
        response = await web.command("take_photo")
        assert response.status_code == 503
        assert response.json()["kind"] == "CommandLinkLost"
        assert response.json()["outcome"] == "not sent"
        # the socket keeps reporting the link while no telemetry arrives
        deadline = time.monotonic() + 3.0
        while True:
            message = await next_message(ws)
            if message["type"] == "link":
                assert message["link"]["up"] is False
                break
            assert time.monotonic() < deadline, "no link report on the socket"
        web.sim.silence(0)  # replies resume: the link comes back, commands work again

        async def link_up() -> bool:
            return (await web.status())["link"]["up"] is True

        await eventually(link_up, what="link restored")
        assert (await web.command("take_photo")).status_code == 200
        message = await next_message(ws)
        assert message["type"] == "telemetry"
        assert message["link"]["restored_count"] >= 1


# -- telemetry ----------------------------------------------------------------------------
async def test_telemetry_follows_a_command(web: Web) -> None:
    async with ws_connect(web.ws_url) as ws:
        first = await next_message(ws)
        assert first["type"] == "telemetry"
        assert first["mode"] == "POINTING_FOLLOW"
        assert first["pod"]["model"] == "D-90Pro(TA)"
        assert first["link"]["up"] is True
        response = await web.command("enter_euler_control", {"pitch": -30.0, "yaw": 90.0})
        assert response.status_code == 200
        yaws: list[float] = []
        seqs: list[int] = [first["seq"]]
        deadline = time.monotonic() + 5.0
        while True:
            message = await next_message(ws)
            assert message["type"] == "telemetry"
            seqs.append(message["seq"])
            yaws.append(message["attitude"]["yaw"])
            if (
                message["mode"] == "EULER_CONTROL"
                and angle_near(message["attitude"]["yaw"], 90.0)
                and angle_near(message["attitude"]["pitch"], -30.0)
            ):
                break
            assert time.monotonic() < deadline, f"gimbal never reached yaw 90: {yaws[-5:]}"
    assert len(set(yaws)) > 2  # values changed on the way, not one jump
    assert seqs == sorted(seqs) and len(set(seqs)) == len(seqs)


@pytest.mark.parametrize("web_options", [{"telemetry_hz": 10.0}])
async def test_telemetry_rate_is_bounded_and_newest_wins(web: Web) -> None:
    async with ws_connect(web.ws_url) as ws:
        await next_message(ws)
        dropped_before = web.gcu.telemetry_dropped
        start = time.monotonic()
        count = 0
        while time.monotonic() - start < 1.0:
            with contextlib.suppress(asyncio.TimeoutError):
                await next_message(ws, timeout=max(0.01, 1.0 - (time.monotonic() - start)))
                count += 1
        # the simulator answers 50 times a second; the socket sends at most 10
        assert 3 <= count <= 11, count
        # the samples in between were dropped (newest wins), not queued
        assert web.gcu.telemetry_dropped > dropped_before
        assert web.gcu.link.up


async def test_several_sockets_and_a_silent_reader(web: Web) -> None:
    async with ws_connect(web.ws_url) as slow, ws_connect(web.ws_url) as fast:
        await asyncio.sleep(0.5)  # `slow` reads nothing meanwhile
        for _ in range(5):
            assert (await next_message(fast))["type"] == "telemetry"
        assert web.gcu.link.up
        assert web.gcu.link.reply_rate > 10  # the heartbeat (50 Hz) is not held up
        assert (await next_message(slow))["type"] == "telemetry"
    # both subscriptions are gone once the sockets closed
    await eventually(lambda: _no_subscribers(web.gcu), timeout=2.0, what="subscriptions released")


async def _no_subscribers(gcu: GcuClient) -> bool:
    return not gcu._telemetry.subscriptions


# -- lifecycle ----------------------------------------------------------------------------
FAST_RETRY: dict[str, Any] = {"connect_timeout": 0.3}
"""Client options that make each failed start-up attempt short."""


async def test_app_starts_before_the_gcu_and_connects_when_it_answers(gcu_sim: SimHandle) -> None:
    gcu_sim.silence(60.0)  # the GCU is off: nothing answers
    async with running_web(gcu_sim.url, gcu_sim, wait_connected=False, **FAST_RETRY) as web:
        await eventually(lambda: _attempts_at_least(web, 2), what="two failed attempts")
        # the app is up and says what it waits for
        response = await web.http.get("/api/status")
        assert response.status_code == 503
        body = response.json()
        assert body["kind"] == "NotConnected"
        assert body["connection"]["state"] == "opening"
        assert body["connection"]["url"] == gcu_sim.url
        assert body["connection"]["attempts"] >= 2
        assert "no reply from the GCU within 0.3 s" in body["connection"]["last_error"]
        assert f"waiting for the GCU at {gcu_sim.url}" in body["error"]
        # commands are refused without sending; parameters are still checked first
        response = await web.command("take_photo")
        assert response.status_code == 503
        assert (response.json()["kind"], response.json()["outcome"]) == ("NotConnected", "not sent")
        assert (await web.command("zoom_to", {"ratio": "ten"})).status_code == 422
        async with ws_connect(web.ws_url) as ws:
            message = await next_message(ws)
            assert message["type"] == "link"
            assert message["connection"]["state"] == "opening"
            assert message["link"]["up"] is False
            gcu_sim.silence(0)  # powered on: the same socket starts carrying telemetry
            deadline = time.monotonic() + 10.0
            while (message := await next_message(ws))["type"] != "telemetry":
                assert message["connection"]["state"] == "opening"
                assert time.monotonic() < deadline, "no telemetry after the GCU came up"
            assert message["connection"]["state"] == "open"
            assert message["link"]["up"] is True
            assert message["pod"]["model"] == "D-90Pro(TA)"
        assert web.gcu.state is ClientState.OPEN
        status = await web.status()
        assert status["connection"]["state"] == "open"
        assert (status["connection"]["attempts"], status["connection"]["last_error"]) == (0, None)
        assert (await web.command("take_photo")).status_code == 200
        assert gcu_sim.simulator.model.executions[Opcode.TAKE_PHOTO] == 1


async def _attempts_at_least(web: Web, n: int) -> bool:
    return web.attempts.count >= n


async def test_app_waits_for_a_gcu_powered_later() -> None:
    """Nothing listens on the GCU's port at first (loopback answers with ICMP port
    unreachable); then a simulator starts on that port."""
    port = free_udp_port()
    url = f"udp://127.0.0.1:{port}"
    async with running_web(url, None, wait_connected=False, **FAST_RETRY) as web:
        await eventually(lambda: _attempts_at_least(web, 2), what="two failed attempts")
        assert web.gcu.state is ClientState.OPENING
        assert (await web.http.get("/api/status")).status_code == 503
        sim = GcuSimulator()
        async with sim.serve_udp("127.0.0.1", port):
            await web.wait_open(10.0)
            status = await web.status()
            assert status["pod"]["model"] == "D-90Pro(TA)"
            assert status["link"]["up"] is True
            assert (await web.command("take_photo")).status_code == 200
            assert sim.model.executions[Opcode.TAKE_PHOTO] == 1


@pytest.mark.parametrize("gcu_sim_transport", ["tcp"])
async def test_a_client_whose_transport_gave_up_is_reported_failed(gcu_sim: SimHandle) -> None:
    # without reconnect, a TCP transport gives up at its first loss: the client fails, and
    # the page and the API say why until the app is restarted
    url = gcu_sim.url + "?reconnect=false"
    async with running_web(url, gcu_sim, **FAST_RETRY) as web:
        async with ws_connect(web.ws_url) as ws:
            assert (await next_message(ws))["type"] == "telemetry"
            assert gcu_sim.kill_connection()
            deadline = time.monotonic() + 5.0
            while (message := await next_message(ws))["type"] != "link" or (
                    message["connection"]["state"] != "failed"):  # fmt: skip
                assert time.monotonic() < deadline, "the socket never said the client failed"
            assert "reconnect is off" in message["connection"]["last_error"]
            assert message["link"]["up"] is False
        response = await web.http.get("/api/status")
        assert response.status_code == 503
        body = response.json()
        assert body["connection"]["state"] == "failed"
        assert body["error"].startswith(f"the client of the GCU at {gcu_sim.url} failed: ")
        response = await web.command("take_photo")
        assert (response.status_code, response.json()["outcome"]) == (503, "not sent")
        assert gcu_sim.simulator.model.executions[Opcode.TAKE_PHOTO] == 0


async def test_app_stops_cleanly_while_waiting(gcu_sim: SimHandle) -> None:
    gcu_sim.silence(60.0)
    async with running_web(gcu_sim.url, gcu_sim, wait_connected=False, **FAST_RETRY) as web:
        ws = await ws_connect(web.ws_url)
        assert (await next_message(ws))["type"] == "link"
        await eventually(lambda: _attempts_at_least(web, 1), what="a failed attempt")
    try:  # the app stopped while waiting: the socket is told, the client is closed
        with pytest.raises(ConnectionClosed) as info:
            await _read_until_closed(ws)
        assert info.value.rcvd is not None
        assert info.value.rcvd.code in (1001, 1012), info.value.rcvd
    finally:
        await ws.close()
    assert web.gcu.state is ClientState.CLOSED
    assert not web.gcu.transport.connected


async def test_app_closes_its_client_on_shutdown(gcu_sim: SimHandle) -> None:
    async with running_web(gcu_sim.url, gcu_sim) as web:
        gcu = web.gcu
        assert gcu.transport.connected
    assert not gcu.transport.connected
    received = gcu_sim.simulator.model.stats.received
    await asyncio.sleep(0.1)
    assert gcu_sim.simulator.model.stats.received == received  # heartbeat stopped


async def test_socket_closes_when_the_app_stops(gcu_sim: SimHandle) -> None:
    async with running_web(gcu_sim.url, gcu_sim) as web:
        ws = await ws_connect(web.ws_url)
        assert (await next_message(ws))["type"] == "telemetry"
    try:  # the server is gone: the socket ends with a "going away" / "restart" close
        with pytest.raises(ConnectionClosed) as info:
            await _read_until_closed(ws)
        assert info.value.rcvd is not None
        assert info.value.rcvd.code in (1001, 1012), info.value.rcvd
    finally:
        await ws.close()


async def _read_until_closed(ws: ClientConnection) -> None:
    for _ in range(100):  # bounded: the buffered messages, then the close
        await asyncio.wait_for(ws.recv(), 2.0)


def test_create_app_rejects_a_bad_rate() -> None:
    for hz in (0.0, -1.0, 51.0):
        with pytest.raises(ValueError, match="telemetry_hz"):
            create_app("udp://127.0.0.1:2337", telemetry_hz=hz)


def test_create_app_rejects_a_bad_url_at_once() -> None:
    # configuration errors are not "the GCU is not there yet": they raise before serving
    with pytest.raises(ValueError, match="ftp"):
        create_app("ftp://127.0.0.1:2337")
    with pytest.raises(ValueError, match="local_port: '2338' is not an integer"):
        create_app("udp://127.0.0.1:2337", local_port="2338")
