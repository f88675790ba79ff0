"""The command line as a new user meets it, through the real entry point (subprocesses):
``send --aircraft`` for the commands that need INS data (against a ``gcu-async sim``
process), the usage rule for timeouts, a did-you-mean, the missing-extra rule, and help
texts that say their defaults."""

from __future__ import annotations

import json
import re
import signal
import struct
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

from gcu_async.protocol.catalogue import CATALOGUE

CLI = [sys.executable, "-m", "gcu_async.cli"]
ROOT = Path(__file__).resolve().parents[2]
NEEDS_MARK = "[--aircraft]"


def run(*args: str, timeout: float = 30.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout,
                          check=False)  # fmt: skip


def one_line_usage_error(result: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert result.returncode == 2, (result.returncode, result.stdout, result.stderr)
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    for needle in needles:
        assert needle in result.stderr, result.stderr
    assert "Traceback" not in result.stderr


@pytest.fixture(scope="module")
def sim_url() -> Iterator[str]:
    proc = subprocess.Popen([*CLI, "sim", "--listen", "udp://127.0.0.1:0", "--pod", "D-90AI"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert proc.stdout is not None
        match = re.search(r"listening on (udp://\S+)", proc.stdout.readline())
        assert match
        yield f"{match.group(1)}?local_port=0"
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            if proc.stdout is not None:
                proc.stdout.close()


# -- item: the aircraft state for the commands that need it ----------------------------------
@pytest.mark.parametrize("aircraft", ["47.38,8.53,400", "47.38,8.53,400,-10", "47.38,8.53,400,350"])
def test_gaze_at_succeeds_with_the_aircraft_given(sim_url: str, aircraft: str) -> None:
    result = run("send", sim_url, "gaze-at", "47.39", "8.54", "420", "--aircraft", aircraft)
    assert result.returncode == 0, (result.stdout, result.stderr)
    out = json.loads(result.stdout)
    assert out["ok"] is True and out["opcode"] == 0x15 and out["mode"] == "GAZE"


def test_enter_gaze_lock_takes_the_aircraft_before_the_command_name(sim_url: str) -> None:
    result = run("send", sim_url, "--aircraft", "47.38,8.53,400", "enter-gaze-lock")
    assert result.returncode == 0, (result.stdout, result.stderr)
    assert json.loads(result.stdout)["opcode"] == 0x16


@pytest.mark.parametrize("command", [e.cli_name for e in CATALOGUE if e.needs_ins])
def test_a_command_that_needs_ins_without_the_aircraft_is_a_usage_error(command: str) -> None:
    args = ["1", "2", "3"] if command == "gaze-at" else []
    one_line_usage_error(run("send", "udp://127.0.0.1:9", command, *args),
                         f"{command}: the GCU runs it only with valid INS data",
                         "--aircraft LAT,LON,ALT[,YAW]")  # fmt: skip


@pytest.mark.parametrize(("aircraft", "needle"), [
    ("47,8", "expected LAT,LON,ALT[,YAW]"), ("a,b,c", "expected LAT,LON,ALT[,YAW]"),
    ("91,8,400", "--aircraft: position.latitude: 91.0 is outside"),
    ("47,8,400,360", "--aircraft: attitude.yaw: 360.0 is outside"),
    ("47,8,400,nan", "attitude.yaw"),
])  # fmt: skip
def test_a_bad_aircraft_is_a_usage_error(aircraft: str, needle: str) -> None:
    one_line_usage_error(run("send", "udp://127.0.0.1:9", "gaze-at", "1", "2", "3",
                             "--aircraft", aircraft), needle)  # fmt: skip


def test_send_help_marks_exactly_the_catalogues_commands_that_need_ins() -> None:
    result = run("send", "--help")
    assert result.returncode == 0
    marked = {line.split()[0] for line in result.stdout.splitlines()
              if line.startswith("  ") and line.rstrip().endswith(NEEDS_MARK)}  # fmt: skip
    assert marked == {e.cli_name for e in CATALOGUE if e.needs_ins} == {"gaze-at",
                                                                         "enter-gaze-lock"}
    assert "--aircraft LAT,LON,ALT[,YAW]" in result.stdout


# -- the usage rule ------------------------------------------------------------------------------
@pytest.mark.parametrize("value", ["nan", "0", "-1", "inf", "1e308", "3601"])
def test_send_timeout_outside_its_range_is_a_usage_error(value: str) -> None:
    one_line_usage_error(run("send", "udp://127.0.0.1:9", "take-photo", "--timeout", value),
                         "--timeout", "(0, 3600] seconds")  # fmt: skip


@pytest.mark.parametrize("value", ["nan", "0", "-1", "inf", "1e308"])
@pytest.mark.parametrize("option", ["--timeout", "--interval"])
def test_monitor_seconds_outside_their_range_are_a_usage_error(option: str, value: str) -> None:
    one_line_usage_error(run("monitor", "udp://127.0.0.1:9", option, value),
                         option, "(0, 3600] seconds")  # fmt: skip


def test_send_hold_is_bounded() -> None:
    one_line_usage_error(run("send", "udp://127.0.0.1:9", "take-photo", "--hold", "inf"),
                         "--hold", "[0, 3600] seconds")  # fmt: skip


def test_an_underscored_command_gets_a_did_you_mean() -> None:
    one_line_usage_error(run("send", "udp://127.0.0.1:9", "zoom_to", "10"),
                         "unknown command 'zoom_to'; did you mean 'zoom-to'?")  # fmt: skip
    result = run("send", "udp://127.0.0.1:9", "frobnicate")
    one_line_usage_error(result, "unknown command 'frobnicate'; gcu-async send --help lists all")
    assert len(result.stderr) < 120, result.stderr  # not every name on one line


def test_an_unknown_command_names_at_most_three_close_ones() -> None:
    result = run("send", "udp://127.0.0.1:9", "set-zoom", "10")
    one_line_usage_error(result, "unknown command 'set-zoom'; did you mean")
    assert result.stderr.count("'") <= 2 + 2 * 3, result.stderr


# -- a missing extra: one rule, one quoted hint ------------------------------------------------
BLOCKED = textwrap.dedent("""
    import sys

    class Missing:
        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] in {blocked!r}:
                raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
            return None

    sys.meta_path.insert(0, Missing())
    from gcu_async.cli import main
    sys.exit(main(sys.argv[1:]))
""")


@pytest.mark.parametrize(("blocked", "args", "extra"), [
    ({"pymavlink"}, ["mavlink-bridge", "udp://127.0.0.1:9", "--mavlink", "udpin:127.0.0.1:0"],
     "mavlink"),
    ({"dpkt", "pcapng"}, ["send", "udp://127.0.0.1:9", "take-photo", "--capture", "x.pcapng"],
     "capture"),
    ({"dpkt", "pcapng"}, ["monitor", "udp://127.0.0.1:9", "--capture", "x.pcapng"], "capture"),
])  # fmt: skip
def test_a_missing_extra_exits_2_with_the_quoted_hint(blocked: set[str], args: list[str],
                                                      extra: str) -> None:  # fmt: skip
    result = subprocess.run([sys.executable, "-c", BLOCKED.format(blocked=blocked), *args],
                            capture_output=True, text=True, timeout=30, check=False)
    one_line_usage_error(result, f"pip install 'gcu-async[{extra}]'")


def test_decode_of_a_capture_without_the_extra_follows_the_same_rule(tmp_path: Path) -> None:
    """The capture extra is needed only once the input turns out to be a capture file."""
    capture = tmp_path / "one.pcap"
    header = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)  # Ethernet
    frame = bytes(12) + b"\x08\x00" + bytes(28)
    capture.write_bytes(header + struct.pack("<IIII", 0, 0, len(frame), len(frame)) + frame)
    blocked = {"dpkt", "pcapng"}
    result = subprocess.run([sys.executable, "-c", BLOCKED.format(blocked=blocked), "decode",
                             "--file", str(capture)],
                            capture_output=True, text=True, timeout=30, check=False)  # fmt: skip
    one_line_usage_error(result, "pip install 'gcu-async[capture]'")


# -- help texts ----------------------------------------------------------------------------------
def test_wireshark_help_shows_one_percent_sign() -> None:
    result = run("wireshark", "--help")
    assert result.returncode == 0
    assert "%APPDATA%" in result.stdout and "%%" not in result.stdout


def test_monitor_help_shows_every_default() -> None:
    result = run("monitor", "--help")
    helps: dict[str, str] = {}  # option -> its help text
    option = ""
    for line in result.stdout.splitlines():
        start = re.match(r"  (?:-\w, )?(--[a-z-]+)", line)
        if start:
            option = start.group(1)
        if option:
            helps[option] = f"{helps.get(option, '')} {line.strip()}"
    for option, default in (("--interval", "default 0.5"), ("--count", "default 0"),
                            ("--timeout", "default 3"), ("--json", "default: text"),
                            ("--capture", "default: none")):  # fmt: skip
        assert default in " ".join(helps[option].split()), (option, helps.get(option))


@pytest.mark.parametrize("args", [
    ["mavlink-bridge", "udp://127.0.0.1:9"], ["monitor"], ["frobnicate"],
    ["monitor", "udp://127.0.0.1:9", "--count", "x"], ["sim", "--no-such-option"],
])  # fmt: skip
def test_a_parser_usage_error_is_one_line(args: list[str]) -> None:
    one_line_usage_error(run(*args), "--help)")


def test_monitor_labels_the_attitude_relative_to_the_aircraft(sim_url: str) -> None:
    result = run("monitor", sim_url, "--count", "1")
    assert result.returncode == 0, result.stderr
    assert "vs aircraft r" in result.stdout and "rel x" not in result.stdout


# -- the docs' sample output -------------------------------------------------------------------
DOCS = [ROOT / "README.md", ROOT / "docs" / "cli.md", ROOT / "docs" / "getting-started.md"]


def test_the_docs_sample_send_output_has_the_real_fields(sim_url: str) -> None:
    samples = [json.loads(m) for path in DOCS
               for m in re.findall(r'(\{"ok": true, "command".*?\})(?:`|$)',
                                   path.read_text(encoding="utf-8"), re.M)]  # fmt: skip
    assert len(samples) >= 2
    result = run("send", sim_url, "enter-euler-control", "0", "-30", "45")
    assert result.returncode == 0, result.stderr
    real = json.loads(result.stdout)
    for sample in samples:
        assert set(sample) == set(real), sample
        assert set(sample["attitude_deg"]) == set(real["attitude_deg"])


@pytest.mark.parametrize("value", ["500", "nan", "1"])
def test_send_rate_is_checked_before_anything_opens(value: str) -> None:
    one_line_usage_error(run("send", "udp://127.0.0.1:9", "take-photo", "--rate", value),
                         f"--rate: {float(value)!r} is outside the allowed range [2, 200] Hz")


def test_a_failure_prints_its_likely_cause(sim_url: str) -> None:
    result = run("send", sim_url, "set-fill-light", "100")  # the D-90AI has no fill light
    assert result.returncode == 1, result.stderr
    out = json.loads(result.stdout)
    assert out["ok"] is False and out["likely_cause"] == "NOT_SUPPORTED"
    assert "Appendix 8: the D-90AI does not support FILL_LIGHT" in out["cause_detail"]
    assert out["error"].endswith(f"(likely cause: {out['cause_detail']})")
