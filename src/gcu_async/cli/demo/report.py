"""The demo's closing summary: what the session left in its :class:`Report`."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, field

from gcu_async.cli.demo.engine import StepEngine, Tally
from gcu_async.client.client import GcuClient
from gcu_async.protocol.enums import opcode_name
from gcu_async.sim.simulator import GcuSimulator


@dataclass
class Report:
    """What the session leaves for the summary (filled while it runs)."""

    started: float = field(default_factory=time.monotonic)
    url: str = ""
    sim: GcuSimulator | None = None
    gcu: GcuClient | None = None
    demo: StepEngine | None = None
    error: str | None = None


def summary_lines(report: Report, interrupted: bool) -> list[str]:
    """The closing summary."""
    lines = ["", "summary"]
    demo = report.demo
    tally = demo.tally if demo is not None else Tally()
    if demo is None:
        lines.append("  steps:              none run (no session)")
    else:
        lines.append(
            f"  steps:              {tally.steps_ok} ok, {tally.steps_failed} failed, "
            f"{tally.steps_skipped} skipped, "
            f"{tally.steps_total - tally.steps_ok - tally.steps_failed - tally.steps_skipped} "
            f"not run (of {tally.steps_total})"
        )
    lines.append(f"  commands:           {tally.commands_run} run, "
                 f"{tally.commands_failed} failed")  # fmt: skip
    if tally.latencies:
        p50 = statistics.median(tally.latencies) * 1000
        lines.append(f"  latency:            p50 {p50:.1f} ms, max "
                     f"{max(tally.latencies) * 1000:.1f} ms")  # fmt: skip
    else:
        lines.append("  latency:            -")
    if report.gcu is not None:
        link = report.gcu.link
        lines.append(f"  packets:            {link.packets_sent} sent, "
                     f"{link.packets_received} received")  # fmt: skip
        lines.append(f"  crc errors:         {link.crc_errors}")
        lines.append(f"  unmatched feedback: {link.unmatched_feedback}")
        lines.append(f"  link lost:          {link.lost_count} times")
    if report.sim is not None:
        executions = report.sim.model.executions
        detail = ", ".join(f"{opcode_name(op).lower()} {n}" for op, n in sorted(executions.items()))
        lines.append(f"  sim executions:     {sum(executions.values())} ({detail or 'none'})")
    else:
        lines.append("  sim executions:     n/a (external GCU)")
    lines.append(f"  duration:           {time.monotonic() - report.started:.1f} s")
    if interrupted:
        result = "INTERRUPTED"
    elif report.error is not None:
        result = f"FAILED ({report.error})"
    elif not tally.ok:
        result = "FAILED" + (f" ({tally.aborted})" if tally.aborted else "")
    else:
        result = "OK"
    lines.append(f"result: {result}")
    return lines
