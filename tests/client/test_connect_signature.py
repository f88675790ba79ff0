"""``connect()`` takes exactly ``GcuClient``'s keyword arguments (derived, not copied), and
hands each one to the client; the rest go to the transport."""

from __future__ import annotations

import inspect
from typing import Any

import pytest

from gcu_async import GcuClient, connect
from gcu_async.client.connect import CLIENT_OPTIONS

KW = inspect.Parameter.KEYWORD_ONLY


def _keywords(obj: Any) -> list[inspect.Parameter]:
    return [p for p in inspect.signature(obj).parameters.values() if p.kind is KW]


def test_connect_has_the_clients_keyword_arguments() -> None:
    ours, theirs = _keywords(connect), _keywords(GcuClient)
    assert ours == theirs  # names, order, defaults and annotations
    assert len(theirs) >= 10
    assert {p.name for p in theirs} == CLIENT_OPTIONS
    params = list(inspect.signature(connect).parameters.values())
    assert params[0].name == "url"
    assert params[-1].kind is inspect.Parameter.VAR_KEYWORD  # the transport's options


def test_every_client_keyword_goes_to_the_client() -> None:
    values: dict[str, Any] = {
        "rate_hz": 40.0, "command_timeout": 1.5, "queue_timeout": 9.0, "connect_timeout": 0.5,
        "open_timeout": 4.0, "wait": False, "restore": True, "silence_timeout": 0.75,
        "check_support": True,
        "reorder_guard": 0.02, "aircraft_timeout": 2.0, "version": 1, "max_zoom": 30.0,
        "conformance": True,
    }  # fmt: skip
    gcu = connect("udp://127.0.0.1:4000", local_port=0, **values)
    for name, value in values.items():
        holder = gcu if hasattr(gcu, name) else gcu.session.config  # some: the session's
        assert getattr(holder, name) == value, name
    assert set(values) == CLIENT_OPTIONS - {"clock", "capture"}  # every option but two here
    ticks = iter(range(10**6))
    gcu = connect("udp://127.0.0.1:4000", local_port=0, clock=lambda: float(next(ticks)))
    assert gcu._clock() < gcu._clock()  # the clock given is the client's


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [("rate_hz", 500.0, "rate_hz"), ("version", 3, "version"),
     ("connect_timeout", -1.0, "connect_timeout"), ("check_support", "yes", "check_support")],
)  # fmt: skip
def test_a_bad_client_keyword_is_the_clients_error(option: str, value: Any, message: str) -> None:
    from gcu_async.transport import MemoryTransport

    with pytest.raises((TypeError, ValueError)) as direct:
        GcuClient(MemoryTransport(), **{option: value})
    with pytest.raises(type(direct.value)) as via_connect:
        connect("udp://127.0.0.1:4000", **{option: value})
    assert message in str(via_connect.value)
    assert str(via_connect.value) == str(direct.value)


def test_other_keywords_go_to_the_transport() -> None:
    with pytest.raises(ValueError, match="'rate' is not a udp option"):
        connect("udp://127.0.0.1:4000", rate=40.0)


def test_connect_passes_reorder_guard_and_its_default_follows_the_transport() -> None:
    client = connect("udp://127.0.0.1:2337", reorder_guard=0.05, local_port=0)
    assert client.reorder_guard == 0.05
    assert connect("udp://127.0.0.1:2337").reorder_guard == 0.015
    assert connect("tcp://127.0.0.1:2332").reorder_guard == 0.0
