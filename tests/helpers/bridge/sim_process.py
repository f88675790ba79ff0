"""The simulator in its own process, for measurements the bridge's process load must not
distort: ``python sim_process.py POD`` serves UDP on 127.0.0.1 (port 0), prints its URL,
then answers lines on stdin: ``report`` → one line, base64 of the pickled (host-packet
times, execution log) so far (``time.monotonic``, the same clock in every process on
Linux); ``silence SECONDS`` → stop answering and executing for that long; ``quit`` or end
of input → exit."""

from __future__ import annotations

import asyncio
import base64
import pickle
import sys
import time
from typing import Any

from gcu_async.sim import GcuSimulator, SimulatorModel


async def main(pod: str) -> None:
    model = SimulatorModel(pod, record_executions=True)
    sim = GcuSimulator(model)
    times: list[float] = []
    handle = model.handle

    def timed(packet: Any) -> Any:
        times.append(time.monotonic())
        return handle(packet)

    model.handle = timed  # type: ignore[method-assign]
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    async with sim.serve_udp("127.0.0.1", 0) as server:
        print(server.url, flush=True)
        while line := (await reader.readline()).decode().split():
            if line[0] == "report":
                data = pickle.dumps((list(times), list(model.execution_log)))
                sys.stdout.write(base64.b64encode(data).decode() + "\n")
                sys.stdout.flush()
            elif line[0] == "silence":
                sim.silence(float(line[1]))
            else:
                return


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1]))
