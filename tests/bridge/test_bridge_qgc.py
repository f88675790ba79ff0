"""docs/qgroundcontrol.md, replayed: every request of its table goes to the bridge (over
loopback, to the simulator) as QGroundControl sends it, and the answer must be the one the
table gives; every message of its "listens to" table must arrive from the component named."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from gcu_async.bridge._mavlink import mavlink
from helpers.bridge.rig import bridge_rig

DOC = Path(__file__).resolve().parents[2] / "docs" / "qgroundcontrol.md"
ROW = re.compile(r"^\|(?P<what>[^|]+)\|\s*`(?P<sends>[^`]+)`\s*\|\s*(?P<to>\d+)\s*\|"
                 r"\s*`(?P<answer>[^`]+)`\s*\|$")  # fmt: skip
STREAM_ROW = re.compile(r"^\|\s*`(?P<msg>[A-Z_0-9]+)`\s*\|\s*(?P<from>[\d, ]+)\|")


def section(name: str) -> list[str]:
    text = DOC.read_text(encoding="utf-8")
    start = text.index(f"<!-- {name} -->")
    end = text.index(f"<!-- /{name} -->")
    return text[start:end].splitlines()


def value(token: str) -> float:
    """A parameter as written in the table: a number, NaN, a message name (its id), or
    flag/enum names joined with "+" (their sum)."""
    if token == "NaN":
        return math.nan
    try:
        return float(token)
    except ValueError:
        pass
    total = 0
    for name in token.split("+"):
        for prefix in ("MAVLINK_MSG_ID_", "GIMBAL_MANAGER_FLAGS_", ""):
            if hasattr(mavlink, prefix + name):
                total += getattr(mavlink, prefix + name)
                break
        else:
            raise AssertionError(f"unknown name in the table: {name}")
    return float(total)


REQUESTS = [m.groupdict() for line in section("qgc-requests") if (m := ROW.match(line))]
STREAMS = [m.groupdict() for line in section("qgc-streams") if (m := STREAM_ROW.match(line))]


def test_the_tables_were_read() -> None:
    assert len(REQUESTS) >= 30 and len(STREAMS) == 6
    rows = [line for line in section("qgc-requests") if line.startswith("| ")]
    assert len(rows) == len(REQUESTS) + 1  # every row but the header parsed


async def test_every_request_gets_the_documented_answer() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        for row in REQUESTS:
            name, *params = row["sends"].split()
            command = getattr(mavlink, f"MAV_CMD_{name}")
            component = int(row["to"])
            result, *then = row["answer"].split()
            gcs.messages.clear()
            gcs.command(component, command, *(value(p) for p in params))
            ack = await gcs.ack(component, command)
            assert ack.result == getattr(mavlink, f"MAV_RESULT_{result}"), row
            assert (ack.target_system, ack.target_component) == (255, 190)
            for message in then:
                await gcs.wait(message, lambda m, c=component: m.get_srcComponent() == c,
                               new=False)  # fmt: skip
        assert rig.state.camera.photos == {1: 1} and not rig.state.camera.recording


async def test_the_streams_qgroundcontrol_listens_to_arrive() -> None:
    async with bridge_rig() as rig:
        received = await rig.gcs.collect(1.2)
        for row in STREAMS:
            components = {int(c) for c in row["from"].replace(",", " ").split()}
            senders = {m.get_srcComponent() for m in received if m.get_type() == row["msg"]}
            assert components <= senders, row


@pytest.mark.parametrize("row", REQUESTS, ids=lambda r: r["what"].strip())
def test_each_request_names_a_real_command(row: dict[str, str]) -> None:
    name = row["sends"].split()[0]
    assert hasattr(mavlink, f"MAV_CMD_{name}")
