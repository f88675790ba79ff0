"""`gcu-async send` and `gcu-async monitor` through the real entry point, against a
`gcu-async sim` process on loopback."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest

from gcu_async import Mode
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.pods import supports
from gcu_async.sim import DEFAULT_POD
from helpers.protocol.catalogue_samples import required_samples

CLI = [sys.executable, "-m", "gcu_async.cli"]


def run(*args: str, timeout: float = 20.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, *args], capture_output=True, text=True, timeout=timeout, check=False
    )


@pytest.fixture(scope="module")
def sim_url() -> Iterator[str]:
    proc = subprocess.Popen(
        [*CLI, "sim", "--listen", "udp://127.0.0.1:0", "--pod", "D-90Pro(TA)"],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        match = re.search(r"listening on (udp://\S+)", line)
        assert match, f"unexpected sim output: {line!r}"
        yield match.group(1)
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            assert proc.wait(timeout=10) == 130  # a signal ended it
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            if proc.stdout is not None:
                proc.stdout.close()


def _derived_sends() -> list[tuple[list[str], int]]:
    """``send`` of every other command the simulated pod executes, with the catalogue's
    samples as its arguments (a new command is sent here without a row of its own)."""
    listed = {"take-photo", "zoom-to", "enter-euler-control", "enter-pointing-lock", "track",
              "set-night-vision", "set-ranging", "set-area-temperature"}  # fmt: skip
    cases = []
    for e in CATALOGUE:
        if (e.cli_name in listed or e.needs_ins or not supports(DEFAULT_POD, e.opcode)
                or e.method in ("start_recording", "stop_recording")):  # fmt: skip
            continue  # by the recording flag: tests/test_client_waiting.py
        args = []
        for value in required_samples(e).values():
            args += [str(v) for v in value] if isinstance(value, tuple) else [str(value)]
        cases.append(([e.cli_name, *args], int(e.opcode)))
    return cases


@pytest.mark.parametrize(
    ("command", "opcode"),
    [
        *_derived_sends(),
        (["take-photo"], 0x20),
        (["zoom-to", "12.5"], 0x25),
        (["enter-euler-control", "0", "-30", "45"], 0x14),
        (["enter-pointing-lock"], 0x11),
        (["enter-pointing-lock", "1.5", "-2"], 0x11),
        (["track", "0.4", "0.4", "0.6", "0.6"], 0x17),
        (["set-night-vision", "auto"], 0x2B),
        (["set-ranging", "on"], 0x81),
        (["set-area-temperature", "on", "0.1", "0.1", "0.9", "0.9"], 0x30),
    ],
)
def test_send_prints_feedback_json(sim_url: str, command: list[str], opcode: int) -> None:
    result = run("send", f"{sim_url}?local_port=0", *command)
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["ok"] is True
    assert out["opcode"] == opcode
    assert out["status"] == "SUCCESS"
    assert out["status_raw"] == 0


def test_send_euler_holds_the_control_values_until_the_camera_arrives(sim_url: str) -> None:
    result = run("send", f"{sim_url}?local_port=0", "enter-euler-control", "0", "-40", "30",
                 "--hold", "3")
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["opcode"] == 0x14
    assert abs(out["attitude_deg"]["pitch"] + 40) < 1.0
    assert abs(out["attitude_deg"]["yaw"] - 30) < 1.0


@pytest.mark.parametrize("aircraft", [["--aircraft", "-33.85,151.2,50"],
                                      ["--aircraft=-33.85,151.2,50"]], ids=["space", "equals"])
def test_send_gaze_at_a_southern_coordinate(sim_url: str, aircraft: list[str]) -> None:
    """The command line a user south of the equator types, as given: `--aircraft` followed
    by a value starting with a minus."""
    result = run("send", f"{sim_url}?local_port=0", "gaze-at", "-33.86", "151.21", "20",
                 *aircraft)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["opcode"] == 0x15


def test_send_failure_exits_1_with_status(sim_url: str) -> None:
    result = run("send", f"{sim_url}?local_port=0", "set-fill-light", "100")  # not on this pod
    assert result.returncode == 1
    out = json.loads(result.stdout)
    assert out["ok"] is False
    assert out["opcode"] == 0x80
    assert out["status_raw"] == 1


def test_send_timeout_exits_1() -> None:
    # nothing listens on this port: no reply, so the connect wait times out
    result = run("send", "udp://127.0.0.1:9?local_port=0", "take-photo", "--timeout", "0.3")
    assert result.returncode == 1
    assert json.loads(result.stdout)["ok"] is False


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["udp://127.0.0.1:2337", "frobnicate"], "unknown command 'frobnicate'"),
        (["udp://127.0.0.1:2337", "zoom-to"], "zoom-to: the following arguments are required: "
                                               "ratio"),
        (["udp://127.0.0.1:2337", "zoom-to", "fast"], "argument ratio: invalid float value"),
        (["udp://127.0.0.1:2337", "zoom-to", "2", "3"], "unrecognized arguments: 3"),
        (["udp://127.0.0.1:2337", "set-area-temperature", "on", "0.1"], "give all of left top "
                                                                    "right bottom, or none"),
        (["udp://127.0.0.1:2337", "set-ranging", "maybe"], "expected on/off"),
        (["ftp://127.0.0.1", "take-photo"], "scheme"),
        (["udp://127.0.0.1:99999", "take-photo"], "port"),
    ],
)
def test_send_usage_errors_exit_2_with_one_line(args: list[str], message: str) -> None:
    result = run("send", *args)
    assert result.returncode == 2
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_send_out_of_range_argument_exits_2_before_sending(sim_url: str) -> None:
    result = run("send", f"{sim_url}?local_port=0", "zoom-to", "0.5")
    assert result.returncode == 2
    assert "ratio: 0.5 is outside the allowed range" in result.stderr


def test_monitor_prints_live_lines(sim_url: str) -> None:
    start = time.monotonic()
    result = run("monitor", f"{sim_url}?local_port=0", "--count", "3", "--interval", "0.1")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.strip().splitlines()
    assert len(lines) == 3
    for line in lines:
        mode = line.split("|")[0].strip()
        assert mode in {m.name for m in Mode}
        assert re.search(r"att r *[+-]\d+\.\d\d p *[+-]\d+\.\d\d y", line)
        assert re.search(r"zoom +\d+\.\dx", line)
        assert "link up" in line
    assert time.monotonic() - start < 15


def test_monitor_bad_url_exits_2() -> None:
    result = run("monitor", "udp://")
    assert result.returncode == 2
    assert result.stderr.startswith("gcu-async monitor:")


def test_send_whose_reader_has_gone_keeps_its_status_and_says_nothing(sim_url: str) -> None:
    """``gcu-async send … | head -c 0``: the command still runs and its exit status is
    its outcome; the closed pipe costs no traceback."""
    proc = subprocess.Popen([*CLI, "send", f"{sim_url}?local_port=0", "take-photo"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    assert proc.stdout is not None
    proc.stdout.close()  # before the result is printed
    try:
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert (proc.returncode, err) == (0, "")
