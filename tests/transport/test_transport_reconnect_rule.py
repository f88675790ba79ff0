"""How long a transport keeps restoring a lost link (docs/transports.md, "Reconnecting"), in
virtual time (tests/helpers/transport/vclock.py): by default until it is closed, whatever the
outage — 2 s,
2 minutes, six hours —, with attempts at most ``cap`` apart, so the link is back within ``cap``
of the peer's return; ``max_attempts`` / ``max_total`` make it give up (``GAVE_UP``), and
so does ``reconnect=False``, at once. The same schedule code (``retry``, ``Reopener``) runs
TCP's reconnection and serial's and UDP's reopening; tests/transport/test_transport_tcp.py,
test_transport_serial.py and tests/client/test_client_outage_matrix.py show it over real
sockets and ptys."""

from __future__ import annotations

import asyncio
import itertools
import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.errors import LinkLost
from gcu_async.transport._reopen import Reopener
from gcu_async.transport.backoff import Backoff, retry
from gcu_async.transport.base import LinkEvent, LinkEventKind
from helpers.scale import scaled
from helpers.transport.vclock import run

OUTAGES = (2.0, 30.0, 120.0, 21600.0)


class Peer:
    """A peer that refuses every attempt until ``back_at`` (virtual seconds)."""

    def __init__(self, back_at: float) -> None:
        self.back_at = back_at
        self.attempts: list[float] = []

    async def attempt(self, timeout: float) -> None:
        now = asyncio.get_running_loop().time()
        self.attempts.append(now)
        if now < self.back_at:
            raise LinkLost("cannot connect: refused")


@pytest.mark.parametrize("outage", OUTAGES)
def test_the_default_schedule_outlasts_any_outage(outage: float) -> None:
    backoff = Backoff()

    async def main() -> float:
        peer = Peer(outage)
        result = await retry(peer.attempt, backoff, random.Random(1), 3.0)
        assert result is None
        gaps = [b - a for a, b in itertools.pairwise(peer.attempts)]
        assert max(gaps) <= backoff.cap
        return peer.attempts[-1]

    restored = run(main(), timeout=outage + 60.0)
    assert outage <= restored <= outage + backoff.cap


@settings(max_examples=scaled(60, 15), deadline=None)
@given(outage=st.floats(0.0, 600.0), seed=st.integers(0, 2**32 - 1),
       cap=st.sampled_from([0.5, 2.0, 5.0]))  # fmt: skip
def test_back_within_cap_of_the_peers_return(outage: float, seed: int, cap: float) -> None:
    backoff = Backoff(base=0.05, cap=cap)

    async def main() -> float:
        peer = Peer(outage)
        assert await retry(peer.attempt, backoff, random.Random(seed), 3.0) is None
        return peer.attempts[-1]

    assert outage <= run(main(), timeout=outage + 60.0) <= outage + cap


@pytest.mark.parametrize(("backoff", "attempts"), [
    (Backoff(max_attempts=5), 5), (Backoff(cap=2.0, max_total=30.0), None),
])  # fmt: skip
def test_opt_in_bounds_give_up(backoff: Backoff, attempts: int | None) -> None:
    async def main() -> tuple[LinkLost | None, Peer, float]:
        peer = Peer(1e9)
        result = await retry(peer.attempt, backoff, random.Random(2), 3.0)
        return result, peer, asyncio.get_running_loop().time()

    result, peer, ended = run(main())
    assert isinstance(result, LinkLost) and "refused" in str(result)
    if attempts is not None:
        assert len(peer.attempts) == attempts
    else:
        assert backoff.max_total is not None
        assert ended <= backoff.max_total and peer.attempts[-1] <= backoff.max_total


def _reopen(reconnect: bool, backoff: Backoff | None, back_at: float,
            until: float) -> list[tuple[float, LinkEvent]]:  # fmt: skip
    """A :class:`Reopener` started after a loss at 0, against a peer back at ``back_at``;
    the events it emits by ``until``."""

    async def main() -> list[tuple[float, LinkEvent]]:
        loop = asyncio.get_running_loop()
        events: list[tuple[float, LinkEvent]] = []
        reopener = Reopener(reconnect, backoff, random.Random(3))
        peer = Peer(back_at)
        reopener.start("serial:///dev/gcu", peer.attempt, 1.0, "reopened",
                       lambda e: events.append((loop.time(), e)))  # fmt: skip
        await asyncio.sleep(until)
        assert not reopener.running
        reopener.closing = True
        await reopener.stop()
        return events

    return run(main())


def test_reopening_restores_after_an_hour_by_default() -> None:
    events = _reopen(True, None, 3600.0, 3700.0)
    assert [e.kind for _, e in events] == [LinkEventKind.RESTORED]
    assert 3600.0 <= events[0][0] <= 3600.0 + Backoff().cap


def test_reopening_gives_up_with_bounds_and_at_once_without_reconnect() -> None:
    events = _reopen(True, Backoff(max_attempts=3), 3600.0, 100.0)
    assert [e.kind for _, e in events] == [LinkEventKind.GAVE_UP]
    assert events[0][1].detail.startswith("giving up after 3 reconnect attempts: last error: ")
    events = _reopen(False, None, 0.0, 100.0)
    assert [(t, e.kind) for t, e in events] == [(0.0, LinkEventKind.GAVE_UP)]
    assert events[0][1].detail == "giving up at once: reconnect is off (serial:///dev/gcu)"
