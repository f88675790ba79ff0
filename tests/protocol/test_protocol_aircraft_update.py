"""``aircraft_update``: the sans-I/O check of an aircraft update, against the client's.

:func:`gcu_async.protocol.aircraft.aircraft_update` is what ``GcuClient.update_aircraft``
delegates to (its ranges come from the host frame schema). The oracle is the client itself:
for the same arguments, the client and ``session.update_aircraft(aircraft_update(...))``
must raise the same exception (type and message) or reach the same state.
"""

from __future__ import annotations

import math
from datetime import datetime, timedelta, timezone
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async import GcuClient
from gcu_async.protocol.aircraft import AIRCRAFT_UPDATE_FIELDS, aircraft_update
from gcu_async.transport.memory import MemoryTransport
from helpers.scale import scaled

REALS: list[Any] = [
    -1e30, -2147483.649, -2147483.648, -360.0, -327.69, -327.68, -327.675, -180.0000001,
    -180.0, -179.995, -90.00001, -90.0, -1, -0.0, 0, 0.004, 1, 89.99999, 90.0, 90.00001,
    179.99999, 179.995, 180.0, 180.0001, 327.67, 327.675, 327.68, 359.999, 359.995, 360.0,
    2147483.647, 2147483.648, 10**40, math.nan, math.inf, -math.inf, True, "1", None, b"x",
]  # fmt: skip
"""Values around every aircraft range (the oracle, not this list, says which are valid)."""
INTS: list[Any] = [-1, 0, 1, 255, 256, 32767, 32768, 604_799_999, 604_800_000, 2**40, True,
                   1.0, "3", None]  # fmt: skip
UTC = timezone.utc
TIMES: list[Any] = [datetime(2024, 5, 1, 12, tzinfo=UTC), datetime(2024, 5, 1, 12),
                    datetime(2608, 1, 1, tzinfo=UTC), datetime(2610, 1, 1, tzinfo=UTC),
                    datetime(9999, 1, 1, tzinfo=timezone(timedelta(hours=3))),
                    "2024", 5]  # fmt: skip


def _triple() -> st.SearchStrategy[Any]:
    element = st.sampled_from(REALS)
    return st.one_of(
        st.tuples(element, element, element),
        st.lists(element, min_size=2, max_size=4),
        st.sampled_from([None, (0.0, 0.0), "abc", 3.0, {"a": 1}]),
    )


def _arguments() -> st.SearchStrategy[dict[str, Any]]:
    values = {
        "attitude": _triple(), "acceleration": _triple(), "velocity": _triple(),
        "position": _triple(), "relative_altitude": st.sampled_from(REALS),
        "satellites": st.sampled_from(INTS), "gnss_week": st.sampled_from(INTS),
        "gnss_ms": st.sampled_from(INTS), "gnss_time": st.sampled_from([None, *TIMES]),
    }  # fmt: skip
    assert set(values) == set(AIRCRAFT_UPDATE_FIELDS)
    return st.fixed_dictionaries({}, optional=values)


def _client() -> GcuClient:
    return GcuClient(MemoryTransport.pair(("a", "b"))[0])


def _outcome(call: Any) -> tuple[str, Any]:
    try:
        return ("ok", call())
    except (TypeError, ValueError) as exc:
        return (type(exc).__name__, str(exc))


def _same(kwargs: dict[str, Any]) -> None:
    client, mine = _client(), _client()
    expected = _outcome(lambda: client.update_aircraft(**kwargs))
    got = _outcome(lambda: mine.session.update_aircraft(aircraft_update(kwargs), 0.0))
    assert got == expected, kwargs


@settings(max_examples=scaled(3000, 300), deadline=None)
@given(_arguments())
def test_aircraft_update_raises_and_changes_what_the_client_does(kwargs: dict[str, Any]) -> None:
    _same(kwargs)


@pytest.mark.parametrize("name", AIRCRAFT_UPDATE_FIELDS)
def test_each_value_alone_at_every_probe(name: str) -> None:
    """Every probe value, alone, in every position of the field (a deterministic sweep)."""
    pool = TIMES if name == "gnss_time" else (
        INTS if name in ("satellites", "gnss_week", "gnss_ms") else REALS)  # fmt: skip
    for value in pool:
        if name in ("attitude", "acceleration", "velocity", "position"):
            for i in range(3):
                triple = [0.0, 0.0, 0.0]
                triple[i] = value
                _same({name: tuple(triple)})
                _same({name: triple})
        else:
            _same({name: value})


def test_gnss_time_with_week_is_the_client_error() -> None:
    when = datetime(2024, 5, 1, 12, tzinfo=UTC)
    _same({"gnss_time": when, "gnss_week": 2300})
    _same({"gnss_time": when, "gnss_ms": 1})
    with pytest.raises(ValueError, match="not both"):
        aircraft_update({"gnss_time": when, "gnss_ms": 1})


def test_unknown_value_is_a_type_error() -> None:
    with pytest.raises(TypeError, match="speed"):
        aircraft_update({"speed": 3.0})
