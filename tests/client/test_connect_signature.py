"""``connect()`` takes exactly ``GcuClient``'s keyword arguments (derived, not copied), and
hands each one to the client; the rest go to the transport."""

from __future__ import annotations

import inspect
from typing import Any, get_type_hints

import pytest

from gcu_async import GcuClient, connect
from gcu_async.client.connect import CLIENT_OPTIONS, ClientOptions, ConnectOptions
from gcu_async.transport.options import TransportOptions
from gcu_async.transport.registry import KINDS

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
    gcu = connect("udp://127.0.0.1:4000", local_port=0, discovery=True, max_attempts=3)
    assert gcu.transport.discovery and gcu.transport.backoff.max_attempts == 3
    with pytest.raises(ValueError, match="'baudrate' is not an option of the client or of a udp"):
        connect("udp://127.0.0.1:4000", baudrate=115200)  # type: ignore[call-arg]  # serial's


def test_an_unknown_option_names_both_kinds_and_the_closest() -> None:
    """A misspelt option: the error lists the client's (and its session's) options and the
    URL's transport's together, and suggests the closest name (it used to list only the
    transport's, hiding ``command_timeout``, and suggest nothing)."""
    with pytest.raises(ValueError, match="comand_timeout") as caught:
        connect("udp://127.0.0.1:4000", comand_timeout=3.0)  # type: ignore[call-arg]
    message = str(caught.value)
    assert message.startswith("option: 'comand_timeout' is not an option of the client or of "
                              "a udp transport; did you mean 'command_timeout'? (client and "
                              "session: aircraft_timeout, capture, check_support, clock, "
                              "command_timeout, ")  # fmt: skip
    client, transport = message.split("(client and session: ")[1].split("; udp transport: ")
    assert set(client.split(", ")) == CLIENT_OPTIONS
    assert set(transport.rstrip(")").split(", ")) == set(KINDS["udp"].options)
    with pytest.raises(ValueError, match=r"did you mean 'baudrate'\?"):
        connect("serial:///dev/ttyUSB0", baudrat=115200)  # type: ignore[call-arg]
    with pytest.raises(ValueError, match=r"; \(client and session: "):  # nothing close
        connect("tcp://127.0.0.1", xyzzy=1)  # type: ignore[call-arg]
    with pytest.raises(ValueError, match=r"^udp://127.0.0.1:99999: port: "):  # the URL first
        connect("udp://127.0.0.1:99999", comand_timeout=3.0)  # type: ignore[call-arg]


def test_the_typed_options_are_the_client_keywords_and_the_transport_options() -> None:
    """``ConnectOptions`` (what type checkers see) holds ``GcuClient``'s keyword arguments
    with their annotations, and every transport's options."""
    client = get_type_hints(ClientOptions)
    assert list(client) == [p.name for p in _keywords(GcuClient)]
    hints = get_type_hints(GcuClient.__init__)
    assert client == {name: hints[name] for name in client}
    transport = set(get_type_hints(TransportOptions))
    assert transport == {n for k in KINDS.values() for n in k.options} - CLIENT_OPTIONS
    assert set(get_type_hints(ConnectOptions)) == set(client) | transport


def test_connect_passes_reorder_guard_and_its_default_follows_the_transport() -> None:
    client = connect("udp://127.0.0.1:2337", reorder_guard=0.05, local_port=0)
    assert client.reorder_guard == 0.05
    assert connect("udp://127.0.0.1:2337").reorder_guard == 0.015
    assert connect("tcp://127.0.0.1:2332").reorder_guard == 0.0
