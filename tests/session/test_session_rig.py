"""The virtual-time rig's own bookkeeping (tests/helpers/session/vtime.py) against the plain
definitions it shortcuts: the contract's checks are only as good as these."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from gcu_async.session import Session
from gcu_async.session.pacing import WINDOW
from helpers.session.vtime import Rig

times = st.floats(0.0, 2.0, allow_nan=False)
stall_lists = st.lists(st.tuples(times, st.floats(0.0, 0.2)).map(lambda p: (p[0], p[0] + p[1])),
                       max_size=25)  # fmt: skip


def first_uncovered(stalls: list[tuple[float, float]], t: float) -> float:
    """The first instant from ``t`` on that no stall [start, stop) covers, by brute force."""
    moved = True
    while moved:
        moved = False
        for start, stop in stalls:
            if start <= t < stop:
                t, moved = stop, True
    return t


@given(stall_lists, st.lists(times, min_size=1, max_size=20))
def test_stall_end_is_the_first_instant_no_stall_covers(
    stalls: list[tuple[float, float]], probes: list[float]
) -> None:
    rig = Rig(Session(), stalls=stalls)
    edges = [x for stall in stalls for x in stall]
    for t in probes + edges:
        assert rig._stall_end(t) == first_uncovered(stalls, t), (stalls, t)


def most_in_window(times: list[float]) -> int:
    """Most of ``times`` within any WINDOW, from scratch (the pacer's arithmetic)."""
    return max((sum(1 for s in times[: i + 1] if s + WINDOW > t) for i, t in enumerate(times)),
               default=0)  # fmt: skip


@given(st.lists(st.lists(st.floats(0.0, 0.05), max_size=30), max_size=6))
def test_max_in_window_carried_on_between_calls_equals_from_scratch(
    batches: list[list[float]],
) -> None:
    rig = Rig(Session())
    now, sent = 0.0, []
    for gaps in batches:
        for gap in gaps:
            now += gap
            sent.append(now)
            rig.sent.append((now, None, None))  # type: ignore[arg-type]
        assert rig.max_in_window() == most_in_window(sent)
