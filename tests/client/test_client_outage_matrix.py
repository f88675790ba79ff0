"""The outage matrix over real parts (docs/client.md, "Lifecycle" and "GCU restarts"): a
simulator process (tests/helpers/sim/outage_rig.py) on UDP, TCP and a pty behind a symlink (the
serial device keeps its name across the simulator's restarts, as a USB adapter's udev name does),
stopped and restarted while the client runs, or silenced; outages of 2 s, 30 s and 120 s.

For each: the client recovers by itself within :data:`RECOVERY` seconds of the GCU's return
(measured from the moment the new simulator listens); its link events say what happened
(``LOST`` … ``RESTORED``, then ``RESTARTED`` when the simulator restarted); nothing executes
twice (the simulators' logs); with ``restore=True`` the restarted GCU executes the mode and
zoom once each, and nothing else. Also: the app started 20 s before its GCU, on each
transport, and ``GAVE_UP`` with ``max_attempts`` set. The 30 s and 120 s outages run
concurrently in one test (the suite's wall time grows by one outage, not six); the same rules
run in virtual time in test_client_outages.py (fast tier)."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from gcu_async import GcuClient, Mode, connect
from gcu_async.client import ClientState
from gcu_async.transport import LinkEvent, LinkEventKind
from helpers.sim.outage_rig import SCHEMES, OutageRig

pytestmark = pytest.mark.subprocess

K = LinkEventKind
RECOVERY = 10.0
"""Seconds within which the client must be back after the GCU returns (the brief's bound:
a capped backoff of 2 s, or 5 s for a client still opening, plus one attempt)."""
SETUP = Counter({"EULER_CONTROL": 1, "ZOOM_TO": 1, "RANGING": 1})
"""What :func:`put_out_of_defaults` makes the GCU execute."""
OUT_OF_DEFAULTS = ("mode EULER_CONTROL -> POINTING_FOLLOW, zoom 5x -> 1x, ranging on -> off")


def options(scheme: str) -> dict[str, Any]:
    return {"local_port": 0} if scheme == "udp" else {}


async def put_out_of_defaults(gcu: GcuClient) -> None:
    """Euler control at pitch -30, yaw 90; zoom 5x; ranging on; then still for a while, so
    that no change is under way when the GCU goes (gcu_async.session.restart)."""
    await gcu.enter_euler_control(roll=0.0, pitch=-30.0, yaw=90.0)
    await gcu.reach_zoom(5.0, timeout=30.0)
    await gcu.set_ranging(True)
    await gcu.wait_attitude(pitch=-30.0, yaw=90.0, timeout=30.0)
    await asyncio.sleep(1.5)


@dataclass
class Run:
    """What one scenario saw."""

    scheme: str
    down: float
    restart: bool
    restore: bool = False
    events: list[tuple[float, LinkEvent]] = field(default_factory=list)
    back_at: float = 0.0
    """``time.monotonic()`` when the GCU was back (listening again, or its silence over)."""
    up_at: float = 0.0
    runs: list[Counter[str]] = field(default_factory=list)

    def kinds(self, *, errors: bool = False) -> list[LinkEventKind]:
        return [e.kind for _, e in self.events if errors or e.kind is not K.ERROR]

    def check(self) -> None:
        label = f"{self.scheme}, {self.down:g} s, restart={self.restart}"
        assert 0.0 <= self.up_at - self.back_at <= RECOVERY, (label, self.up_at - self.back_at)
        expected = [K.UP, K.LOST, K.RESTORED] + ([K.RESTARTED] if self.restart else [])
        assert self.kinds() == expected, (label, self.events)
        if self.restart:
            detail = self.events[-1][1].detail
            assert detail.startswith(f"the GCU restarted: {OUT_OF_DEFAULTS}"), (label, detail)
            assert self.runs[0] == SETUP, (label, self.runs)
            restored = Counter({"EULER_CONTROL": 1, "ZOOM_TO": 1}) if self.restore else Counter()
            assert self.runs[1] == restored + Counter({"TAKE_PHOTO": 1}), (label, self.runs)
        else:
            assert self.runs == [SETUP + Counter({"TAKE_PHOTO": 1})], (label, self.runs)


async def outage(rig: OutageRig, down: float, *, restart: bool, restore: bool = False) -> Run:
    """A client up against ``rig`` (running), an outage of ``down`` seconds (a restart: the
    simulator stopped and started again; else: silenced), the client back, a photo taken."""
    run = Run(rig.scheme, down, restart, restore)
    gcu = connect(rig.url, restore=restore, **options(rig.scheme))
    gcu.on_link_change(lambda event: run.events.append((time.monotonic(), event)))
    async with gcu:
        await put_out_of_defaults(gcu)
        if restart:
            await rig.restart(down)
            run.back_at = rig.started_at[-1]
        else:
            rig.silence()
            await asyncio.sleep(down)
            run.back_at = time.monotonic()
        await gcu.wait_link(True, timeout=RECOVERY + 5.0)
        run.up_at = time.monotonic()
        assert gcu.state is ClientState.OPEN
        if restore:
            await gcu.wait_zoom(5.0, timeout=30.0)
            await gcu.wait_attitude(pitch=-30.0, yaw=90.0, timeout=30.0)
            status = gcu.status
            assert status is not None and status.mode is Mode.EULER_CONTROL
        await gcu.take_photo()
    await rig.stop()
    run.runs = rig.runs
    return run


@contextlib.asynccontextmanager
async def rigs(tmp_path: Path, names: list[str], **kwargs: Any) -> Any:
    """One started rig per name (``<scheme>`` or ``<scheme>-<tag>``), each in its own
    directory; all closed at the end."""
    made = []
    try:
        for name in names:
            directory = tmp_path / name
            directory.mkdir()
            made.append(OutageRig(name.partition("-")[0], directory, **kwargs))
        yield made
    finally:
        for rig in made:
            await rig.close()


@pytest.mark.parametrize("kind", ["silence", "restart", "restart-restore"])
@pytest.mark.parametrize("scheme", SCHEMES)
async def test_a_2_s_outage(scheme: str, kind: str, tmp_path: Path) -> None:
    restart, restore = kind.startswith("restart"), kind.endswith("restore")
    async with rigs(tmp_path, [scheme], silence=2.0) as (rig,):
        await rig.start()
        run = await outage(rig, 2.0, restart=restart, restore=restore)
    run.check()
    if restart and scheme == "udp":  # nothing listened meanwhile: the OS said so, once
        assert run.kinds(errors=True).count(K.ERROR) == 1, run.events


@pytest.mark.timeout(600)
async def test_30_s_and_120_s_outages_on_every_transport(tmp_path: Path) -> None:
    """Six power cycles at once: each transport, 30 s and 120 s off; the 120 s ones with
    ``restore=True``."""
    cases = [(scheme, down) for scheme in SCHEMES for down in (30.0, 120.0)]
    names = [f"{scheme}-{down:g}" for scheme, down in cases]
    async with rigs(tmp_path, names) as made:
        await asyncio.gather(*(rig.start() for rig in made))
        runs = await asyncio.gather(*(
            outage(rig, down, restart=True, restore=down > 60.0)
            for rig, (_, down) in zip(made, cases, strict=True)
        ))  # fmt: skip
    for run in runs:
        run.check()


@pytest.mark.timeout(300)
async def test_an_app_started_20_s_before_its_gcu_on_every_transport(tmp_path: Path) -> None:
    async def app(rig: OutageRig) -> Run:
        run = Run(rig.scheme, 20.0, restart=False)
        gcu = connect(rig.url, wait=False, **options(rig.scheme))
        gcu.on_link_change(lambda event: run.events.append((time.monotonic(), event)))
        async with gcu:
            assert gcu.state is ClientState.OPENING and gcu.status is None
            await asyncio.sleep(20.0)
            await rig.start()
            run.back_at = rig.started_at[-1]
            await gcu.wait_link(True, timeout=RECOVERY + 5.0)
            run.up_at = time.monotonic()
            await gcu.take_photo()
        await rig.stop()
        run.runs = rig.runs
        return run

    async with rigs(tmp_path, list(SCHEMES)) as made:
        runs = await asyncio.gather(*(app(rig) for rig in made))
    for run in runs:
        assert 0.0 <= run.up_at - run.back_at <= RECOVERY, (run.scheme, run.up_at - run.back_at)
        kinds = run.kinds()
        assert kinds[-1] is K.UP and kinds.count(K.UP) == 1, (run.scheme, run.events)
        assert set(kinds[:-1]) == {K.RETRYING}, (run.scheme, run.events)
        assert run.runs == [Counter({"TAKE_PHOTO": 1})], (run.scheme, run.runs)


@pytest.mark.parametrize("scheme", ["tcp", "serial"])
async def test_max_attempts_gives_up_and_the_client_fails(scheme: str, tmp_path: Path) -> None:
    """With ``max_attempts`` the transport gives up on a GCU that stays away; the client
    says so (``GAVE_UP``, ``FAILED``) and the same client opens again once it is back."""
    async with rigs(tmp_path, [scheme]) as (rig,):
        await rig.start()
        gcu = connect(f"{rig.url}?max_attempts=3&backoff_cap=0.2")
        events: list[LinkEvent] = []
        gcu.on_link_change(events.append)
        async with gcu:
            await gcu.take_photo()
            await rig.stop()
            with pytest.raises(ConnectionError, match="the client failed"):
                await gcu.wait_link(True, timeout=10.0)  # it never comes: the client fails
            assert gcu.state is ClientState.FAILED
            assert gcu.failure is not None and "giving up after 3 reconnect attempts" in gcu.failure
            assert [e.kind for e in events] == [K.UP, K.LOST, K.GAVE_UP]
            await rig.start()
            await gcu.open()
            await gcu.take_photo()
        assert gcu.state is ClientState.CLOSED
        await rig.stop()
        assert rig.runs == [Counter({"TAKE_PHOTO": 1})] * 2
