"""``gcu-async demo``: a scripted session against the built-in simulator (or a real GCU).

By default a :class:`~gcu_async.sim.GcuSimulator` listens on an ephemeral loopback UDP port
in this process and the client connects to it over real UDP. While a slowly turning
aircraft is fed to the GCU, the script switches modes, slews, pans, zooms, takes a photo,
records, ranges and tracks a box, checking each effect in the telemetry; a live view shows
mode, attitude, zoom, flags and link health; a summary closes the run.

Exit status: 0 every step passed, 1 a step failed or no connection, 2 bad options,
130 interrupted (Ctrl-C / SIGTERM: the session closes cleanly and the summary so far is
printed).

One module a job: :mod:`~gcu_async.cli.demo.options` (the command line),
:mod:`~gcu_async.cli.demo.flight` (the aircraft), :mod:`~gcu_async.cli.demo.engine` (running
steps and checking their effects), :mod:`~gcu_async.cli.demo.script` (the steps),
:mod:`~gcu_async.cli.demo.report` (the summary) and :mod:`~gcu_async.cli.demo.session`
(putting them together).
"""

from __future__ import annotations

from typing import Any

from gcu_async.cli.demo.engine import StepEngine, StepFailed, Tally
from gcu_async.cli.demo.flight import FlightPath, fly
from gcu_async.cli.demo.options import DemoOptions, add_parser, parse_options
from gcu_async.cli.demo.report import Report, summary_lines
from gcu_async.cli.demo.script import Demo
from gcu_async.cli.demo.session import run


def register(sub: Any) -> None:
    """Add the ``demo`` subcommand to the ``gcu-async`` parser."""
    add_parser(sub).set_defaults(run=run)


__all__ = [
    "Demo", "DemoOptions", "FlightPath", "Report", "StepEngine", "StepFailed", "Tally", "fly",
    "parse_options", "register", "run", "summary_lines",
]  # fmt: skip
