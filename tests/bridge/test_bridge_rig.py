"""The bridge rigs' pymavlink peers (tests/helpers/bridge/rig.py) each own their port."""

from __future__ import annotations

import errno
import socket

import pytest

from helpers.bridge.rig import AUTOPILOT, GCS, Peer


def test_a_peer_port_is_taken_by_no_other_socket() -> None:
    """pymavlink's udpin sets SO_REUSEADDR; with it on both, Linux would hand a peer's
    ephemeral port to another socket (measured: 14 of 300,000 pairs of peers), which then
    takes the peer's datagrams and the rig waits for nothing."""
    peers = [Peer(*GCS), Peer(*AUTOPILOT)]
    try:
        assert peers[0].port != peers[1].port
        for peer in peers:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as other:
                other.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                with pytest.raises(OSError, match=rf"\[Errno {errno.EADDRINUSE}\]"):
                    other.bind(("127.0.0.1", peer.port))
    finally:
        for peer in peers:
            peer.close()
