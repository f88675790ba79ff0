"""What a new user meets first (docs/client.md): failures that say their likely cause,
boxes and triples from JSON lists, one yaw input range, the pod's zoom limit, ``await
connect(url)``, lifecycle errors that name the state, frames printed in engineering units —
against the simulator over UDP."""

from __future__ import annotations

import re
import warnings
from typing import Any

import pytest

from gcu_async import CommandFailed, FieldRangeError, GcuClient, WaitTimeout, connect
from gcu_async.client.causes import explain
from gcu_async.client.waiting import _attitude_targets
from gcu_async.errors import ClientStateError, CommandLinkLost, LikelyCause, Outcome
from gcu_async.protocol.catalogue import BY_METHOD, NEEDS_INS
from gcu_async.protocol.commands import ZoomTo
from gcu_async.protocol.enums import Opcode
from gcu_async.pytest_plugin import SimHandle
from gcu_async.transport import MemoryTransport

AT_REST = {"acceleration": (0.0, 0.0, 0.0), "velocity": (0.0, 0.0, 0.0)}


# -- likely causes ----------------------------------------------------------------------------
def test_the_catalogue_names_the_commands_that_need_ins() -> None:
    assert {Opcode.GAZE_AT_COORDINATES, Opcode.GAZE_LOCK} == NEEDS_INS
    for entry in BY_METHOD.values():  # the one-line docs say it exactly where the flag is
        assert ("needs valid aircraft INS data" in entry.doc) is entry.needs_ins, entry.method


async def test_a_gaze_without_ins_says_ins_invalid(gcu_client: GcuClient) -> None:
    assert not gcu_client.ins_valid
    with pytest.raises(CommandFailed) as caught:
        await gcu_client.gaze_at(47.39, 8.54, 420.0)
    exc = caught.value
    assert exc.likely_cause is LikelyCause.INS_INVALID
    assert "INS invalid" in exc.cause_detail and "update_aircraft" in exc.cause_detail
    assert str(exc).endswith(f"(likely cause: {exc.cause_detail})")
    assert exc.outcome is Outcome.FAILED and exc.status == 0x01
    # the same command with the aircraft state given: it runs, and says nothing of INS
    gcu_client.update_aircraft(attitude=(0.0, 0.0, 90.0), **AT_REST)
    assert gcu_client.ins_valid
    feedback = await gcu_client.gaze_at(47.39, 8.54, 420.0)
    assert feedback.succeeded


async def test_a_failure_unrelated_to_ins_names_no_cause(gcu_client: GcuClient) -> None:
    with pytest.raises(CommandFailed) as caught:  # D-90Pro(TA) has no fill light
        await gcu_client.set_fill_light(10)
    assert caught.value.likely_cause is LikelyCause.NOT_SUPPORTED
    gcu_client.update_aircraft(attitude=(0.0, 0.0, 0.0), **AT_REST)
    with pytest.raises(CommandFailed) as caught:  # tracking an empty box fails on the sim
        await gcu_client.track([0.5, 0.5, 0.5, 0.5])
    assert caught.value.likely_cause is None and caught.value.cause_detail == ""
    assert "likely cause" not in str(caught.value)


@pytest.mark.parametrize("gcu_sim_pod", ["Z-6A"])
async def test_appendix_8_names_the_pod_model(gcu_client: GcuClient) -> None:
    assert not gcu_client.check_support
    with pytest.raises(CommandFailed) as caught:
        await gcu_client.zoom_to(10.0)
    exc = caught.value
    assert exc.likely_cause is LikelyCause.NOT_SUPPORTED
    assert "Appendix 8" in str(exc) and "Z-6A" in str(exc) and "ZOOM_TO" in str(exc)


def test_a_zoom_beyond_the_limit_names_it() -> None:
    error = CommandFailed(0x25, 0x01, 0x01, name="ZOOM_TO")
    explain(error, ZoomTo(ratio=31.0), None, ins_invalid=False, max_zoom=30.0,
            aircraft_timeout=1.0)  # fmt: skip
    assert error.likely_cause is LikelyCause.ZOOM_LIMIT
    assert "31x is beyond camera 1's maximum zoom 30x" in str(error)


# -- the zoom limit -----------------------------------------------------------------------------
@pytest.fixture
def gcu_client_options() -> dict[str, Any]:
    return {"max_zoom": 30.0}


async def test_zoom_beyond_max_zoom_is_refused_before_sending(
    gcu_sim: SimHandle, gcu_client: GcuClient,
) -> None:  # fmt: skip
    before = dict(gcu_sim.simulator.model.executions)
    for call in (lambda: gcu_client.zoom_to(31.0), lambda: gcu_client.reach_zoom(31.0)):
        with pytest.raises(FieldRangeError) as caught:
            await call()
        assert caught.value.high == 30.0
        assert "camera 1's maximum zoom is 30x (max_zoom)" in str(caught.value)
    assert dict(gcu_sim.simulator.model.executions) == before  # nothing was sent
    assert (await gcu_client.zoom_to(30.0)).succeeded


@pytest.mark.parametrize("gcu_sim_model_options", [{"max_zoom": 1.5}])
async def test_reach_zoom_beyond_an_unknown_limit_says_where_the_zoom_stopped(
    gcu_sim: SimHandle,
) -> None:
    async with gcu_sim.client() as gcu:
        with pytest.raises(WaitTimeout) as caught:
            await gcu.reach_zoom(4.0, timeout=4.0)
    message = str(caught.value)
    assert "camera 1 last reported 1.5x: its maximum may be lower than 4x" in message
    assert "max_zoom" in message
    assert "0x" not in message  # the mode in words, no raw code
    assert re.search(r"last seen: mode [a-z ]+, roll", message), message


# -- arguments as a new user writes them ----------------------------------------------------
async def test_track_takes_a_list(gcu_client: GcuClient) -> None:
    assert (await gcu_client.track([0.4, 0.4, 0.5, 0.5])).succeeded
    with pytest.raises(TypeError, match=r"box: expected an ImageBox or a tuple or list"):
        await gcu_client.track("0.4 0.4 0.5 0.5")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="box"):
        await gcu_client.track([0.4, 0.4, 0.5])


def test_aircraft_yaw_takes_mavlink_headings_and_compass_headings() -> None:
    gcu = GcuClient(MemoryTransport())
    for given, sent in ((-10.0, 350.0), (-180.0, 180.0), (359.99, 359.99), (10.0, 10.0)):
        state = gcu.update_aircraft(attitude=[0.0, 0.0, given], **AT_REST)
        assert state.attitude is not None and state.attitude.yaw == pytest.approx(sent)
        packet = state.main_frame()
        assert packet.aircraft_attitude.yaw == pytest.approx(sent % 360)
    for bad in (-180.01, 360.0, 720.0):
        with pytest.raises(FieldRangeError) as caught:
            gcu.update_aircraft(attitude=(0.0, 0.0, bad))
        assert (caught.value.field, caught.value.low, caught.value.high) == (
            "attitude.yaw", -180.0, 360.0)
    euler_yaw = BY_METHOD["enter_euler_control"].parameter("yaw")
    assert (euler_yaw.low, euler_yaw.high, euler_yaw.high_open) == (-180.0, 360.0, True)


def test_reach_attitude_takes_the_commands_pitch_range() -> None:
    pitch = BY_METHOD["enter_euler_control"].parameter("pitch")
    assert _attitude_targets(None, pitch.low, None) == {"pitch": -180.0}
    assert _attitude_targets(None, -120.0, -170.0) == {"pitch": -120.0, "yaw": -170.0}
    with pytest.raises(FieldRangeError) as caught:
        _attitude_targets(None, -180.5, None)
    assert (caught.value.low, caught.value.high) == (pitch.low, pitch.high)


# -- the lifecycle --------------------------------------------------------------------------------
async def test_await_connect_opens_the_client(gcu_sim: SimHandle) -> None:
    gcu = await gcu_sim.client()
    try:
        assert gcu.state.value == "open"
        assert (await gcu.take_photo()).succeeded
    finally:
        await gcu.close()


async def test_a_command_before_open_says_how_to_open() -> None:
    gcu = connect("udp://127.0.0.1:9", local_port=0)
    with pytest.raises(CommandLinkLost) as caught:
        await gcu.take_photo()
    message = str(caught.value)
    assert "not opened" in message and "async with" in message
    assert caught.value.outcome is Outcome.NOT_SENT


async def test_reentering_names_the_state(gcu_client: GcuClient) -> None:
    with pytest.raises(ClientStateError) as caught:
        async with gcu_client:
            pass
    assert isinstance(caught.value, RuntimeError)
    assert caught.value.state == "open" and "GcuClient is open" in str(caught.value)
    await gcu_client.close()
    with pytest.raises(CommandLinkLost, match="client is closed"):
        await gcu_client.take_photo()


async def test_print_status_shows_engineering_units(gcu_client: GcuClient) -> None:
    await gcu_client.reach_attitude(pitch=-30.0, yaw=45.0, timeout=15.0)
    text = str(gcu_client.status)
    assert "mode EULER_CONTROL (0x14)" in text and "deg" in text
    assert "pitch -30" in text and "pitch_raw" not in text
    assert "zoom 1x" in str(gcu_client.info)
    assert "pitch_raw=" in repr(gcu_client.status)  # repr keeps the raw fields


def test_the_rate_warning_points_at_the_callers_line() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        connect("udp://127.0.0.1:9", local_port=0, rate_hz=20.0)
        GcuClient(MemoryTransport(), rate_hz=60.0)
    assert [w.filename for w in caught] == [__file__, __file__]
    assert all("30-50 Hz" in str(w.message) for w in caught)
