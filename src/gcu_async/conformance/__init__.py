"""Conformance reports: how one side of a link deviates from V2.0.6, from what it sends.

:class:`HostConformance` collects the packets a host sends (your autopilot, your code) and
reports what they do outside V2.0.6 (:class:`ConformanceReport`), one module per check
(:mod:`~gcu_async.conformance.host`). :class:`GcuConformance` collects the replies a GCU
sends (and, optionally, the opcodes of the host packets they answer) and reports what it
does outside V2.0.6 (:class:`GcuReport`). Both are sans-I/O and share their deviations and
text (:mod:`~gcu_async.conformance.findings`): docs/conformance.md.
"""

from gcu_async.conformance.findings import EXAMPLES, Deviation, Example
from gcu_async.conformance.gcu import MODE_SETTLE_S, STUCK_MOVE_DEG, GcuConformance, GcuReport
from gcu_async.conformance.host import ConformanceReport, HostConformance
from gcu_async.conformance.host_fields import field_diagnosis, frame_anomalies, yaw_reading
from gcu_async.conformance.host_rate import GAP_S, MIN_RATE_HZ
from gcu_async.conformance.host_runs import LONG_RUN_S
from gcu_async.conformance.runs import FEEDBACK_GRACE_S

__all__ = [
    "EXAMPLES", "FEEDBACK_GRACE_S", "GAP_S", "LONG_RUN_S", "MIN_RATE_HZ", "MODE_SETTLE_S",
    "STUCK_MOVE_DEG", "ConformanceReport", "Deviation", "Example", "GcuConformance",
    "GcuReport", "HostConformance", "field_diagnosis", "frame_anomalies", "yaw_reading",
]  # fmt: skip
