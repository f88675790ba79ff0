"""The bridge's admission rules, pure (gcu_async.bridge.admission; docs/mavlink-bridge.md,
"The bridge contract", rules 1, 3, 5, 6): the retransmission rule, what a new command
supersedes (in its share only), the bounds, the memory's eviction order, the shares' turns,
the command budget and the log limiter."""

from __future__ import annotations

import logging
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.bridge import admission
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.admission import Budget, Entry, Memory, Queue, Share, is_retransmission
from gcu_async.bridge.commands import CommandIn
from gcu_async.bridge.lograte import LogLimiter

CAMERA = mavlink.MAV_COMP_ID_CAMERA
ZOOM = mavlink.MAV_CMD_SET_CAMERA_ZOOM
PHOTO = mavlink.MAV_CMD_IMAGE_START_CAPTURE


def cmd(command: int = ZOOM, *params: float, source: tuple[int, int] = (255, 190),
        confirmation: int = 0, frame: int | None = None) -> CommandIn:  # fmt: skip
    values = (*params, *([0.0] * (7 - len(params))))
    return CommandIn(command, values, source, 1, CAMERA, frame,  # type: ignore[arg-type]
                     confirmation)  # fmt: skip


def entry(c: CommandIn, share: object = "a", at: float = 0.0) -> Entry:
    return Entry(c, CAMERA, share, at, admission.SLOTS.get(c.command),
                 stop=admission.is_stop(c), confirmation=c.confirmation)  # fmt: skip


PARAM = st.sampled_from([0.0, 1.0, -1.0, 0.5, math.nan, math.inf])


@given(st.lists(PARAM, min_size=7, max_size=7), st.lists(PARAM, min_size=7, max_size=7),
       st.integers(0, 255), st.integers(0, 255))  # fmt: skip
def test_retransmission_rule(a: list[float], b: list[float], c1: int, c2: int) -> None:
    old = entry(cmd(ZOOM, *a, confirmation=c1))
    new = cmd(ZOOM, *b, confirmation=c2)
    same = all(x == y or (math.isnan(x) and math.isnan(y)) for x, y in zip(a, b, strict=True))
    assert is_retransmission(new, old, 0.0) == (same and c2 > 0 and c2 >= c1)


def test_command_int_repeats_within_the_recent_window_only() -> None:
    old = entry(cmd(ZOOM, 1, 1, frame=0))
    assert is_retransmission(cmd(ZOOM, 1, 1, frame=0), old, 0.0)
    assert not is_retransmission(cmd(ZOOM, 1, 1, frame=3), old, 0.0)  # another frame
    old.done_at = 1.0
    assert is_retransmission(cmd(ZOOM, 1, 1, frame=0), old, 1.0 + admission.RECENT_SECONDS)
    assert not is_retransmission(cmd(ZOOM, 1, 1, frame=0), old, 1.1 + admission.RECENT_SECONDS)


def test_a_stop_is_never_superseded_and_a_new_intent_replaces_the_waiting_one() -> None:
    q = Queue()
    zoom_in = entry(cmd(ZOOM, mavlink.ZOOM_TYPE_CONTINUOUS, 1))
    stop = entry(cmd(ZOOM, mavlink.ZOOM_TYPE_CONTINUOUS, 0))
    zoom_out = entry(cmd(ZOOM, mavlink.ZOOM_TYPE_CONTINUOUS, -1))
    photo = entry(cmd(PHOTO, 0, 0, 1))
    q.push(zoom_in)
    q.push(photo)
    assert q.superseded_by(stop) == [zoom_in]
    q.remove(zoom_in)
    q.push(stop)
    assert q.superseded_by(zoom_out) == []  # the stop stays
    assert q.superseded_by(entry(cmd(PHOTO, 0, 0, 1))) == []  # photos have no slot


def test_a_share_supersedes_only_its_own_waiting_commands() -> None:
    """Another share's newer zoom (a flood's, say) does not cancel a station's waiting zoom:
    each share's latest intent gets its turn."""
    q = Queue()
    station_zoom = entry(cmd(ZOOM, mavlink.ZOOM_TYPE_RANGE, 10), share="station")
    q.push(station_zoom)
    assert q.superseded_by(entry(cmd(ZOOM, mavlink.ZOOM_TYPE_RANGE, 90), share="flood")) == []
    assert q.superseded_by(entry(cmd(ZOOM, mavlink.ZOOM_TYPE_RANGE, 20),
                                 share="station")) == [station_zoom]  # fmt: skip


def test_bounds_are_per_share_and_none_is_common() -> None:
    q = Queue()
    for n in range(admission.MAX_WAITING_PER_SHARE):
        q.push(entry(cmd(PHOTO, 0, 0, 1, source=(n, n)), share="flood"))
    assert "from this sender" in (q.refusal(entry(cmd(PHOTO), share="flood")) or "")
    for flood in range(50):  # any number of other full shares leave a station its room
        for _ in range(admission.MAX_WAITING_PER_SHARE):
            q.push(entry(cmd(PHOTO), share=("other", flood)))
    assert q.refusal(entry(cmd(PHOTO), share="station")) is None


def test_expiry_and_the_next_deadline() -> None:
    q = Queue()
    assert q.next_deadline() == math.inf
    early, late = entry(cmd(PHOTO), at=0.0), entry(cmd(PHOTO), share="b", at=1.0)
    q.push(late)
    q.push(early)
    assert q.next_deadline() == admission.COMMAND_WAIT
    assert q.expired(admission.COMMAND_WAIT - 0.001) == []
    assert q.expired(admission.COMMAND_WAIT) == [early]


def test_shares_take_turns() -> None:
    q = Queue()
    for n in range(5):
        q.push(entry(cmd(PHOTO, n), share="flood"))
    q.push(entry(cmd(PHOTO, 99), share="gcs"))
    order = []
    while (e := q.pop()) is not None:
        order.append((e.share, e.cmd.params[0] if e.cmd else None))
    assert order[:2] == [("flood", 0), ("gcs", 99)]
    assert q.size == 0 and not q.shares


def test_a_station_that_sends_now_and_then_goes_ahead_of_busy_shares() -> None:
    """Twenty flood shares keep commands waiting all the time; a station's occasional
    command is next (it was served longer ago than any of them), where a plain rotation
    would put it behind all twenty."""
    q = Queue()
    for turn in range(200):
        for flood in range(20):
            while q.refusal(e := entry(cmd(PHOTO), share=flood)) is None:
                q.push(e)
        if turn == 100:
            q.push(entry(cmd(PHOTO, 1), share="station"))
        e = q.pop()
        assert e is not None
        if turn == 100:
            assert e.share == "station"
        if turn == 105:  # served 5 turns ago: the 15 floods served before it go first
            q.push(entry(cmd(PHOTO, 2), share="station"))
            order = [q.pop().share for _ in range(16)]  # type: ignore[union-attr]
            assert order.index("station") == 15 and len(set(order)) == 16
    assert len(q.served) <= len(q.shares) + admission.REMEMBERED_TURNS


def test_idle_shares_are_forgotten_oldest_first() -> None:
    q = Queue()
    for n in range(admission.REMEMBERED_TURNS + 50):
        q.push(entry(cmd(PHOTO), share=n))
        q.pop()
    assert len(q.served) == admission.REMEMBERED_TURNS
    assert min(q.served) == 50  # the 50 served longest ago are the ones forgotten


@given(st.lists(st.tuples(st.booleans(), st.integers(0, 5)), max_size=300))
def test_a_share_waits_at_most_one_turn_of_each_other_share(
        ops: list[tuple[bool, int]]) -> None:  # fmt: skip
    """Whatever the others push and whenever, between a command of share 0 reaching the
    queue and its turn, each other share runs at most one command more than share 0 had
    waiting ahead of it (rule 3: the shares take turns)."""
    q = Queue()
    pushed = 0
    waiting: list[int] = []
    ahead: dict[int, int] = {}
    runs_since: dict[int, dict[object, int]] = {}
    for is_pop, share in ops:
        if not is_pop:
            e = entry(cmd(PHOTO, pushed), share=share)
            if q.refusal(e) is None:
                q.push(e)
                if share == 0:
                    ahead[pushed], runs_since[pushed] = len(waiting), {}
                    waiting.append(pushed)
            pushed += 1
            continue
        e = q.pop()
        if e is None:
            continue
        number = int(e.cmd.params[0])  # type: ignore[union-attr]
        if e.share == 0:
            assert waiting.pop(0) == number  # its own in order
            for other, count in runs_since.pop(number).items():
                assert count <= ahead[number] + 1, (other, count, ahead[number])
        else:
            for seen in runs_since.values():
                seen[e.share] = seen.get(e.share, 0) + 1


def test_shares_are_independent() -> None:
    a, b = Share("a"), Share("b")
    assert sum(a.budget.take(0.0) for _ in range(10_000)) == admission.COMMAND_BURST
    assert b.budget.take(0.0)  # a's flood took nothing from b
    assert a.memory is not b.memory


@given(st.lists(st.tuples(st.integers(0, 3000), st.booleans(), st.floats(0, 0.01)),
                max_size=3000))  # fmt: skip
def test_memory_is_bounded_and_keeps_what_ran(ops: list[tuple[int, bool, float]]) -> None:
    memory = Memory()
    now = 0.0
    ran: list[Entry] = []
    for n, did_run, dt in ops:
        now += dt
        e = entry(cmd(PHOTO, source=(n % 250, n // 250)), at=now)
        memory.add(e, now)
        e.state, e.ran, e.done_at, e.result = "done", did_run, now, 0
        if did_run:
            ran.append(e)
        assert len(memory.keys) <= admission.MAX_REMEMBERED + 1
    for e in ran:  # a command that ran is remembered for RECENT_SECONDS after its answer
        if e.done_at is not None and now - e.done_at <= admission.RECENT_SECONDS:
            assert e.cmd is not None
            again = cmd(PHOTO, source=e.cmd.source, confirmation=1)
            assert memory.find(again, CAMERA, now) is not None


def test_budget() -> None:
    budget = Budget()
    taken = sum(budget.take(0.0) for _ in range(1000))
    assert taken == admission.COMMAND_BURST
    # sustained: a try every millisecond for 2 s takes the rate's worth, no more
    taken = sum(budget.take(n / 1000) for n in range(1, 2001))
    assert abs(taken - 2 * admission.COMMANDS_PER_SECOND) <= 1


def test_log_limiter(caplog: pytest.LogCaptureFixture) -> None:
    clock = [0.0]
    logger = logging.getLogger("test.lograte")
    limiter = LogLimiter(logger, burst=3, window=10.0, clock=lambda: clock[0])
    with caplog.at_level(logging.INFO, logger="test.lograte"):
        for n in range(1000):
            limiter.log(logging.INFO, "kind", "line %d", n)
        clock[0] = 10.0
        limiter.flush()
    assert [r.getMessage() for r in caplog.records] == [
        "line 0", "line 1", "line 2", "bridge: 997 more kind lines suppressed in 10 s"]


def test_the_contract_states_the_bounds_the_code_uses() -> None:
    from pathlib import Path

    text = " ".join((Path(__file__).parents[2] / "docs" / "mavlink-bridge.md").read_text(
        encoding="utf-8").split())
    from gcu_async.bridge import links, stream_link, udp_link
    from gcu_async.session import SessionConfig

    a = admission
    for phrase in (
        f"within **{a.COMMAND_WAIT:g} s**",
        f"At most {a.MAX_WAITING_PER_SHARE} commands waiting per share",
        f"Each share may bring {a.COMMANDS_PER_SECOND:g} commands/s (a burst of "
        f"{a.COMMAND_BURST:g})",
        f"at most {udp_link.MAX_DESTINATIONS} on a `udpin` link, "
        f"{stream_link.MAX_TCP_CLIENTS} on `tcpin`",
        f"HEARTBEAT within the last {links.STATION_SECONDS:g} s and is one of the link's "
        "destinations",
        f"the last reply is at most {SessionConfig().control_silence:g} s old",
        f"{a.MAX_REMEMBERED:,} (sender, component, command) keys × {a.PER_KEY} per share",
        f"taken at most {1 / a.CONTROL_INTERVAL:g} times a second",
        f"for {a.RECENT_SECONDS:g} s after its answer",
    ):
        assert phrase in text, phrase
