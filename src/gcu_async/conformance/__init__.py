"""Conformance reports: how one side of a link deviates from V2.0.6, from what it sends.

:class:`GcuConformance` collects the replies a GCU sends (and, optionally, the opcodes of
the host packets they answer) and reports what it does outside V2.0.6
(:class:`GcuReport`): docs/conformance.md. The host's report is
:class:`gcu_async.protocol.conformance.HostConformance`.
"""

from gcu_async.conformance.gcu import MODE_SETTLE_S, STUCK_MOVE_DEG, GcuConformance, GcuReport
from gcu_async.conformance.runs import FEEDBACK_GRACE_S

__all__ = ["FEEDBACK_GRACE_S", "MODE_SETTLE_S", "STUCK_MOVE_DEG", "GcuConformance", "GcuReport"]
