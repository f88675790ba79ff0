"""The accepted forms of a MAVLink connection string (docs/mavlink-bridge.md, "Links"): each
one parsed to what it means; every malformed one refused with one line naming the part."""

from __future__ import annotations

import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.bridge.bridge import make_link
from gcu_async.bridge.endpoint import BAUD_RANGE, DEFAULT_BAUD, Endpoint, parse_endpoint
from gcu_async.bridge.stream_link import SerialLink, TcpInLink, TcpLink
from gcu_async.bridge.udp_link import UdpInLink, UdpOutLink


@pytest.mark.parametrize(("text", "kind", "host", "port"), [
    ("udpout:127.0.0.1:14550", "udpout", "127.0.0.1", 14550),
    ("udpin:0.0.0.0:14550", "udpin", "0.0.0.0", 14550),
    ("udpin:127.0.0.1:0", "udpin", "127.0.0.1", 0),
    ("udpin:[::1]:14550", "udpin", "::1", 14550),
    ("tcp:localhost:5760", "tcp", "localhost", 5760),
    ("tcpin:[::]:5760", "tcpin", "::", 5760),
    ("tcp:192.168.1.20:65535", "tcp", "192.168.1.20", 65535),
])  # fmt: skip
def test_network_forms(text: str, kind: str, host: str, port: int) -> None:
    assert parse_endpoint(text) == Endpoint(text, kind, host=host, port=port)


@pytest.mark.parametrize(("text", "device", "baud"), [
    ("/dev/ttyACM0,115200", "/dev/ttyACM0", 115200),
    ("/dev/ttyUSB1", "/dev/ttyUSB1", DEFAULT_BAUD),
    ("/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0,57600",
     "/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0", 57600),
    ("COM3,921600", "COM3", 921600),
])  # fmt: skip
def test_serial_forms(text: str, device: str, baud: int) -> None:
    assert parse_endpoint(text) == Endpoint(text, "serial", device=device, baud=baud)


@pytest.mark.parametrize(("text", "part"), [
    ("udpin:127.0.0.1:99999", "port 99999 is outside the allowed range [0, 65535]"),
    ("udpout:127.0.0.1:0", "port 0 is outside the allowed range [1, 65535]"),
    ("udpin:::1:14550", "an IPv6 address goes in brackets, e.g. udpin:[::1]:14550"),
    ("tcp:127.0.0.1:x", "port 'x' is not a number"),
    ("tcp:127.0.0.1:", "port '' is not a number"),
    ("udpout:127.0.0.1", "no port"),
    ("tcp::5760", "no host"),
    ("udpin:[::1:14550", "expected [IPV6]:PORT"),
    ("udpin:[::g]:14550", "not a valid IPv6 address"),
    ("udpin:300.1.1.1:14550", "not a valid IPv4 address"),
    ("ftp:x:1", "unknown scheme 'ftp'"),
    ("udp:0.0.0.0:14550", "use udpin: to listen or udpout: to send to a listener"),
    ("localhost", "no scheme"),
    ("/dev/ttyACM0,", "baud '' is not a whole number"),
    ("/dev/ttyACM0,49", f"baud 49 is outside the allowed range [{BAUD_RANGE[0]}, "),
    ("/dev/", "no serial device path"),
    ("", "empty"),
])  # fmt: skip
def test_malformed_forms(text: str, part: str) -> None:
    with pytest.raises(ValueError, match=re.escape(f"connection {text!r}: ")) as info:
        parse_endpoint(text)
    message = str(info.value)
    assert message.startswith(f"connection {text!r}: ")
    assert part in message
    assert "\n" not in message


@given(st.text(max_size=40))
def test_anything_parses_or_is_one_value_error(text: str) -> None:
    outcome = _parse_or_error(text)
    if isinstance(outcome, str):
        assert outcome.startswith(f"connection {text!r}: ")
        assert "\n" not in outcome.removeprefix(f"connection {text!r}: ")
    else:
        assert outcome.kind in ("udpout", "udpin", "tcp", "tcpin", "serial")
        if outcome.kind != "serial":
            assert 0 <= outcome.port <= 65535


def _parse_or_error(text: str) -> Endpoint | str:
    try:
        return parse_endpoint(text)
    except ValueError as exc:
        return str(exc)


def test_each_kind_gets_its_link() -> None:
    kinds = {"udpout:127.0.0.1:1": UdpOutLink, "udpin:127.0.0.1:0": UdpInLink,
             "tcp:127.0.0.1:1": TcpLink, "tcpin:127.0.0.1:0": TcpInLink,
             "/dev/ttyS0": SerialLink}  # fmt: skip
    for text, cls in kinds.items():
        assert type(make_link(text)) is cls


def test_the_docs_state_the_link_constants() -> None:
    # docs/mavlink-bridge.md "Links" restates the module constants: they must agree
    from pathlib import Path

    from gcu_async.bridge import links, stream_link, udp_link

    text = (Path(__file__).parent.parent.parent / "docs" / "mavlink-bridge.md").read_text()
    section = text[text.index("\n## Links\n"):]
    stated = [
        f"**{udp_link.DESTINATION_EXPIRY_SECONDS:g} s**", f"**{udp_link.MAX_DESTINATIONS}**",
        f"**{udp_link.MAX_SENDERS}**", f"**{links.RETRY_SECONDS:g} s**",
        f"**{links.OPEN_TIMEOUT:g} s**", f"**{links.INBOX_BYTES // 1024} KiB**",
        f"**{links.DRAIN_SECONDS * 1000:g} ms**", f"**{links.SEND_BUFFER_BYTES // 1024} KiB**",
        f"up to {stream_link.MAX_TCP_CLIENTS} TCP clients",
        f"once per {links.LOG_INTERVAL:g} s",
        f"BAUD {BAUD_RANGE[0]}–{BAUD_RANGE[1]:,}", f"default {DEFAULT_BAUD}",
    ]  # fmt: skip
    assert [s for s in stated if s not in section] == []
