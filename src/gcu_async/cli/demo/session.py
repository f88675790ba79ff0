"""The demo's session: start the simulator (or not), connect, feed the aircraft, run the
script under the live view, print the summary; the exit status."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import sys
import time
from typing import Any

from gcu_async.cli._exit import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    Interrupted,
    interruptible,
)
from gcu_async.cli.demo.engine import Tally
from gcu_async.cli.demo.flight import FlightPath, fly
from gcu_async.cli.demo.options import CONNECT_TIMEOUT, PROG, DemoOptions, parse_options
from gcu_async.cli.demo.report import Report, summary_lines
from gcu_async.cli.demo.script import Demo
from gcu_async.cli.liveview import Console, LiveView
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.errors import GcuError, LinkLost
from gcu_async.protocol.pods import pod_name
from gcu_async.sim.simulator import GcuSimulator


async def _session(opts: DemoOptions, console: Console, report: Report) -> None:
    async with contextlib.AsyncExitStack() as stack:
        options: dict[str, Any] = {}
        if opts.url is None:
            report.sim = sim = GcuSimulator(pod=opts.pod)
            server = await stack.enter_async_context(sim.serve(opts.listen))
            report.url = server.url
            if report.url.startswith("udp:"):
                options["local_port"] = 0
            console.line(f"simulator: {sim.model.profile.name} on {report.url} (in this process)")
        else:
            report.url = opts.url
        console.line(f"connecting to {report.url} ...")
        t0 = time.monotonic()
        gcu = connect(report.url, connect_timeout=CONNECT_TIMEOUT, capture=opts.capture,
                      **options)  # fmt: skip
        report.gcu = await stack.enter_async_context(gcu)
        path = FlightPath()
        started = time.monotonic()
        gcu.update_aircraft(**path.state_at(0.0))
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(_first_info(gcu), CONNECT_TIMEOUT)
        model, info = gcu.pod_model, gcu.info
        if model is None or info is None:
            pod = "pod unknown (no sub frame yet)"
        else:
            pod = (f"pod {pod_name(model)}, hardware {info.hardware_version:g}, "
                   f"firmware {info.firmware_version:g}")  # fmt: skip
        console.line(f"connected in {(time.monotonic() - t0) * 1000:.0f} ms: {pod}")
        console.line(f"aircraft: {path.speed:g} m/s, turning {path.turn_rate:g} deg/s, "
                     f"{path.height:g} m up (INS + GNSS sent in every packet)")  # fmt: skip
        demo = Demo(gcu, console, opts.speed, path, started)
        demo.pod = model
        report.demo = demo
        flight = asyncio.create_task(fly(gcu, path, started), name="demo-aircraft")
        try:
            async with LiveView(gcu, console):
                await demo.run()
        finally:
            flight.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await flight
            gcu.release_control()


async def _first_info(gcu: GcuClient) -> None:
    stream = gcu.telemetry()
    async with contextlib.aclosing(stream) as samples:
        async for sample in samples:
            if sample.info is not None:
                return


async def _main(opts: DemoOptions) -> int:
    console = Console(sys.stdout, opts.live)
    report = Report()
    interrupted = False
    try:
        await interruptible(_session(opts, console, report))
    except Interrupted:
        interrupted = True
    except BrokenPipeError:
        raise
    except (LinkLost, GcuError, OSError) as exc:
        report.error = str(exc) or type(exc).__name__
        console.finish()
        print(f"{PROG}: {report.error}", file=sys.stderr)
    console.finish()
    if interrupted:
        console.line("interrupted: session closed")
    for line in summary_lines(report, interrupted):
        console.line(line)
    if interrupted:
        return EXIT_INTERRUPTED
    tally = report.demo.tally if report.demo is not None else Tally()
    return EXIT_OK if report.error is None and tally.ok and report.demo else EXIT_FAILED


def run(args: argparse.Namespace) -> int:
    try:
        opts = parse_options(args, isatty=sys.stdout.isatty())
    except ValueError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return asyncio.run(_main(opts))
    except KeyboardInterrupt:  # platforms without loop signal handlers
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # e.g. `gcu-async demo | head`: stop quietly
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_FAILED
