"""The heartbeat on a busy event loop over real UDP (docs/session-contract.md, "Guarantees",
G4 and G6): the client in this process, its loop kept busy by four tasks that each spin
5 ms per step (about 20 ms iterations, the issue's load); the simulator in a process of its
own, counting the host packets it receives on the shared monotonic clock.

The old pacer sent 22-26 packets/s here. What a loaded machine cannot blur: the chunks are
measured on the loop's own clock, and every iteration of the loop is counted, so the floor
of G6 (a packet per iteration that lasts a period or more) is checked against the
iterations the loop actually ran. The 45 packets/s the issue asks for needs a loop that
turns ~50 times a second: when the machine did not give it that CPU the test says so and
skips that one figure (never a widened bound).
"""

from __future__ import annotations

import asyncio
import itertools
import json
import selectors
import signal
import subprocess
import sys
import time
from typing import Any

import pytest

from gcu_async import connect

SIMULATOR = r"""
import asyncio, json, signal, sys, time
from gcu_async.sim import GcuSimulator

async def main() -> None:
    sim = GcuSimulator()
    received: list[float] = []
    handle = sim.model.handle

    def record(packet):
        received.append(time.monotonic())
        return handle(packet)

    sim.model.handle = record
    stop = asyncio.Event()
    asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, stop.set)
    async with sim.serve_udp("127.0.0.1", 0) as server:
        print(server.url, flush=True)
        await asyncio.wait_for(stop.wait(), 120)
    print(json.dumps(received), flush=True)

asyncio.run(main())
"""

CHUNK = 0.005
TASKS = 4
WARM_UP = 1.0
MEASURE = 5.0
RATE_HZ = 50.0
FLOOR = 45.0
"""Packets per second the receiver must count (the issue's figure)."""
LOOP_NEEDED = 47.0
"""Iterations per second below which the machine did not give the loop its CPU: four 5 ms
chunks make ~49.9 iterations/s."""


class Receiver:
    """The simulator process; :meth:`stop` returns the times it received host packets."""

    def __init__(self) -> None:
        self.proc = subprocess.Popen([sys.executable, "-c", SIMULATOR], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)  # fmt: skip
        assert self.proc.stdout is not None
        with selectors.DefaultSelector() as sel:
            sel.register(self.proc.stdout, selectors.EVENT_READ)
            if not sel.select(15.0):
                self.proc.kill()
                raise TimeoutError("the simulator printed nothing")
        self.url = self.proc.stdout.readline().strip()

    def stop(self) -> list[float]:
        self.proc.send_signal(signal.SIGTERM)
        out, err = self.proc.communicate(timeout=15)
        assert self.proc.returncode == 0, err
        received: list[float] = json.loads(out)
        return received


def most_in_window(times: list[float], window: float = 1.0) -> int:
    best, j = 0, 0
    for i, t in enumerate(times):
        while times[j] + window <= t:
            j += 1
        best = max(best, i - j + 1)
    return best


async def busy_run() -> dict[str, Any]:
    """One run: (sent, received, iterations) counted within the measured span, and more."""
    receiver = Receiver()
    try:
        sends: list[float] = []
        ticks: list[float] = []
        async with connect(receiver.url, local_port=0, rate_hz=RATE_HZ) as gcu:
            loop = asyncio.get_running_loop()
            send = gcu.transport.send

            def tap(data: bytes) -> None:
                sends.append(time.monotonic())
                send(data)

            gcu.transport.send = tap  # type: ignore[method-assign]
            stop = asyncio.Event()

            async def chunks() -> None:
                while not stop.is_set():
                    end = loop.time() + CHUNK
                    while loop.time() < end:
                        pass
                    await asyncio.sleep(0)

            async def ticker() -> None:  # one step per loop iteration
                while not stop.is_set():
                    ticks.append(loop.time())
                    await asyncio.sleep(0)

            tasks = [asyncio.create_task(chunks()) for _ in range(TASKS)]
            tasks.append(asyncio.create_task(ticker()))
            await asyncio.sleep(WARM_UP)
            a = time.monotonic()
            await asyncio.sleep(MEASURE)
            b = time.monotonic()
            stop.set()
            await asyncio.gather(*tasks)
    finally:
        received = receiver.stop()
    span = b - a
    iterations = sum(1 for t in ticks if a <= t < b)
    lengths = [v - u for u, v in itertools.pairwise(ticks) if a <= u < b]
    return {
        "sent": sum(1 for t in sends if a <= t < b),
        "received": sum(1 for t in received if a <= t < b),
        "iterations": iterations,
        "span": span,
        "shortest": min(lengths),
        "most_in_window": most_in_window(sends),
    }


async def test_a_busy_loop_keeps_the_heartbeat_over_real_udp() -> None:
    runs = []
    for _ in range(3):  # a loaded machine may starve a run's loop: up to three tries
        r = await busy_run()
        runs.append(r)
        print(f"\nbusy loop: {r['sent'] / r['span']:.1f} packets/s sent, "
              f"{r['received'] / r['span']:.1f}/s received, "
              f"{r['iterations'] / r['span']:.1f} iterations/s "
              f"(shortest {r['shortest'] * 1000:.2f} ms), "
              f"most in a second {r['most_in_window']}")  # fmt: skip
        # G4 at the client's send times; G6: a packet every iteration (each lasts >= 20 ms,
        # a period), on whatever CPU the loop got; the receiver saw them all (loopback)
        assert r["most_in_window"] <= 51, r
        assert r["shortest"] >= 1 / RATE_HZ, r  # the chunks did take 20 ms per iteration
        assert r["sent"] >= r["iterations"] - 2, r
        assert r["received"] >= r["sent"] - 2, r
        if r["iterations"] / r["span"] >= LOOP_NEEDED:
            assert r["received"] / r["span"] >= FLOOR, r
            return
    rates = ", ".join(f"{r['iterations'] / r['span']:.1f}" for r in runs)
    pytest.skip(f"the machine did not give the event loop its CPU: {rates} iterations/s "
                f"(4 x 5 ms chunks make ~49.9); {FLOOR:g} packets/s could not be shown, "
                f"the floor was held against the iterations the loop ran")  # fmt: skip
