"""The GCU conformance report through the real entry point: ``gcu-async monitor --report``
against ``gcu-async sim`` (another process, a real socket) playing the Z-1Pro's firmware
names the signed camera yaw; against the document's firmware it names nothing
(docs/conformance.md)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from helpers.sim.process import CLI, SimProcess

TURNED = ("enter-angle-control", "0", "0", "-140")
"""The camera 140° left of the aircraft (facing north): a heading of 220°, west of north."""


def report_of(firmware: str, path: Path) -> tuple[str, str]:
    """The report ``monitor`` writes of a simulator playing ``firmware`` whose camera was
    turned (:data:`TURNED`), and the simulator's first line."""
    sim = SimProcess("--listen", "udp://127.0.0.1:0", "--pod", "Z-1Pro", "--firmware", firmware)
    try:
        sent = subprocess.run([*CLI, "send", f"{sim.url}?local_port=0", *TURNED],
                              capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
        assert sent.returncode == 0, sent.stderr
        assert json.loads(sent.stdout)["attitude_deg"]["yaw"] == pytest.approx(220.0, abs=0.5)
        done = subprocess.run([*CLI, "monitor", f"{sim.url}?local_port=0", "--json", "--count",
                               "5", "--interval", "0.1", "--report", str(path)],
                              capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
        assert done.returncode == 0, done.stderr
        for line in done.stdout.splitlines():  # monitor shows the heading, raw kept
            status = json.loads(line)["status"]
            assert status["attitude_deg"]["yaw"] == pytest.approx(220.0, abs=0.5)
            assert (status["attitude_raw"][2] >= 47536) is (firmware == "z1pro-6.7")
    finally:
        sim.stop()
    return path.read_text(encoding="utf-8"), sim.banner


@pytest.mark.subprocess
def test_monitor_report_names_the_z1pro_signed_yaw(tmp_path: Path) -> None:
    text, banner = report_of("z1pro-6.7", tmp_path / "gcu.txt")
    assert "Z-1Pro (firmware z1pro-6.7) listening on" in banner
    assert text.startswith("GCU conformance to V2.0.6: ")
    assert "pod: Z-1Pro (code 49), hardware 0.1, firmware 6.7, protocol version 2" in text
    assert "- main.yaw_raw.signed: camera yaw sent as a signed S16" in text
    assert "heading 220.00°" in text
    assert "fault bits seen 0x4000" in text


@pytest.mark.subprocess
def test_monitor_report_of_the_document_names_nothing(tmp_path: Path) -> None:
    text, banner = report_of("v2.0.6", tmp_path / "gcu.txt")
    assert "firmware" not in banner
    assert "\n  no deviation found\n" in text
    assert "\n- " not in text  # not one deviation block
