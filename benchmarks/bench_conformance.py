"""GCU conformance report benchmark: the cost per reply of feeding ``GcuConformance``, next to
the cost of decoding the reply (what a client already pays for every reply).

Run from the repository root::

    .venv/bin/python benchmarks/bench_conformance.py          # default: about 15 s
    .venv/bin/python benchmarks/bench_conformance.py --seconds 0.05 --repeats 2

Three reply streams of 10,000 replies each, every reply preceded by the opcode of the host
packet it answers (``host_sent``) as a client's driver would feed them: the simulator playing
the document (conforming: the common case), the simulator playing the Z-1Pro's firmware 6.7
with the camera swinging past north (about half the replies carry the signed yaw), and every
reply anomalous in several fields (the worst case). The report is fed the decoded parts
(``add_reply``, the cheap path) and, for comparison, the bytes (``add``, which decodes).
One core, process CPU time, rounds interleaving the workloads; best and median of the samples
(see bench_codec.py for the method).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from _machine import machine_lines
from bench_codec import sample_rates

from gcu_async.conformance import GcuConformance
from gcu_async.protocol import (
    AngleControl,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    NullCommand,
    decode_gcu_packet,
)
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.sim import ManualClock, SimulatorModel

HZ = 50.0
"""The client's default heartbeat: a reply every 20 ms."""
Stream = list[tuple[int, bytes, GcuPacket]]
"""(the host packet's opcode, the reply's bytes, the decoded reply)."""


def simulated(firmware: str, n: int) -> Stream:
    """``n`` replies of the simulator playing ``firmware``: the camera swings ±170° in angle
    control, an angle command every second, null packets between."""
    clock = ManualClock()
    model = SimulatorModel("Z-1Pro", firmware=firmware, clock=clock)
    out: Stream = []
    for i in range(n):
        yaw = 170.0 if (i // 100) % 2 else -170.0
        command = AngleControl() if i % 50 == 1 else NullCommand()
        main = HostMainFrame.build(control=ControlValues.angles(0.0, -10.0, yaw),
                                   subframe_request=1)  # fmt: skip
        [raw] = model.receive(HostPacket(main, None, command).encode())
        out.append((int(command.OPCODE), raw, decode_gcu_packet(raw)))
        clock.advance(1 / HZ)
    return out


def anomalous(n: int) -> Stream:
    """``n`` replies with a signed yaw, a miss distance out of range, an unknown mode and pod
    code and an undefined status each: every check's slow path."""
    out: Stream = []
    for i in range(n):
        main = GcuMainFrame(mode_raw=0x42, miss_x=1001 + i % 1000, yaw_raw=47536 + i % 18000,
                            relative_z_raw=i % 18000)  # fmt: skip
        packet = GcuPacket(main, GcuSubFrame(pod_code=200), Feedback(0x20, 0x07))
        raw = packet.encode(deviations={"miss_x", "yaw_raw", "mode_raw"})
        out.append((0x20, raw, decode_gcu_packet(raw)))
    return out


def parts_pass(stream: Stream) -> int:
    c = GcuConformance()
    t = 0.0
    for opcode, _, packet in stream:
        c.host_sent(opcode, t)
        c.add_reply(packet.main, packet.sub, packet.feedback, t, version=packet.version)
        t += 0.02
    c.report()
    return len(stream)


def bytes_pass(stream: Stream) -> int:
    c = GcuConformance()
    t = 0.0
    for opcode, raw, _ in stream:
        c.host_sent(opcode, t)
        c.add(raw, t)
        t += 0.02
    c.report()
    return len(stream)


def decode_pass(stream: Stream) -> int:
    for _, raw, _ in stream:
        decode_gcu_packet(raw)
    return len(stream)


def check(stream: Stream, keys: set[str]) -> None:
    """Feed once and check the report finds what the stream has (so the timed loop does the
    real work)."""
    c = GcuConformance()
    for i, (opcode, raw, _) in enumerate(stream):
        c.host_sent(opcode, i / HZ)
        c.add(raw, i / HZ)
    found = set(c.report().keys)
    if not keys <= found or (not keys and found):
        raise SystemExit(f"check failed: the report found {sorted(found)}, expected {keys}")


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--replies", type=int, default=10_000, help="replies per stream [10000]")
    ap.add_argument("--seconds", type=float, default=0.4,
                    help="minimum duration of one sample [0.4]")
    ap.add_argument("--repeats", type=int, default=5, help="samples per measurement [5]")
    args = ap.parse_args(argv)  # fmt: skip
    if args.replies < 400 or args.seconds <= 0 or args.repeats < 1:
        ap.error("need --replies >= 400, --seconds > 0, --repeats >= 1")
    print("gcu_async GCU conformance report benchmark")
    for line in machine_lines():
        print(f"  {line}")
    streams = {
        "document": simulated("v2.0.6", args.replies),
        "z1pro-6.7": simulated("z1pro-6.7", args.replies),
        "every check flagged": anomalous(args.replies),
    }
    check(streams["document"], set())
    check(streams["z1pro-6.7"], {"main.yaw_raw.signed"})
    check(streams["every check flagged"], {"main.yaw_raw.signed", "main.miss_x",
                                           "main.mode_raw", "sub.pod_code"})  # fmt: skip
    signed = sum(p.main.yaw_raw >= 47536 for _, _, p in streams["z1pro-6.7"])
    print(f"  streams  : {args.replies} replies each; z1pro-6.7: {signed} with a signed yaw")
    workloads: dict[str, Callable[[], int]] = {}
    for name, stream in streams.items():
        workloads[f"{name}: decode"] = lambda s=stream: decode_pass(s)  # type: ignore[misc]
        workloads[f"{name}: report, parts"] = lambda s=stream: parts_pass(s)  # type: ignore[misc]
        workloads[f"{name}: report, bytes"] = lambda s=stream: bytes_pass(s)  # type: ignore[misc]
    rates: dict[str, list[float]] = {name: [] for name in workloads}
    for _ in range(args.repeats):
        for name, one_pass in workloads.items():
            rates[name] += sample_rates(one_pass, args.seconds, 1)
    print("\nmicroseconds per reply (best / median of the samples); ratio to decoding the "
          "reply; share of one core at 50 replies/s")  # fmt: skip
    for name in streams:
        decode_us = 1e6 / max(rates[f"{name}: decode"])
        for what in ("decode", "report, parts", "report, bytes"):
            r = rates[f"{name}: {what}"]
            best, median = 1e6 / max(r), 1e6 / sorted(r)[len(r) // 2]
            print(f"  {name + ': ' + what:<36} {best:7.2f} / {median:7.2f} us"
                  f"   x{best / decode_us:4.2f}   {best * HZ / 1e4:.4f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
