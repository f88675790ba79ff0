"""Host check: the packet rate and the silences between packets.

V2.0.6 asks for 30–50 host packets a second and says a host must never stop sending (the
packets carry the aircraft state): a rate below :data:`MIN_RATE_HZ` over a run of two
seconds or more, and every silence longer than :data:`GAP_S`, are deviations.
"""

from __future__ import annotations

from gcu_async.conformance.findings import Deviation, Findings

MIN_RATE_HZ = 30.0
"""The document asks for 30–50 Hz; slower is a deviation (faster is not)."""
GAP_S = 0.5
"""A silence longer than this between two host packets is a gap (the host "must never stop
sending": the packets carry the aircraft state)."""


class RateCheck:
    """Gaps between packets, and the rate over the whole run."""

    def __init__(self, findings: Findings) -> None:
        self._f = findings
        self._last: float | None = None
        self._longest = 0.0

    def add(self, time: float, t: float, raw: bytes) -> None:
        """A packet at ``time`` (``t``: since the first)."""
        gap = 0.0 if self._last is None else time - self._last
        if gap > GAP_S:
            self._f.flag("rate.gaps", f"silences longer than {GAP_S:g} s between host packets",
                         t, raw, f"no packet for {gap:.3f} s before this one")  # fmt: skip
        self._longest = max(self._longest, gap)
        self._last = time

    def report(self, devs: dict[str, Deviation], total: int, duration: float,
               notes: list[str]) -> None:  # fmt: skip
        rate = (total - 1) / duration if duration > 0 else 0.0
        notes.append(f"{total} packets in {duration:.1f} s: {rate:.1f}/s, longest silence "
                     f"{self._longest * 1000:.0f} ms")  # fmt: skip
        if duration >= 2.0 and rate < MIN_RATE_HZ:
            devs["rate.low"] = Deviation(
                "rate.low", f"packet rate below {MIN_RATE_HZ:g} Hz", 1, 0, [],
                f"{rate:.1f} packets/s: V2.0.6 asks for 30–50 Hz; the gimbal depends on the "
                "aircraft state they carry")  # fmt: skip
        gaps = devs.get("rate.gaps")
        if gaps is not None:
            gaps.total = max(total - 1, 0)  # of the intervals between packets
            gaps.diagnosis = (f"longest {self._longest:.2f} s: the host must never stop "
                              "sending (V2.0.6: 30–50 Hz)")  # fmt: skip
