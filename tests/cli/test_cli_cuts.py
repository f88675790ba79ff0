"""The CLI's smaller behaviours, through the real entry point against a
``gcu-async sim`` process: each ``send`` command's own ``--help``, ``--timeout`` for every
command (calibrate included), ``--cameras``, the demo against a GCU left zoomed in, the
vendor's pod names in ``monitor --json``."""

from __future__ import annotations

import argparse
import io
import json
import subprocess
import time
from collections.abc import Iterator
from typing import Any

import pytest

from gcu_async import GcuSubFrame
from gcu_async.cli import build_parser, main
from gcu_async.cli.send import resolve
from gcu_async.cli.send_commands import COMMANDS, parse_cameras
from gcu_async.protocol import CameraMask
from helpers.sim.process import CLI, SimProcess

DEAD = "udp://127.0.0.1:9?local_port=0"  # discard port: nothing answers


def cli(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout,
                          check=False)  # fmt: skip


@pytest.fixture
def sim() -> Iterator[SimProcess]:
    process = SimProcess("--listen", "udp://127.0.0.1:0")
    yield process
    process.stop()


# -- 1. each send command has its own help ---------------------------------------------------
def test_send_help_lists_every_command_with_its_arguments_and_method() -> None:
    done = cli("send", "--help")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    width = max(map(len, COMMANDS))  # the names in one column
    for name, spec in COMMANDS.items():
        args = " ".join(f"[{p.name}]" if p.optional else p.name for p in spec.params)
        mark = " [--aircraft]" if spec.needs_ins else ""  # the catalogue's needs_ins
        line = f"  {name:<{width}} {args + ' ' if args else ''}-> {spec.method}(){mark}"
        assert line in lines, line


def test_a_command_help_shows_its_arguments_units_ranges_and_method() -> None:
    done = cli("send", DEAD, "enter-euler-control", "--help")
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert out.startswith("usage: gcu-async send URL enter-euler-control ")
    assert "GcuClient.enter_euler_control(roll, pitch, yaw)" in out
    flat = " ".join(out.split())  # argparse aligns the help column to the longest option
    for line in ("roll -180 to 180 deg: Euler roll (default: the current one)",
                 "pitch -180 to 180 deg: Euler pitch (default: the current one)",
                 "yaw -180 to 360 (excluded) deg: Euler yaw"):  # fmt: skip
        assert line in flat, out
    assert "--cameras" not in out  # euler addresses no camera
    assert "zoom_to" not in out and "set-area-temperature" not in out  # not the generic list


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_help_is_its_own(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["send", DEAD, name, "--help"])
    assert exited.value.code == 0
    out = " ".join(capsys.readouterr().out.split())  # argparse wraps at the terminal width
    spec = COMMANDS[name]
    assert out.startswith(f"usage: gcu-async send URL {name} ")
    assert f"GcuClient.{spec.method}(" in out
    for param in spec.params:
        assert f"{param.name} {' '.join(param.help.split())}" in out, param
    assert ("--cameras LIST" in out) == spec.takes_cameras
    assert "--timeout SECONDS" in out


# -- 2. --timeout applies to every command ---------------------------------------------------
@pytest.mark.alone  # a bound on the wall clock, interpreter start-up included (helpers/tiers.py)
@pytest.mark.parametrize("before", [False, True], ids=["after", "before"])
def test_calibrate_obeys_timeout(sim: SimProcess, before: bool) -> None:
    """The simulator calibrates for 3 s: with ``--timeout 1`` the command gives up after
    1 s (the method's own default is 15 s), wherever the option is written."""
    url = f"{sim.url}?local_port=0"
    args = ["--timeout", "1", url, "calibrate"] if before else [url, "calibrate", "--timeout", "1"]
    t0 = time.monotonic()
    done = cli("send", *args)
    elapsed = time.monotonic() - t0
    assert done.returncode == 1, (done.stdout, done.stderr)
    out = json.loads(done.stdout)
    assert out["ok"] is False
    assert "within 1 s" in out["error"] and "in progress" in out["error"], out
    assert elapsed < 2.8, elapsed  # well before the 3 s calibration ends
    assert sim.executions()[("CALIBRATION", "-")] == 1


def test_calibrate_without_timeout_waits_for_the_calibration(sim: SimProcess) -> None:
    done = cli("send", f"{sim.url}?local_port=0", "calibrate")
    assert done.returncode == 0, (done.stdout, done.stderr)
    assert json.loads(done.stdout)["command"] == "CALIBRATION"


@pytest.mark.alone  # a bound on the wall clock, interpreter start-up included (helpers/tiers.py)
def test_timeout_bounds_every_other_command_too() -> None:
    t0 = time.monotonic()
    done = cli("send", DEAD, "zoom-to", "4", "--timeout", "0.4")
    assert done.returncode == 1
    assert time.monotonic() - t0 < 4.0  # not the default 5 s


# -- 3. --cameras ----------------------------------------------------------------------------
def test_parse_cameras() -> None:
    assert parse_cameras("1") == CameraMask.CAMERA_1
    assert parse_cameras("2") == CameraMask.CAMERA_2
    assert parse_cameras("1,2") == CameraMask.VISIBLE | CameraMask.THERMAL
    assert parse_cameras(" Visible , thermal ") == 0b11
    assert parse_cameras("3,camera-8") == 0b1000_0100
    for bad in ("", "0", "9", "1,", "x", "0x03", "1;2"):
        with pytest.raises(argparse.ArgumentTypeError, match="camera numbers 1-8 or names"):
            parse_cameras(bad)


@pytest.mark.parametrize(("args", "executed"), [
    (["set-palette", "3"], ("PALETTE", "02 03")),  # the method's default: camera 2
    (["set-palette", "3", "--cameras", "1,2"], ("PALETTE", "03 03")),
    (["--cameras", "thermal", "take-photo"], ("TAKE_PHOTO", "02")),  # before the command's name
    (["zoom-to", "4", "--cameras", "1,2"], ("ZOOM_TO", "03 d8 ff")),
    (["toggle-recording", "--cameras", "visible,thermal"], ("RECORD", "03")),
])  # fmt: skip
def test_cameras_reach_the_wire(sim: SimProcess, args: list[str],
                                executed: tuple[str, str]) -> None:  # fmt: skip
    url = f"{sim.url}?local_port=0"
    argv = [*args[:2], url, *args[2:]] if args[0].startswith("--") else [url, *args]
    done = cli("send", *argv)
    assert done.returncode == 0, (done.stdout, done.stderr)
    assert [key for key in sim.executions() if key[0] == executed[0]] == [executed]


@pytest.mark.parametrize("name", [n for n, s in COMMANDS.items() if not s.takes_cameras])
def test_cameras_refused_for_a_command_without_cameras(name: str) -> None:
    args = [a for p in COMMANDS[name].params if not p.optional
            for a in [SAMPLE.get(p.name, "1")]]  # fmt: skip
    parsed = build_parser().parse_args(["send", DEAD, name, *args, "--cameras", "1"])
    with pytest.raises(ValueError, match=rf"^--cameras: {name} addresses no camera"):
        resolve(parsed)


SAMPLE = {"on": "on", "mode": "1", "coordinates": "aircraft", "hours": "1"}


def test_cameras_refused_through_the_entry_point(sim: SimProcess) -> None:
    done = cli("send", f"{sim.url}?local_port=0", "set-time-zone", "3", "--cameras", "1")
    assert done.returncode == 2
    assert done.stderr.strip() == ("gcu-async send: --cameras: set-time-zone addresses no camera "
                                   "(set_time_zone() has no cameras parameter)")  # fmt: skip
    assert done.stdout == ""
    assert not sim.executions()  # nothing was sent


def test_bad_cameras_is_a_usage_error() -> None:
    done = cli("send", DEAD, "take-photo", "--cameras", "9")
    assert done.returncode == 2
    assert "camera numbers 1-8 or names" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


# -- 4. the demo against a GCU left zoomed in ------------------------------------------------
def zoom_of(url: str) -> float:
    done = cli("monitor", url, "--json", "--count", "1", "--interval", "0.1")
    assert done.returncode == 0, done.stderr
    info: dict[str, Any] = json.loads(done.stdout.splitlines()[0])["info"]
    return float(info["camera1_zoom"])


def test_demo_runs_against_a_gcu_zoomed_to_10x(sim: SimProcess) -> None:
    url = f"{sim.url}?local_port=0"
    done = cli("send", url, "zoom-to", "10", "--hold", "2.5")  # the zoom travels ~1.2 s
    assert done.returncode == 0, done.stderr
    assert zoom_of(url) == pytest.approx(10.0)  # the demo starts from a zoomed-in camera
    done = cli("demo", "--url", url, "--quick", "--no-live", timeout=90)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "[prep] camera 1 is at 10.0x: back to 1x first" in done.stdout
    assert "result: OK" in done.stdout
    assert zoom_of(url) == pytest.approx(1.0)


async def test_demo_pan_rate_follows_the_zoom() -> None:
    """Even if the GCU stays zoomed in (no preparation), the pan keeps within 150 / zoom."""
    from gcu_async import connect
    from gcu_async.cli.demo import Demo, FlightPath
    from gcu_async.cli.liveview import Console
    from gcu_async.sim import GcuSimulator

    out = io.StringIO()
    sim = GcuSimulator()
    async with sim.serve_udp("127.0.0.1", 0) as server, connect(server.url, local_port=0) as gcu:
        await gcu.reach_zoom(10.0)
        demo = Demo(gcu, Console(out, "off"), speed=10.0, path=FlightPath(),
                    started=time.monotonic())  # fmt: skip
        await demo.step_pan()
        assert gcu.info is not None and gcu.info.camera1_zoom == pytest.approx(10.0)
    text = out.getvalue()
    assert "enter_pointing_lock(yaw_rate=13.5): ok" in text, text  # 0.9 * 150 / 10
    assert "seen a 30 deg pan" in text, text


# -- 5. the vendor's pod names ---------------------------------------------------------------
def test_sub_frame_dict_uses_the_vendors_name() -> None:
    assert GcuSubFrame.build(pod_model=41).as_dict()["pod_model"] == "D-90AI"
    assert GcuSubFrame.build(pod_model=41).as_dict()["pod_model_member"] == "D_90AI"
    assert GcuSubFrame.build(pod_model=45).as_dict()["pod_model"] == "D-90Pro(TA)"
    assert GcuSubFrame.build(pod_model=99).as_dict()["pod_model"] == "unknown (code 99)"


def test_monitor_json_shows_the_vendors_pod_name() -> None:
    sim = SimProcess("--listen", "udp://127.0.0.1:0", "--pod", "D-90AI")
    try:
        done = cli("monitor", f"{sim.url}?local_port=0", "--json", "--count", "3",
                   "--interval", "0.2")  # fmt: skip
    finally:
        sim.stop()
    assert done.returncode == 0, done.stderr
    infos = [json.loads(line)["info"] for line in done.stdout.splitlines()]
    assert {i["pod_model"] for i in infos if i is not None} == {"D-90AI"}


# -- a value out of range is a usage error before anything is opened -------------------------
@pytest.mark.parametrize(("args", "message"), [
    (["zoom-to", "0.5"], "ratio: 0.5 is outside the allowed range [1, 3276.8] x"),
    (["set-time-zone", "20"], "offset_hours: 20 is outside the allowed range [-12, 14] h"),
    (["enter-euler-control", "0", "-30", "400"],
     "yaw: 400.0 is outside the allowed range [-180, 360) deg"),
    (["enter-pointing-lock", "0", "200"],
     "yaw_rate: 200.0 is outside the allowed range [-150, 150]"),
])  # fmt: skip
def test_out_of_range_values_fail_before_connecting(args: list[str], message: str) -> None:
    # nothing answers at DEAD: had the client been opened, this would be a timeout (1)
    done = cli("send", DEAD, *args, "--timeout", "5")
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert done.stderr.startswith(f"gcu-async send: {message}"), done.stderr
    assert done.stdout == ""
