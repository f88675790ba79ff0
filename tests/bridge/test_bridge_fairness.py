"""Fair admission (docs/mavlink-bridge.md, "The bridge contract", BG8), attacked: a ground
station that heartbeats keeps its share of the command budget while another process floods
the same ``udpin:`` port — the flood a field report measured (5,000 commands/s, each from its own
system/component ids), a flood that heartbeats too, a flood with the station's own ids,
floods from many addresses and on many links. Real loopback sockets, pymavlink on both
sides, the flood in a process of its own (tests/helpers/bridge/mavlink_flood.py)."""

from __future__ import annotations

import asyncio
import contextlib
import subprocess
import sys
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from gcu_async.bridge._mavlink import mavlink
from helpers.bridge.rig import CAMERA, Peer, Rig, bridge_rig

PHOTO = mavlink.MAV_CMD_IMAGE_START_CAPTURE
ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
FLOOD = Path(__file__).parents[1] / "helpers" / "bridge" / "mavlink_flood.py"
STATION = (250, mavlink.MAV_COMP_ID_MISSIONPLANNER)
ANSWER_WITHIN = 5.0
"""Seconds within which the station's photo must be answered (the issue: never)."""


def start_flood(port: int, rate: int, seconds: float, pairs: int,
                *options: str) -> subprocess.Popen[str]:  # fmt: skip
    return subprocess.Popen([sys.executable, str(FLOOD), str(port), "command", str(rate),
                             str(seconds), str(pairs), *options], stdout=subprocess.PIPE,
                            text=True)  # fmt: skip


def udpin_port(rig: Rig, index: int = -1) -> int:
    return int(rig.bridge.links[index].local_address[1])  # type: ignore[attr-defined]


@contextlib.asynccontextmanager
async def station_on(port: int, ids: tuple[int, int] = STATION) -> AsyncIterator[Peer]:
    """A ground station on the bridge's udpin ``port``, heartbeating at 1 Hz, once the
    bridge writes to it."""
    station = Peer(*ids, bridge_port=port)
    beating = asyncio.ensure_future(station.heartbeats())
    try:
        await station.wait("HEARTBEAT", lambda m: m.get_srcComponent() == CAMERA, timeout=5.0)
        yield station
    finally:
        beating.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await beating
        station.close()


@contextlib.asynccontextmanager
async def flooding(rig: Rig, port: int, *options: str, rate: int = 5000,
                   seconds: float = 10.0, pairs: int = 50_000) -> AsyncIterator[None]:  # fmt: skip
    """A flood into ``port`` from another process, under way (the bridge is receiving it);
    stopped on exit."""
    before = rig.bridge.stats["messages"]
    proc = start_flood(port, rate, seconds, pairs, *options)
    try:
        await rig.until(lambda: rig.bridge.stats["messages"] > before + rate // 5, 20.0,
                        "the flood arriving")  # fmt: skip
        yield
    finally:
        proc.terminate()
        await asyncio.to_thread(proc.communicate, timeout=20)


PHOTOS = 2
"""Photos the station takes under each flood, :data:`PHOTO_SPACING` apart."""
PHOTO_SPACING = 1.0
"""Seconds between the station's photos: a user's pace. (Back to back, a station is one of
the shares taking turns, each served in its turn: BG8.)"""


def kernel_drops(port: int) -> int | None:
    """Datagrams the kernel dropped at the loopback UDP socket bound to ``port`` (its
    receive buffer full; Linux's /proc/net/udp), ``None`` where that cannot be read."""
    try:
        rows = Path("/proc/net/udp").read_text(encoding="ascii").splitlines()[1:]
    except OSError:
        return None
    for row in rows:
        fields = row.split()
        if fields[1].endswith(f":{port:04X}"):
            return int(fields[-1])
    return None


async def answered(rig: Rig, station: Peer, port: int) -> float:
    """The station takes :data:`PHOTOS` photos as a ground station does (retransmitting
    every second while unanswered); each is ACCEPTED within :data:`ANSWER_WITHIN`, at its
    first transmission unless the kernel dropped datagrams at the bridge's socket meanwhile
    (before the bridge reads them: outside BG8), and the bridge never shed nor refused a
    command of the station's. Returns the longest wait."""
    longest = 0.0
    for n in range(PHOTOS):
        if n:
            await station.collect(PHOTO_SPACING)
        drops = kernel_drops(port)
        start = time.monotonic()
        ack, transmissions = await station.command_retried(CAMERA, PHOTO, 0, 0, 1)
        elapsed = time.monotonic() - start
        longest = max(longest, elapsed)
        assert ack.result == ACCEPTED, mavlink.enums["MAV_RESULT"][ack.result].name
        assert elapsed <= ANSWER_WITHIN
        if transmissions > 1:
            after = kernel_drops(port)
            assert drops is not None and after is not None and after > drops, (
                f"answered after {transmissions} transmissions, no datagram dropped by the "
                "kernel")  # fmt: skip
            print(f"\n(the kernel dropped {after - drops} datagrams: {transmissions} "
                  "transmissions)")  # fmt: skip
    share = next(p.share for p in rig.bridge.links[-1].destinations()
                 if p.addr == ("127.0.0.1", station.port))  # fmt: skip
    assert (share.shed, share.refused) == (0, 0)
    return longest


async def test_a_station_keeps_its_share_through_the_field_reports_flood() -> None:
    """The field report: 5,000 commands/s for 10 s from another socket on the station's
    udpin port, each from its own ids; the station heartbeats at 1 Hz and retransmits its
    photo every second. Main: no answer at all to most photos (the link's budget went to the
    flood; one that got through found the link's room full: TEMPORARILY_REJECTED)."""
    async with bridge_rig(extra_links=("udpin:127.0.0.1:0",)) as rig:
        port = udpin_port(rig)
        async with station_on(port) as station, flooding(rig, port):
            elapsed = await answered(rig, station, port)
            stats = dict(rig.bridge.stats)
        print(f"\nanswered within {elapsed:.2f} s; stats {stats}")


def acks_for_others(station: Peer) -> list[Any]:
    """COMMAND_ACKs the station got for commands it never sent (it sends only photos)."""
    station.poll()
    return [m for m in station.messages if m.get_type() == "COMMAND_ACK" and m.command != PHOTO]


async def test_a_flood_that_heartbeats_too_gets_a_share_not_the_stations() -> None:
    """The flood's address sends HEARTBEATs as well: it is a station, with a share of its
    own; the ground station keeps its own."""
    async with bridge_rig(extra_links=("udpin:127.0.0.1:0",)) as rig:
        port = udpin_port(rig)
        async with station_on(port) as station, flooding(rig, port, "--heartbeats"):
            elapsed = await answered(rig, station, port)
        print(f"\nanswered in {elapsed:.2f} s; stats {rig.bridge.stats}")


async def test_a_flood_with_the_stations_own_ids_neither_takes_its_share_nor_answers_it(
) -> None:
    """Every flood message carries the station's own system and component ids (and
    HEARTBEATs with them): the ids identify nobody, the address does. The station is
    answered, and no answer to the flood's commands — addressed to the station's ids —
    reaches it. Main wrote every answer to every sender on the link."""
    async with bridge_rig(extra_links=("udpin:127.0.0.1:0",)) as rig:
        port = udpin_port(rig)
        ids = f"{STATION[0]}:{STATION[1]}"
        async with station_on(port) as station, flooding(rig, port, "--ids", ids,
                                                         "--heartbeats"):  # fmt: skip
            elapsed = await answered(rig, station, port)
            await station.collect(1.0)
            forged = acks_for_others(station)
            taken = rig.bridge.stats["commands"]
        print(f"\nanswered in {elapsed:.2f} s; {taken} commands taken; stats {rig.bridge.stats}")
        assert taken > 50  # the flood's commands were taken and answered — to the flood
        assert forged == [], f"{len(forged)} answers to the flood's commands reached the station"


async def test_many_senders_that_came_first_cannot_keep_a_station_out() -> None:
    """40 addresses flood first (valid commands, no HEARTBEAT), taking every destination
    slot of the udpin link; a ground station that heartbeats then joins, becomes a
    destination in place of one of them, and is answered. Main: never written to."""
    async with bridge_rig(extra_links=("udpin:127.0.0.1:0",)) as rig:
        port = udpin_port(rig)
        link = rig.bridge.links[-1]
        async with flooding(rig, port, "--sockets", "40"):
            await rig.until(lambda: len(link.destinations()) == 16, 5.0,  # type: ignore[attr-defined]
                            "the flood filling the destinations")  # fmt: skip
            async with station_on(port) as station:
                elapsed = await answered(rig, station, port)
        print(f"\nanswered in {elapsed:.2f} s; stats {rig.bridge.stats}")


async def test_heartbeating_senders_that_come_later_cannot_push_a_station_out() -> None:
    """The station first; then 40 addresses that heartbeat flood the port (2,000 commands/s:
    50/s each, beyond a share's 20/s): they fill the free destination slots, never the
    station's, and take nothing of its share. Once each of the 15 flood shares has had its
    turn, the station's photo goes next (served less recently than all of them); before
    that it waits for one command of each (BG8; the pure rule:
    tests/bridge/test_bridge_admission.py). (At 5,000/s the 15 shares' admitted commands
    and the parsing saturate the bridge's process on a 2-core machine and the kernel drops
    datagrams of every sender, the station's included: see docs/mavlink-bridge.md.)"""
    async with bridge_rig(extra_links=("udpin:127.0.0.1:0",)) as rig:
        port = udpin_port(rig)
        link = rig.bridge.links[-1]
        queue = rig.bridge.executor.queue
        async with station_on(port) as station, flooding(rig, port, "--sockets", "40",
                                                         "--heartbeats", rate=2000,
                                                         pairs=20_000):  # fmt: skip
            await rig.until(lambda: len(link.destinations()) == 16, 5.0,  # type: ignore[attr-defined]
                            "the flood filling the destinations")  # fmt: skip
            await rig.until(lambda: len(queue.shares) >= 15
                            and all(share in queue.served for share in queue.shares), 10.0,
                            "every flood share served once")  # fmt: skip
            elapsed = await answered(rig, station, port)
            assert ("127.0.0.1", station.port) in link.destination_addresses  # type: ignore[attr-defined]
        print(f"\nanswered in {elapsed:.2f} s; stats {rig.bridge.stats}")


async def test_floods_on_many_links_leave_a_station_its_turn() -> None:
    """Four udpin links flooded at once (1,250 commands/s each, 5,000/s in all, each from
    its own ids), the station on a fifth: the shares take turns, so its photo waits at most
    one command of each."""
    links = ("udpin:127.0.0.1:0",) * 5
    async with bridge_rig(extra_links=links) as rig:
        ports = [udpin_port(rig, i) for i in range(-5, 0)]
        async with contextlib.AsyncExitStack() as stack:
            for flooded in ports[:4]:
                await stack.enter_async_context(flooding(rig, flooded, rate=1250,
                                                         pairs=12_500))  # fmt: skip
            station = await stack.enter_async_context(station_on(ports[4]))
            elapsed = await answered(rig, station, ports[4])
        print(f"\nanswered in {elapsed:.2f} s; stats {rig.bridge.stats}")
