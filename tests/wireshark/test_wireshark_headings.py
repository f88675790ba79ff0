"""The dissector reads the camera yaw as ``gcu-async decode`` does: a heading in [0°, 360°)
whatever the pod sends (the Z-1Pro's signed S16 too), the raw value kept, the same anomaly
words (docs/protocol-notes.md, "What real pods do"; docs/wireshark.md)."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.cli.decode import decode_capture
from helpers.protocol import z1pro
from helpers.wireshark.tshark import dissect, needs_tshark, scratch_dir
from helpers.wireshark.xfgcu_compare import compare_capture
from helpers.wireshark.xfgcu_corpus import write_capture

pytestmark = needs_tshark
EDGES = (0, 1, 17999, 18000, 35999, 36000, 36001, 47535, 47536, 47537, 65534, 65535)


def heading(raw: int) -> float:
    """The rule by range, written out (independent of the library and the dissector)."""
    if raw >= 47536:
        raw -= 65536
    elif raw >= 36000:
        raw -= 36000
    return (raw % 36000) / 100


def agree(yaws: list[int], *, seed: int = 1) -> None:
    """Z-1Pro replies with these raw yaws over UDP, TCP and serial: the dissector shows what
    decode shows, and decode shows the heading."""
    packets = [z1pro.reply(i * 7 % 36000 - 18000, yaw) for i, yaw in enumerate(yaws)]
    path = scratch_dir() / "headings.pcapng"
    try:
        write_capture(path, packets, seed=seed, junk_rate=0.1)
        objs = decode_capture(path.read_bytes())
        for obj in objs:
            raw = obj["main"]["attitude_raw"][2]
            assert obj["main"]["attitude_deg"]["yaw"] == heading(raw)
            assert [a["field"] for a in obj.get("anomalies", ())] == (
                ["yaw_raw"] if raw >= 36000 else [])  # fmt: skip
        compared, _ = compare_capture(objs, dissect(path))
        assert compared >= 3 * len(packets)
    finally:
        path.unlink(missing_ok=True)
        path.parent.rmdir()


def test_the_logged_z1pro_yaws_and_every_band_edge() -> None:
    logged = [y for move in z1pro.MOVES for y in (move[1], move[3])]
    agree([*EDGES, *logged])


def test_a_sweep_of_every_257th_raw_yaw() -> None:
    agree(list(range(0, 65536, 257)), seed=2)


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(yaws=st.lists(st.integers(0, 65535), min_size=10, max_size=40),
       seed=st.integers(0, 2**32 - 1))  # fmt: skip
def test_any_raw_yaw(yaws: list[int], seed: int) -> None:
    agree(yaws, seed=seed)
