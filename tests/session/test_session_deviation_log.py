"""A GCU that sends values outside V2.0.6 is said once per kind, not once per packet: the
first reply with a signed camera yaw logs one warning, later ones (other values too) log
nothing; another kind (a status byte the command never answers) gets its own line."""

from __future__ import annotations

import logging

import pytest

from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame
from gcu_async.protocol.headings import SIGNED_DETAIL
from gcu_async.protocol.packets import GcuPacket
from gcu_async.session import Session


def reply(yaw_raw: int, status: int | None = None, opcode: int = 0) -> bytes:
    return GcuPacket(GcuMainFrame(yaw_raw=yaw_raw), None,
                     Feedback(opcode, status)).encode(deviations=("yaw_raw",))  # fmt: skip


@pytest.mark.parametrize("datagram", [True, False], ids=["datagram", "stream"])
def test_each_kind_of_deviation_is_logged_once(caplog: pytest.LogCaptureFixture,
                                               datagram: bool) -> None:  # fmt: skip
    session = Session(name="gcu")
    session.open(0.0)
    caplog.set_level(logging.WARNING, logger="gcu_async.session")
    now = 0.0
    for raw in [51552, 51552, 65170, 60584, 1000, 47664] * 20:
        now += 0.02
        session.receive(reply(raw), now, datagram=datagram)
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and SIGNED_DETAIL in lines[0], lines
    session.receive(reply(1000, status=7, opcode=0x20), now + 0.02, datagram=datagram)
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 2 and "TAKE_PHOTO" not in lines[0], lines
    assert session.status is not None and session.status.yaw_raw == 1000
