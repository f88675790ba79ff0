"""``gcu-async sim`` (the real CLI, its own process) fed 3.5 s of ArduPilot's recorded packets
over a real TCP socket, at their recorded pace: SIGQUIT writes the conformance report
(``--report``, ``--report-json``) while it runs, the exit prints it again, and the JSON names
ArduPilot's deviations, the simulator's counters and how often each command ran."""

from __future__ import annotations

import contextlib
import json
import signal
import socket
import time
from pathlib import Path

from helpers.sim.process import SimProcess
from helpers.sitl.ardupilot import load_conversation

DATA = Path(__file__).parent.parent / "data" / "ardupilot-4.7.0-sitl.gcuconv.gz"


def ardupilot_slice() -> list[tuple[float, bytes]]:
    """3.5 s of the recording around the first photo and the record start/stop."""
    rows = load_conversation(DATA)
    photo = next(t for t, host, _ in rows if host[69] == 0x20)
    return [(t - photo + 1.5, host) for t, host, _ in rows if photo - 1.5 <= t <= photo + 2.0]


def feed(port: int, packets: list[tuple[float, bytes]]) -> int:
    """Send at the recorded times; return the reply bytes received."""
    received = 0
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.setblocking(False)
        start = time.monotonic()
        for t, host in packets:
            time.sleep(max(0.0, start + t - time.monotonic()))
            s.sendall(host)
            with contextlib.suppress(BlockingIOError):
                received += len(s.recv(65536))
        s.setblocking(True)
        s.settimeout(0.5)
        try:
            while chunk := s.recv(65536):
                received += len(chunk)
        except TimeoutError:
            pass
    return received


def test_the_report_on_sigquit_and_at_exit(tmp_path: Path) -> None:
    text, data = tmp_path / "report.txt", tmp_path / "report.json"
    packets = ardupilot_slice()
    assert any(p[69] == 0x21 and p[70] == 0x00 for _, p in packets)  # the record stop
    sim = SimProcess("--listen", "tcp://127.0.0.1:0", "--report", str(text),
                     "--report-json", str(data))  # fmt: skip
    try:
        port = int(sim.url.rsplit(":", 1)[1])
        received = feed(port, packets)
        assert received >= 73 * len(packets)  # every packet answered (73+ bytes each)
        sim.proc.send_signal(signal.SIGQUIT)
        deadline = time.monotonic() + 10
        while not data.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert sim.proc.poll() is None  # SIGQUIT reports, it does not end the simulator
        during = json.loads(data.read_text(encoding="utf-8"))
        assert during["conformance"]["packets"] == len(packets)
    finally:
        log = sim.stop()
    assert sim.proc.returncode == 130  # ended by a signal (docs/cli.md, "Exit status")
    assert log.count("Host conformance to V2.0.6") == 2  # SIGQUIT, then exit
    assert text.read_text(encoding="utf-8").startswith("Host conformance to V2.0.6")
    document = json.loads(data.read_text(encoding="utf-8"))
    conformance, simulator = document["conformance"], document["simulator"]
    assert conformance["conforms"] is False
    keys = {d["key"] for d in conformance["deviations"]}
    assert {"main.aircraft_yaw_raw", "main.all_zero", "ins_valid.toggles",
            "opcode.standing.ANGLE_CONTROL", "command.RECORD.cameras"} <= keys  # fmt: skip
    record = next(d for d in conformance["deviations"] if d["key"] == "command.RECORD.cameras")
    assert " 21 00 " in record["examples"][0]["raw_hex"]  # opcode 0x21, parameter 0x00
    photos = sum(p[69] == 0x20 for _, p in packets)  # ArduPilot sends each command once
    assert photos >= 1
    assert simulator["executions"]["TAKE_PHOTO"] == photos
    assert simulator["executions"]["RECORD"] == 2  # start, and ArduPilot's stop (0x00)
    assert simulator["tolerated"] == 1 and simulator["anomalous"] == 1
    assert simulator["anomalies_by_field"]["aircraft_yaw_raw"] == simulator["frame_anomalies"]
    assert "with frame-field anomalies: aircraft_yaw_raw" in log  # the summary line
    assert log.count("host packet field out of range: aircraft_yaw_raw") == 1  # logged once
