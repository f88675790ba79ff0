"""The bridge's admission rules, pure (gcu_async.bridge.admission; docs/mavlink-bridge.md,
"The bridge contract", rules 1, 3, 5, 6): the retransmission rule, what a new command
supersedes, the bounds, the memory's eviction order, round-robin between links, the
command budget and the log limiter."""

from __future__ import annotations

import logging
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.bridge import admission
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.admission import Budget, Entry, Memory, Queue, is_retransmission
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


def entry(c: CommandIn, link: object = "a", at: float = 0.0) -> Entry:
    return Entry(c, CAMERA, link, at, admission.SLOTS.get(c.command),
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


def test_bounds() -> None:
    q = Queue()
    for _ in range(admission.MAX_WAITING_PER_SOURCE):
        q.push(entry(cmd(PHOTO, 0, 0, 1, source=(9, 9))))
    assert "from (9, 9)" in (q.refusal(entry(cmd(PHOTO, source=(9, 9)))) or "")
    while q.size < admission.MAX_WAITING_PER_LINK:
        q.push(entry(cmd(PHOTO, source=(q.size, 1))))
    assert "this link" in (q.refusal(entry(cmd(PHOTO, source=(200, 1)))) or "")
    while q.size < admission.MAX_WAITING:
        q.push(entry(cmd(PHOTO, source=(q.size, 1)), link=("b", q.size)))
    assert "commands are waiting" in (q.refusal(entry(cmd(PHOTO), link="c")) or "")


def test_links_take_turns() -> None:
    q = Queue()
    for n in range(5):
        q.push(entry(cmd(PHOTO, n), link="flood"))
    q.push(entry(cmd(PHOTO, 99), link="gcs"))
    order = []
    while (e := q.pop()) is not None:
        order.append((e.link, e.cmd.params[0] if e.cmd else None))
    assert order[:2] == [("flood", 0), ("gcs", 99)]
    assert q.size == 0 and not q.links


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
    a = admission
    for phrase in (
        f"within **{a.COMMAND_WAIT:g} s**",
        f"At most {a.MAX_WAITING} commands wait ({a.MAX_WAITING_PER_LINK} from one link, "
        f"{a.MAX_WAITING_PER_SOURCE} from one sender)",
        f"bring {a.COMMANDS_PER_SECOND:g} commands/s (a burst of {a.COMMAND_BURST:g})",
        f"{a.MAX_REMEMBERED:,} (sender, component, command) keys × {a.PER_KEY} per link",
        f"taken at most {1 / a.CONTROL_INTERVAL:g} times a second",
        f"for {a.RECENT_SECONDS:g} s after its answer",
    ):
        assert phrase in text, phrase
