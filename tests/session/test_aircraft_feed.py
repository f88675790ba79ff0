"""The aircraft feed in the sans-I/O session, in virtual time: INS-valid only with attitude,
acceleration and velocity all given and current, stale data withheld (counted, one warning
per episode, restored by the next update), GNSS time advancing between updates; a Hypothesis
property over any schedule of updates; and the simulator's GCU model seeing all of it
(docs/client.md, "Aircraft data: what the packets claim")."""

from __future__ import annotations

import logging
import math
from itertools import combinations
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.errors import FieldRangeError
from gcu_async.protocol import (
    AircraftState,
    GazeLock,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    decode_host_packet,
)
from gcu_async.protocol.gpstime import MS_PER_WEEK
from gcu_async.session import Session, TicketState
from helpers.session.vtime import Rig

ATT = (1.5, -2.0, 350.0)
ACC = (0.12, -0.25, 0.5)
VEL = (5.0, -1.25, 0.75)
POS = (47.3977418, 8.5455938, 488.0)
FULL = {"attitude": ATT, "acceleration": ACC, "velocity": VEL}
INS = ("attitude", "acceleration", "velocity")
INS_RAW = HostMainFrame._fields[4:13]
WEEK = 2300


def opened(timeout: float = 1.0) -> Session:
    session = Session(aircraft_timeout=timeout)
    session.open(0.0)
    return session


def packet(session: Session, now: float) -> HostPacket:
    """The packet the heartbeat sends at ``now`` (callers step 21 ms or more)."""
    data = session.poll(now)
    assert data is not None, f"no packet due at {now}"
    return decode_host_packet(data)


def ins_raw(p: HostPacket) -> tuple[int, ...]:
    return tuple(getattr(p.main, name) for name in INS_RAW)


def gnss_total(sub: HostSubFrame) -> int:
    return sub.gnss_week * MS_PER_WEEK + sub.gnss_ms


# -- 1. INS valid needs all three parts -----------------------------------------------------
@pytest.mark.parametrize("parts", [c for n in range(4) for c in combinations(INS, n)],
                         ids=lambda c: "+".join(c) or "none")  # fmt: skip
def test_ins_valid_only_with_all_three_parts(parts: tuple[str, ...]) -> None:
    session = opened()
    session.update_aircraft({p: FULL[p] for p in parts}, 0.0)
    p = packet(session, 0.0)
    complete = len(parts) == 3
    assert p.main.ins_valid is complete is session.ins_valid(0.0)
    if complete:
        assert ins_raw(p) == ins_raw(HostPacket(HostMainFrame.build(
            attitude=ATT, acceleration=ACC, velocity=VEL)))  # fmt: skip
        assert p.main.aircraft_attitude == ATT and p.main.velocity == VEL
    else:  # a part given alone is not sent, and zeros are never marked valid
        assert ins_raw(p) == (0,) * 9


def test_the_builders_mark_ins_valid_only_with_all_three() -> None:
    for n in range(4):
        for parts in combinations(INS, n):
            frame = HostMainFrame.build(**{p: FULL[p] for p in parts})
            assert frame.ins_valid is (n == 3), parts
            state = AircraftState(**{p: FULL[p] for p in parts})
            assert state.ins_complete is (n == 3)
            assert state.main_frame().ins_valid is (n == 3)


def test_clearing_one_part_clears_ins_valid() -> None:
    session = opened()
    session.update_aircraft(FULL, 0.0)
    assert packet(session, 0.0).main.ins_valid
    session.update_aircraft({"velocity": None}, 0.01)
    p = packet(session, 0.03)
    assert not p.main.ins_valid and ins_raw(p) == (0,) * 9
    assert session.stats.aircraft_stale == 0  # withheld for want of data, not for age


# -- 2. stale after the timeout, part by part ----------------------------------------------
def test_stale_after_the_timeout_not_before() -> None:
    session = opened(timeout=0.5)
    session.update_aircraft(FULL, 0.25)
    assert packet(session, 0.25).main.ins_valid
    assert packet(session, 0.75).main.ins_valid  # exactly the timeout: still current
    assert session.stats.aircraft_stale == 0
    p = packet(session, 0.7501 + 0.02)
    assert not p.main.ins_valid and ins_raw(p) == (0,) * 9
    assert session.stats.aircraft_stale == 1
    assert not session.ins_valid(0.8)
    assert session.aircraft.attitude == ATT  # the state as given is kept


def test_each_part_ages_on_its_own() -> None:
    # attitude at 50 Hz, velocity and acceleration given once: they go stale all the same
    session = opened(timeout=0.5)
    session.update_aircraft(FULL, 0.0)
    for i in range(1, 24):  # up to 0.483 s
        session.update_aircraft({"attitude": ATT}, i * 0.021)
        assert packet(session, i * 0.021).main.ins_valid
    t = 24 * 0.021
    session.update_aircraft({"attitude": ATT}, t)
    assert not packet(session, t).main.ins_valid
    assert session.stats.aircraft_stale == 1
    t += 0.021
    session.update_aircraft({"acceleration": ACC, "velocity": VEL}, t)
    assert packet(session, t).main.ins_valid


def test_set_aircraft_gives_every_part_at_once() -> None:
    session = opened(timeout=0.5)
    state = AircraftState(**FULL, position=POS)
    session.set_aircraft(state, 0.0)
    assert packet(session, 0.49).main.ins_valid
    session.set_aircraft(state, 0.49)  # the same values again: measured again
    p = packet(session, 0.9)
    assert p.main.ins_valid and p.sub is not None
    assert session.stats.aircraft_stale == 0


def test_a_rejected_update_changes_nothing_and_refreshes_nothing() -> None:
    session = opened(timeout=0.5)
    session.update_aircraft({**FULL, "position": POS}, 0.0)
    before = session.aircraft
    with pytest.raises(FieldRangeError, match="aircraft roll"):
        session.update_aircraft({**FULL, "attitude": (999.0, 0.0, 0.0)}, 0.4)
    with pytest.raises(TypeError, match="changes: speed: not AircraftState fields"):
        session.update_aircraft({"attitude": ATT, "speed": 3}, 0.4)
    with pytest.raises(TypeError, match="changes"):
        session.update_aircraft([("attitude", ATT)], 0.4)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="state"):
        session.set_aircraft(FULL, 0.4)  # type: ignore[arg-type]
    assert session.aircraft is before
    p = packet(session, 0.51)
    assert not p.main.ins_valid and p.sub is None  # still as old as at 0.0


@pytest.mark.parametrize(("value", "error"), [
    (0, FieldRangeError), (0.0, FieldRangeError), (-1.0, FieldRangeError),
    (10.000001, FieldRangeError), (math.inf, FieldRangeError), (math.nan, FieldRangeError),
    (True, TypeError), ("1", TypeError), (None, TypeError),
])  # fmt: skip
def test_aircraft_timeout_is_checked(value: Any, error: type[Exception]) -> None:
    with pytest.raises(error, match=r"^aircraft_timeout: "):
        Session(aircraft_timeout=value)


def test_aircraft_timeout_range_ends() -> None:
    assert Session(aircraft_timeout=10).config.aircraft_timeout == 10.0
    assert Session(aircraft_timeout=1e-9).config.aircraft_timeout == 1e-9
    assert Session().config.aircraft_timeout == 1.0  # the default: at most 1 s


# -- 3. the position and the sub frame -----------------------------------------------------
def test_stale_position_withholds_the_sub_frame_only() -> None:
    session = opened(timeout=0.5)
    session.update_aircraft({**FULL, "position": POS, "satellites": 12}, 0.0)
    sub = packet(session, 0.0).sub
    assert isinstance(sub, HostSubFrame) and sub.latitude_raw == 473977418
    session.update_aircraft(FULL, 0.3)
    p = packet(session, 0.55)
    assert p.main.ins_valid and p.sub is None
    assert session.stats.aircraft_stale == 1
    session.update_aircraft({"position": POS}, 0.6)
    p = packet(session, 0.6)
    assert isinstance(p.sub, HostSubFrame) and p.sub.satellites == 12


# -- 4. stale episodes: counted, one warning each ------------------------------------------
def test_one_warning_and_one_count_per_episode(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="gcu_async.session")
    session = opened(timeout=0.5)
    for start in (0.0, 2.0):  # two updates, each followed by 1.5 s without one
        session.update_aircraft({**FULL, "position": POS}, start)
        for i in range(72):  # a packet every 21 ms: 24 current, then 48 stale
            packet(session, start + i * 0.021)
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert session.stats.aircraft_stale == 2
    assert len(warnings) == 2, [r.getMessage() for r in warnings]
    message = warnings[0].getMessage()
    assert "attitude, acceleration, velocity, position not updated for 0.5 s" in message
    assert "INS-valid cleared" in message and "no sub frame" in message
    assert sum("current again" in r.getMessage() for r in caplog.records) == 1


# -- 5. GNSS time advances between updates -------------------------------------------------
def test_gnss_time_advances_with_the_session_clock_across_a_week() -> None:
    session = opened(timeout=10.0)
    given = WEEK * MS_PER_WEEK + MS_PER_WEEK - 100  # 100 ms before the week ends
    session.update_aircraft({"position": POS, "gnss_week": WEEK,
                             "gnss_ms": MS_PER_WEEK - 100}, 1.0)  # fmt: skip
    sent = []
    for i in range(12):
        now = 1.0 + i * 0.021
        sub = packet(session, now).sub
        assert isinstance(sub, HostSubFrame)
        assert gnss_total(sub) == given + math.floor((now - 1.0) * 1000)
        sent.append((sub.gnss_week, sub.gnss_ms))
    assert sent[0] == (WEEK, MS_PER_WEEK - 100)
    assert sent[-1] == (WEEK + 1, 131)  # 231 ms later: into the next week
    assert session.aircraft.gnss_ms == MS_PER_WEEK - 100  # the state keeps what was given


def test_the_same_reading_again_keeps_its_anchor_a_new_one_moves_it() -> None:
    session = opened(timeout=10.0)
    session.update_aircraft({"position": POS, "gnss_week": WEEK, "gnss_ms": 5000}, 0.0)
    # set_aircraft(mapper.state) at every message repeats the 1 Hz SYSTEM_TIME reading
    session.set_aircraft(session.aircraft, 0.5)
    session.update_aircraft({"gnss_week": WEEK, "gnss_ms": 5000}, 0.6)
    sub = packet(session, 0.7).sub
    assert isinstance(sub, HostSubFrame) and sub.gnss_ms == 5700  # no jump back to 5000
    session.update_aircraft({"gnss_ms": 5990}, 1.0)  # a new reading (10 ms of latency)
    sub = packet(session, 1.0).sub
    assert isinstance(sub, HostSubFrame) and sub.gnss_ms == 5990
    session.update_aircraft({"gnss_week": 0, "gnss_ms": 0}, 1.1)  # no time any more
    for now in (1.1, 1.2, 1.3):
        sub = packet(session, now).sub
        assert isinstance(sub, HostSubFrame) and (sub.gnss_week, sub.gnss_ms) == (0, 0)


def test_gnss_time_is_not_sent_past_the_last_week() -> None:
    session = opened(timeout=10.0)
    session.update_aircraft({"position": POS, "gnss_week": 32767,
                             "gnss_ms": MS_PER_WEEK - 10}, 0.0)  # fmt: skip
    assert packet(session, 0.0).sub.gnss_week == 32767  # type: ignore[union-attr]
    sub = packet(session, 0.021).sub
    assert isinstance(sub, HostSubFrame) and (sub.gnss_week, sub.gnss_ms) == (0, 0)


# -- 6. the property: any schedule of updates and times -----------------------------------
_VALUES: dict[str, list[Any]] = {
    "attitude": [None, ATT, (0.0, 0.0, 0.0), (-180.0, 90.0, 359.99)],
    "acceleration": [None, ACC, (0.0, 0.0, 0.0), (-327.68, 327.67, 0.0)],
    "velocity": [None, VEL, (0.0, 0.0, 0.0), (100.0, -100.0, 3.0)],
    "position": [None, POS, (-90.0, 180.0, -400.0)],
}
GNSS_T0 = WEEK * MS_PER_WEEK + 123_456
"""The true GNSS clock at session time 0 (ms)."""

updates = st.fixed_dictionaries(
    {},
    optional={
        **{name: st.sampled_from(values) for name, values in _VALUES.items()},
        "gnss": st.sampled_from(["reading", "repeat", "none"]),
    },
)
steps = st.lists(
    st.tuples(
        st.one_of(st.floats(0.021, 1.5), st.sampled_from([0.021, 0.1, 0.5, 1.0, 1.001])),
        st.none() | st.tuples(updates, st.booleans()),
    ),
    max_size=40,
)


@given(timeout=st.sampled_from([0.1, 0.5, 1.0]), lag=st.integers(0, 200), schedule=steps)
def test_property_wire_claims_only_current_data(
    timeout: float, lag: int, schedule: list[tuple[float, Any]]
) -> None:
    """INS valid on the wire iff attitude, acceleration and velocity are all given and each
    was given within the timeout; the sub frame iff the position is; GNSS time = the last new
    reading + the session time since (monotonic under a true clock read ``lag`` ms late);
    stale episodes counted once per run of packets that withhold a claim."""
    session = opened(timeout)
    state: dict[str, Any] = {}
    given_at: dict[str, float] = {}
    last_pair: tuple[int, int] | None = None
    anchor: tuple[int, float] | None = None
    now, previous_time, runs, was_stale = 0.0, -1, 0, False
    for dt, update in schedule:
        now += dt
        if update is not None:
            changes, whole = update
            changes = dict(changes)
            gnss = changes.pop("gnss", None)
            pair = None
            if gnss == "none":
                pair = (0, 0)
            elif gnss == "reading" or (gnss == "repeat" and last_pair is None):
                pair = divmod(GNSS_T0 + math.floor(now * 1000) - lag, MS_PER_WEEK)
            elif gnss == "repeat":
                pair = last_pair
            if pair is not None:
                changes["gnss_week"], changes["gnss_ms"] = pair
            state.update(changes)
            if whole:
                session.set_aircraft(AircraftState(**state), now)
                given_at.update(dict.fromkeys(_VALUES, now))
            else:
                session.update_aircraft(changes, now)
                given_at.update({k: now for k in changes if k in _VALUES})
            current = (state.get("gnss_week", 0), state.get("gnss_ms", 0))
            if current == (0, 0):
                anchor = None
            elif anchor is None or current != last_pair:
                anchor = (current[0] * MS_PER_WEEK + current[1], now)
            last_pair = current if current != (0, 0) else None
        p = packet(session, now)

        def fresh(part: str, now: float = now) -> bool:
            return state.get(part) is not None and now - given_at[part] <= timeout

        ins = all(fresh(part) for part in INS)
        assert p.main.ins_valid is ins
        if ins:
            expected = AircraftState(**{part: state[part] for part in INS}).main_frame()
            assert ins_raw(p) == tuple(getattr(expected, n) for n in INS_RAW)
        else:
            assert ins_raw(p) == (0,) * 9
        assert (p.sub is not None) is fresh("position")
        if p.sub is not None:
            if anchor is None:
                assert (p.sub.gnss_week, p.sub.gnss_ms) == (0, 0)
            else:
                sent = gnss_total(p.sub)
                assert sent == anchor[0] + math.floor((now - anchor[1]) * 1000)
                truth = GNSS_T0 + now * 1000 - lag
                assert truth - 2 <= sent <= truth + 1e-6
                assert sent >= previous_time
                previous_time = sent
        complete = all(state.get(part) is not None for part in INS)
        stale = (complete and not ins) or (state.get("position") is not None
                                           and not fresh("position"))  # fmt: skip
        runs += stale and not was_stale
        was_stale = stale
    assert session.stats.aircraft_stale == runs


# -- 7. the simulator's GCU sees it: INS off after the timeout, gaze refused, back on ------
def test_the_gcu_model_sees_ins_valid_go_off_and_come_back() -> None:
    rig = Rig(Session(aircraft_timeout=0.5))
    session, aircraft = rig.session, rig.model.state.aircraft
    state = AircraftState(**FULL, position=POS)
    rig.open()
    rig.at(0.2, lambda: session.set_aircraft(state, rig.now))
    rig.run_until(0.4)
    assert aircraft.ins_valid and aircraft.has_sub_frame
    assert aircraft.attitude == ATT and aircraft.velocity == VEL and aircraft.acceleration == ACC
    ok = rig.submit(GazeLock())
    rig.run_while(rig.pending, 2.0)
    assert ok is not None and ok.state is TicketState.SUCCEEDED
    assert rig.now < 0.7
    rig.run_until(1.0)
    assert not aircraft.ins_valid and not aircraft.has_sub_frame
    off = [t for t, p, _ in rig.sent if t > 0.2 and not p.main.ins_valid]
    assert 0.7 < off[0] <= 0.7 + 1 / 50 + 1e-9  # the first packet after the timeout
    assert all(p.main.ins_valid for t, p, _ in rig.sent if 0.2 < t < 0.69)
    refused = rig.submit(GazeLock())
    rig.run_while(rig.pending, 2.0)
    assert refused is not None and refused.state is TicketState.FAILED  # no INS: no gaze
    rig.at(rig.now, lambda: session.set_aircraft(state, rig.now))
    rig.run_until(rig.now + 0.1)
    assert aircraft.ins_valid and aircraft.has_sub_frame
    assert aircraft.ins_changes == 3  # invalid → valid → stale → valid
    assert session.stats.aircraft_stale == 1
    rig.check_counts()  # the two GazeLock() are equal: counted per opcode
