"""Property: the Lua dissector and ``gcu-async decode`` agree on any packets.

Hypothesis draws packets of every frame kind: valid packets from the protocol strategies
(every command, every sub frame kind, every feedback), and raw packets sealed with a valid
CRC whose bytes are arbitrary (any values, versions, opcodes: every command row's and any
other; parameters of the row's length with arbitrary bytes, so that the range checks of each
command are exercised; wrong lengths; long execution statuses). Each example goes through
UDP, TCP and serial with junk, CRC failures and cuts; tshark and decode must agree on every
field.
"""

from __future__ import annotations

import struct

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.cli.decode import decode_capture
from gcu_async.protocol import GCU_HEADER, HOST_HEADER
from gcu_async.wireshark.tables import rows
from helpers.protocol.strategies import U8, gcu_packets, host_packets, seal
from helpers.wireshark.tshark import dissect, needs_tshark, scratch_dir
from helpers.wireshark.xfgcu_compare import compare_capture
from helpers.wireshark.xfgcu_corpus import write_capture

pytestmark = needs_tshark
PARAMS_SIZE = {r.opcode: struct.calcsize("<" + "".join(p.fmt for p in r.params)) for r in rows()}
"""Each command row's parameter bytes."""


@st.composite
def raw_packets(draw: st.DrawFn) -> bytes:
    header = draw(st.sampled_from([HOST_HEADER, GCU_HEADER]))
    version = draw(st.sampled_from([1, 2, 1, 2, 0, 3, 255]))
    body = bytearray(draw(st.binary(min_size=64, max_size=64)))
    sub = draw(st.sampled_from(["standard", "none", "any"]))
    if sub == "standard":
        body[32] = 0x01
    elif sub == "none":
        body[32:64] = bytes(32)
    if header == HOST_HEADER:
        opcode = draw(st.one_of(st.sampled_from(sorted(PARAMS_SIZE)), U8))
        known = PARAMS_SIZE.get(opcode)
        right = known if known is not None else draw(st.integers(0, 20))
        size = right if draw(st.integers(0, 4)) else draw(st.integers(0, 20))
        params = draw(st.binary(min_size=size, max_size=size))
    else:
        opcode = draw(U8)
        params = draw(st.sampled_from([b"", b"", b"\x00", b"\x01", b"\x02", b"\x03\x04"]))
        if len(params) == 1 and draw(st.booleans()):
            params = bytes([draw(U8)])
    return seal(header, bytes(body) + bytes([opcode]) + params, version)


packets = st.one_of(host_packets.map(lambda p: p.encode()), gcu_packets.map(lambda p: p.encode()),
                    raw_packets())  # fmt: skip


@needs_tshark
@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])  # fmt: skip
@given(batch=st.lists(packets, min_size=20, max_size=60), seed=st.integers(0, 2**32 - 1))
def test_both_decoders_agree_on_any_packets(batch: list[bytes], seed: int) -> None:
    path = scratch_dir() / "property.pcapng"
    try:
        write_capture(path, batch, seed=seed, junk_rate=0.25)
        compared, _ = compare_capture(decode_capture(path.read_bytes()), dissect(path))
        assert compared >= 3 * len(batch)
    finally:
        path.unlink(missing_ok=True)
        path.parent.rmdir()
