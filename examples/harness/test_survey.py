"""Tests of the survey app against the gcu_async simulator.

The fixtures come from gcu_async's pytest plugin, registered automatically when gcu-async
is installed (entry point ``pytest11``): ``gcu_sim`` is a simulated GCU on a real loopback
UDP port (its model, fault switches and ``silence()``), ``gcu_client`` a client connected to
it. Override ``gcu_sim_pod``, ``gcu_sim_faults``, ``gcu_client_options`` … to set the scene.
"""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from survey import run_survey

from gcu_async import GcuClient, Mode, Opcode
from gcu_async.pytest_plugin import SimHandle
from gcu_async.sim import FaultConfig

PHOTOS = 5


@pytest.fixture
def gcu_client_options() -> dict[str, Any]:
    # short timeouts keep the failure cases fast (defaults: 2 s command, 1 s silence)
    return {"command_timeout": 1.0, "silence_timeout": 0.3}


async def test_survey_takes_every_photo_top_down(gcu_sim: SimHandle, gcu_client: GcuClient) -> None:
    report = await run_survey(gcu_client, photos=PHOTOS, interval=0.05, zoom=4.0)

    assert report.completed, report.notes
    assert report.photos_taken == PHOTOS
    assert report.zoom == 4.0
    assert report.notes == []
    model = gcu_sim.simulator.model
    assert model.executions[Opcode.TAKE_PHOTO] == PHOTOS  # each photo taken exactly once
    assert model.state.camera.photos == {1: PHOTOS}
    assert model.state.mode is Mode.TOP_DOWN
    assert model.state.attitude.pitch == pytest.approx(-90.0, abs=0.5)
    assert model.state.zoom[1] == pytest.approx(4.0, abs=0.1)


class TestFlakyLink:
    """20 % of the packets lost in each direction: commands repeat until confirmed."""

    @pytest.fixture
    def gcu_sim_faults(self) -> FaultConfig:
        return FaultConfig(drop=0.2, seed=11)

    async def test_survey_completes_without_duplicate_photos(
        self, gcu_sim: SimHandle, gcu_client: GcuClient
    ) -> None:
        report = await run_survey(gcu_client, photos=PHOTOS, interval=0.05)

        assert report.completed, report.notes
        assert report.photos_taken == PHOTOS
        sim = gcu_sim.simulator
        assert sim.request_faults.stats.dropped > 0  # the link really was flaky
        assert sim.reply_faults.stats.dropped > 0
        assert sim.model.executions[Opcode.TAKE_PHOTO] == PHOTOS


class TestPodWithoutZoom:
    """The Z-6A has no "zoom to ratio" command (Appendix 8): the survey shoots at 1×."""

    @pytest.fixture
    def gcu_sim_pod(self) -> str:
        return "Z-6A"

    async def test_gcu_refuses_zoom_and_survey_carries_on(
        self, gcu_sim: SimHandle, gcu_client: GcuClient
    ) -> None:
        report = await run_survey(gcu_client, photos=3, interval=0.05, zoom=4.0)

        assert report.completed
        assert report.photos_taken == 3
        assert report.zoom is None
        assert any("zoom not available" in note for note in report.notes)
        model = gcu_sim.simulator.model
        assert model.executions[Opcode.ZOOM_TO] == 1  # tried once, the GCU said no
        assert model.state.zoom[1] == 1.0
        assert model.executions[Opcode.TAKE_PHOTO] == 3

    async def test_client_refuses_zoom_before_sending(self, gcu_sim: SimHandle) -> None:
        # a client of your own, with options: check_support refuses locally (Appendix 8)
        async with gcu_sim.client(check_support=True) as gcu:
            report = await run_survey(gcu, photos=1, zoom=4.0)

        assert report.completed
        assert report.zoom is None
        assert gcu_sim.simulator.model.executions[Opcode.ZOOM_TO] == 0  # never sent


async def test_survey_waits_out_a_short_outage(gcu_sim: SimHandle, gcu_client: GcuClient) -> None:
    model = gcu_sim.simulator.model
    survey = asyncio.create_task(run_survey(gcu_client, photos=PHOTOS, interval=0.1))
    await wait_until(lambda: model.executions[Opcode.TAKE_PHOTO] >= 2, "two photos")
    gcu_sim.silence(0.8)  # the GCU stops answering: the client reports the link lost
    report = await asyncio.wait_for(survey, 10.0)

    assert report.completed, report.notes
    assert report.link_losses >= 1
    assert report.photos_taken == PHOTOS
    # a photo on the wire when the GCU fell silent may have been taken before it was repeated
    extra = report.retries + report.repeated_unknown
    assert PHOTOS <= model.executions[Opcode.TAKE_PHOTO] <= PHOTOS + extra, report
    assert gcu_client.link.up


async def test_survey_gives_up_when_the_gcu_stays_silent(
    gcu_sim: SimHandle, gcu_client: GcuClient
) -> None:
    model = gcu_sim.simulator.model
    survey = asyncio.create_task(
        run_survey(gcu_client, photos=PHOTOS, interval=0.1, reconnect_timeout=0.5)
    )
    await wait_until(lambda: model.executions[Opcode.TAKE_PHOTO] >= 2, "two photos")
    gcu_sim.silence(30.0)
    report = await asyncio.wait_for(survey, 10.0)  # returns a report, does not raise

    assert not report.completed
    assert 2 <= report.photos_taken < PHOTOS
    assert report.photos_taken == model.executions[Opcode.TAKE_PHOTO]
    assert report.link_losses == 1
    assert "link lost" in report.notes[-1]
    assert not gcu_client.link.up


async def wait_until(predicate: Any, what: str, timeout: float = 5.0) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while not predicate():
        if loop.time() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.01)
