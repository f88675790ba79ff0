"""``gcu-async demo`` through the real console script, in subprocesses.

The full scripted runs take a few seconds each (the simulated zoom and slews move in real
time), so the module fixture starts them all at once and each test checks its own run.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and ptys")

_SCRIPT = Path(sys.executable).with_name("gcu-async")
CLI = (
    [str(_SCRIPT)]
    if _SCRIPT.exists()
    else [sys.executable, "-c", "import sys; from gcu_async.cli import main; sys.exit(main())"]
)
HEADER = re.compile(r"^\[\s*(\d+)/(\d+)\] (.+)$", re.MULTILINE)
ANSI_CLEAR = "\r\x1b[2K"


class Run:
    """A CLI subprocess whose stdout (a pipe, or a pty with ``tty=True``) and stderr are
    collected by reader threads."""

    def __init__(self, *args: str, tty: bool = False) -> None:
        self._out = bytearray()
        self._err = bytearray()
        self._changed = threading.Condition()
        env = {**os.environ, "COLUMNS": "200"}
        if tty:
            leader, follower = os.openpty()
            try:
                self.proc = subprocess.Popen(
                    [*CLI, *args], stdin=subprocess.DEVNULL, stdout=follower,
                    stderr=subprocess.PIPE, env=env,
                )  # fmt: skip
            except BaseException:
                os.close(leader)
                raise
            finally:
                os.close(follower)
            out_reader = threading.Thread(target=self._read_fd, args=(leader,), daemon=True)
        else:
            self.proc = subprocess.Popen(
                [*CLI, *args], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                stderr=subprocess.PIPE, env=env,
            )  # fmt: skip
            assert self.proc.stdout is not None
            out_reader = threading.Thread(
                target=self._read_pipe, args=(self.proc.stdout, self._out), daemon=True
            )
        assert self.proc.stderr is not None
        err_reader = threading.Thread(
            target=self._read_pipe, args=(self.proc.stderr, self._err), daemon=True
        )
        self._threads = [out_reader, err_reader]
        for thread in self._threads:
            thread.start()
        self._result: tuple[int, str, str] | None = None

    def _append(self, buffer: bytearray, data: bytes) -> None:
        with self._changed:
            buffer += data
            self._changed.notify_all()

    def _read_pipe(self, stream: IO[bytes], buffer: bytearray) -> None:
        with stream:
            while data := stream.read1(4096):  # type: ignore[attr-defined]
                self._append(buffer, data)

    def _read_fd(self, fd: int) -> None:
        try:
            while True:
                try:
                    data = os.read(fd, 4096)
                except OSError:  # EIO: the child side of the pty is closed
                    break
                if not data:
                    break
                self._append(self._out, data)
        finally:
            os.close(fd)

    @property
    def output(self) -> str:
        with self._changed:
            return self._out.decode()

    def wait_for(self, pattern: str, timeout: float = 15.0) -> re.Match[str]:
        """Wait until stdout matches ``pattern``."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                match = re.search(pattern, self._out.decode(), re.MULTILINE)
                if match:
                    return match
                left = deadline - time.monotonic()
                if left <= 0 or self.proc.poll() is not None:
                    raise AssertionError(f"{pattern!r} not printed:\n{self._out.decode()}")
                self._changed.wait(min(left, 0.2))

    def finish(self, timeout: float = 60.0) -> tuple[int, str, str]:
        """Exit status, stdout and stderr once the process has ended."""
        if self._result is None:
            try:
                rc = self.proc.wait(timeout)
            finally:
                self.kill()
            for thread in self._threads:
                thread.join(10)
            self._result = (rc, self._out.decode(), self._err.decode())
        return self._result

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)


class Sim(Run):
    """``gcu-async sim`` on an ephemeral loopback UDP port."""

    def __init__(self, *args: str) -> None:
        super().__init__("sim", "--listen", "udp://127.0.0.1:0", *args)
        self.url = self.wait_for(r"listening on (\S+)").group(1)

    def stop(self) -> tuple[int, str, str]:
        self.proc.send_signal(signal.SIGTERM)
        return self.finish(10)


def steps(out: str) -> list[tuple[int, int, str, str]]:
    """(number, total, title, body) of every step block in the output."""
    heads = list(HEADER.finditer(out))
    ends = [h.start() for h in heads[1:]] + [out.find("\nsummary")]
    return [
        (int(h[1]), int(h[2]), h[3], out[h.end() : end]) for h, end in zip(heads, ends, strict=True)
    ]


def summary(out: str) -> dict[str, str]:
    """``name: value`` lines after the ``summary`` line."""
    assert "\nsummary\n" in out, out
    text = out.split("\nsummary\n", 1)[1]
    return dict(re.findall(r"^\s*([a-z ]+):\s+(.*)$", text, re.MULTILINE))


def numbers(text: str) -> list[float]:
    return [float(n) for n in re.findall(r"-?\d+(?:\.\d+)?", text)]


def check_complete_run(out: str, *, skipped: int = 0) -> dict[str, str]:
    """A run where every step passed (or was skipped): check steps and summary together."""
    found = steps(out)
    total = found[0][1]
    assert total >= 10
    assert [n for n, *_ in found] == list(range(1, total + 1)), out
    for number, _, title, body in found:
        assert re.search(r"=> (ok \(\d+\.\d s\)|skipped: )", body), f"step {number} {title}"
        assert "FAILED" not in body and "NOT SEEN" not in body, body
    ok_commands = len(re.findall(r": ok in \d+\.\d ms$", out, re.MULTILINE))
    s = summary(out)
    assert numbers(s["steps"]) == [total - skipped, 0, skipped, 0, total], s["steps"]
    assert numbers(s["commands"]) == [ok_commands, 0], (s["commands"], ok_commands)
    latency = re.fullmatch(r"p50 (\d+\.\d) ms, max (\d+\.\d) ms", s["latency"])
    assert latency, s["latency"]
    p50, worst = float(latency[1]), float(latency[2])
    assert 0 < p50 <= worst < 2000
    sent, received = numbers(s["packets"])
    assert 0 < received <= sent
    assert s["crc errors"] == "0"
    assert s["link lost"] == "0 times"
    assert s["result"] == "OK"
    return s


# -- the runs ---------------------------------------------------------------------------------
BAD_OPTIONS = [
    ["--speed", "0"],
    ["--speed", "fast"],
    ["--listen", "ftp://127.0.0.1:1"],
    ["--listen", "serial:///dev/ttyUSB0"],
    ["--pod", "X-999"],
    ["--url", "udp://127.0.0.1:1", "--listen", "udp://127.0.0.1:0"],
    ["--url", "bogus://127.0.0.1:1"],
]
SUBPROCESS_USAGE = [BAD_OPTIONS[1], BAD_OPTIONS[5]]
"""Run through the console script too (exit status of the process, stderr)."""


@pytest.fixture(scope="module")
def runs() -> Iterator[dict[str, Run]]:
    made: dict[str, Run] = {}
    try:
        made["sim"] = sim = Sim()
        made["udp"] = Run("demo", "--quick", "--no-live")
        made["tcp"] = Run("demo", "--quick", "--listen", "tcp://127.0.0.1:0")
        made["url"] = Run("demo", "--quick", "--no-live", "--url", f"{sim.url}?local_port=0")
        made["tty"] = Run("demo", "--quick", "--listen", "pty", tty=True)
        made["pod"] = Run("demo", "--speed", "20", "--no-live", "--pod", "Z-6C")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as quiet:  # bound, never answers
            quiet.bind(("127.0.0.1", 0))
            url = f"udp://127.0.0.1:{quiet.getsockname()[1]}?local_port=0"
            made["silent"] = Run("demo", "--quick", "--no-live", "--url", url)
            for args in [*SUBPROCESS_USAGE, ["--help"]]:  # quick ones, while the others run
                made[" ".join(args)] = Run("demo", *args)
            yield made
    finally:
        for run in made.values():
            run.kill()
            run.finish(10)


def test_default_run_over_udp_reports_every_step_and_a_consistent_summary(
    runs: dict[str, Run],
) -> None:
    rc, out, err = runs["udp"].finish()
    assert rc == 0, out + err
    assert re.search(r"^simulator: D-90Pro\(TA\) on udp://127\.0\.0\.1:\d+ ", out, re.M), out
    s = check_complete_run(out)
    # every command the client saw succeed was executed exactly once by the simulator
    executions = numbers(s["sim executions"].split(" ", 1)[0])[0]
    assert executions == numbers(s["commands"])[0]
    for call in ("enter_pointing_follow()", "enter_euler_control(pitch=-45)",
                 "enter_pointing_lock(yaw_rate=",
                 "enter_top_down()", "zoom_to(10)", "zoom_to(1)", "take_photo()",
                 "start_recording()", "stop_recording()", "set_ranging(True)", "track(",
                 "stop_tracking()"):  # fmt: skip
        assert re.search(rf"^\s+{re.escape(call)}.*: ok in ", out, re.M), call
    # the effects showed in the telemetry: the slew reached its angles, the zoom moved
    # through intermediate ratios to 10x, the recording flag came and went
    slew = re.search(r"seen the slew: euler_control, pitch (\S+), yaw (\S+)", out)
    assert slew and abs(float(slew[1]) + 45.0) <= 0.5, out
    zoom = re.search(r"seen zoom 10x: 10\.0x after \S+ s \[(.*)\]", out)
    assert zoom, out
    ratios = [float(r.rstrip("x")) for r in zoom[1].split(" -> ")]
    assert len(ratios) >= 3 and ratios == sorted(ratios) and ratios[-1] == 10.0, ratios
    assert "seen the recording flag: recording" in out
    assert "seen the recording flag cleared" in out
    assert re.search(r"seen a laser distance: \d+\.\d m", out)
    assert re.search(r"seen tracking: track, ", out)
    assert "live:" not in out and "\x1b" not in out  # --no-live: progress lines only
    assert "Traceback" not in err


def test_listen_tcp_with_plain_live_lines_when_stdout_is_not_a_terminal(
    runs: dict[str, Run],
) -> None:
    rc, out, err = runs["tcp"].finish()
    assert rc == 0, out + err
    assert re.search(r"^simulator: \S+ on tcp://127\.0\.0\.1:\d+ ", out, re.M), out
    check_complete_run(out)
    live = re.findall(r"^  live: (.*)$", out, re.M)
    assert len(live) >= 3, out
    assert all(re.search(r"link up \d+/s crc 0 lost 0$", line) for line in live), live
    assert any(line.startswith("track ") for line in live) or any(
        line.startswith("top_down ") for line in live
    ), live
    assert "\x1b" not in out and "\r" not in out


def test_url_drives_an_external_simulator(runs: dict[str, Run]) -> None:
    rc, out, err = runs["url"].finish()
    assert rc == 0, out + err
    assert "simulator:" not in out
    s = check_complete_run(out)
    assert s["sim executions"].startswith("n/a")
    # the simulator subprocess logged every command the demo ran (and nothing more)
    src, _, sim_err = runs["sim"].stop()
    assert src == 130  # ended by a signal (docs/cli.md, "Exit status")
    executed = re.findall(r" executed (\w+) ", sim_err)
    assert len(executed) == numbers(s["commands"])[0], sim_err
    assert "EULER_CONTROL" in executed and "TRACK" in executed


def test_terminal_output_redraws_one_status_line_in_place(runs: dict[str, Run]) -> None:
    rc, out, err = runs["tty"].finish()
    assert rc == 0, out + err
    out = out.replace("\r\n", "\n")  # undo the terminal's output processing (ONLCR)
    redraws = re.findall(rf"{re.escape(ANSI_CLEAR)}([^\r\n\x1b]*)", out)
    status = [r for r in redraws if " | link up " in r]
    assert len(status) >= 10, out
    assert any(" zoom 10.0x " in r for r in status) and any(r.startswith("track ") for r in status)
    assert "  live:" not in out
    # what stays on the screen: per line, the text after the last clear-line
    screen = "\n".join(line.rsplit(ANSI_CLEAR, 1)[-1] for line in out.split("\n"))
    assert " | link up " not in screen  # every status line was redrawn or cleared
    assert re.search(r"^simulator: \S+ on serial:///dev/\S+ ", screen, re.M), screen
    check_complete_run(screen)


def test_pod_without_zoom_to_tracking_and_ranging(runs: dict[str, Run]) -> None:
    rc, out, err = runs["pod"].finish()
    assert rc == 0, out + err
    assert "pod Z-6C" in out
    check_complete_run(out, skipped=2)
    assert re.search(r"skipped: Z-6C does not support ranging", out)
    assert re.search(r"skipped: Z-6C does not support track", out)
    # no zoom-to on this pod: continuous zoom in/out, then stop
    assert "zoom_in() (this pod has no zoom-to): ok" in out
    assert "zoom_out() (this pod has no zoom-to): ok" in out
    assert len(re.findall(r"stop_zoom\(\): ok", out)) == 2
    assert "seen zoom 10x: 10.0x" in out and "seen zoom 1x: 1.0x" in out


# -- runs that end early ----------------------------------------------------------------------
def test_ctrl_c_stops_cleanly_with_status_130_and_a_summary() -> None:
    run = Run("demo", "--no-live")
    try:
        run.wait_for(r"^\[ 2/")
        run.proc.send_signal(signal.SIGINT)
        rc, out, err = run.finish(10)
    finally:
        run.kill()
    assert rc == 130, out + err
    assert "interrupted: session closed" in out
    s = summary(out)
    ok, failed, skipped, not_run, total = numbers(s["steps"])
    assert ok >= 1 and not_run >= 1 and ok + failed + skipped + not_run == total
    assert s["result"] == "INTERRUPTED"
    assert "Traceback" not in err


def test_link_lost_mid_run_fails_the_step_and_exits_1() -> None:
    sim = Sim("--silence", "30")
    try:
        run = Run("demo", "--quick", "--no-live", "--url", f"{sim.url}?local_port=0")
        try:
            run.wait_for(r"^\[ 3/")
            sim.proc.send_signal(signal.SIGUSR2)  # the simulator stops answering
            rc, out, err = run.finish(20)
        finally:
            run.kill()
    finally:
        sim.stop()
    assert rc == 1, out + err
    assert "=> FAILED: link lost" in out
    s = summary(out)
    assert numbers(s["steps"])[3] >= 1  # steps not run after the link was lost
    assert s["result"].startswith("FAILED (link lost")


def test_no_gcu_at_the_url_exits_1_with_one_line(runs: dict[str, Run]) -> None:
    rc, out, err = runs["silent"].finish()
    assert rc == 1, out + err
    assert err.strip().count("\n") == 0 and "no reply" in err, err
    assert "steps:              none run (no session)" in out
    assert re.search(r"^result: FAILED \(.*no reply", out, re.M), out


@pytest.mark.parametrize("args", SUBPROCESS_USAGE, ids=" ".join)
def test_bad_options_exit_2_with_one_line(runs: dict[str, Run], args: list[str]) -> None:
    rc, out, err = runs[" ".join(args)].finish(20)
    assert rc == 2, out + err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("gcu-async demo: --"), err


@pytest.mark.parametrize("args", BAD_OPTIONS, ids=" ".join)
def test_every_bad_option_is_refused_before_anything_starts(
    args: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    from gcu_async.cli import main

    assert main(["demo", *args]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.splitlines()
    option = args[-2] if args[0] == "--url" and len(args) > 2 else args[0]
    assert len(lines) == 1 and lines[0].startswith(f"gcu-async demo: {option}"), err


def test_help_documents_url_listen_and_exit_statuses(runs: dict[str, Run]) -> None:
    rc, out, _ = runs["--help"].finish(20)
    assert rc == 0
    text = " ".join(out.split())
    for word in ("--url", "--listen", "--pod", "--speed", "--quick", "--no-live", "130"):
        assert word in text, word
