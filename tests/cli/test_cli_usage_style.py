"""One style of usage error across the sub-commands (docs/cli.md, "Exit status"): one line
on stderr, exit status 2, starting ``gcu-async COMMAND: `` as ``send``'s do (no argparse
``error:``), naming the command-line option in the command line's terms (``--system-id``,
never the library's ``system_id``) — whether the parser, the sub-command's own checks or
the library below found it. Through the entry point, in-process: nothing is opened."""

from __future__ import annotations

from pathlib import Path

import pytest

from gcu_async.cli import main

CASES = [
    # (arguments, the start of the one line)
    (["sim", "--loss", "2"], "gcu-async sim: --loss: 2.0 is outside the allowed range [0, 1]"),
    (["sim", "--listen", "ftp://127.0.0.1"], "gcu-async sim: --listen: "),
    (["sim", "--pod", "X-1"], "gcu-async sim: --pod: 'X-1' is not one of "),
    (["sim", "--max-zoom", "0.5"], "gcu-async sim: --max-zoom: 0.5 is outside the allowed "),
    (["sim", "--reply-port", "0"], "gcu-async sim: --reply-port: 0 is outside 1-65535"),
    (["sim", "--loss", "x"], "gcu-async sim: argument --loss: invalid float value: 'x'"),
    (["sim", "--bogus"], "gcu-async sim: unrecognized arguments: --bogus"),
    (["demo", "--speed", "0"], "gcu-async demo: --speed: 0.0 is outside the allowed range"),
    (["demo", "--url", "ftp://x"], "gcu-async demo: --url: ftp://x: scheme: "),
    (["demo", "--bogus"], "gcu-async demo: unrecognized arguments: --bogus"),
    (["monitor", "udp://127.0.0.1", "--bogus"], "gcu-async monitor: unrecognized arguments"),
    (["monitor", "udp://127.0.0.1", "--interval", "0"], "gcu-async monitor: --interval: "),
    (["send", "udp://127.0.0.1", "--bogus", "take-photo"],
     "gcu-async send: unrecognized arguments: --bogus"),
    (["send", "udp://127.0.0.1"],  # a command may take no argument: ask for none
     "gcu-async send: the following arguments are required: COMMAND (see gcu-async send"),
    (["decode", "--bogus"], "gcu-async decode: unrecognized arguments: --bogus"),
    (["wireshark", "--install", "--print-folder"], "gcu-async wireshark: argument "),
    (["sned", "udp://127.0.0.1"], "gcu-async: unknown command 'sned': did you mean 'send'?"),
]  # fmt: skip


def status_of(args: list[str]) -> object:
    """``main``'s exit status: returned by the sub-command, or argparse's ``SystemExit``."""
    try:
        return main(args)
    except SystemExit as exc:
        return exc.code


@pytest.mark.parametrize(("args", "start"), CASES, ids=[" ".join(a) for a, _ in CASES])
def test_one_line_naming_the_sub_command(
    args: list[str], start: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert status_of(args) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and err.startswith(start), err
    assert ": error: " not in err


def test_an_unknown_option_before_the_sub_command_is_the_top_levels(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert status_of(["--bogus", "demo"]) == 2
    assert capsys.readouterr().err.startswith("gcu-async: unrecognized arguments: --bogus")


@pytest.mark.parametrize(("option", "value", "parameter"), [
    ("--system-id", "300", "300 is outside the allowed range [1, 255]"),
    ("--max-zoom", "0", "0.0 is outside the allowed range [1, "),
    ("--video-url", "ftp://x", "'ftp://x' has scheme 'ftp'"),
])  # fmt: skip
def test_the_bridge_names_its_options(
    option: str, value: str, parameter: str, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("pymavlink", reason="mavlink-bridge needs the 'mavlink' extra")
    args = ["mavlink-bridge", "udp://127.0.0.1", "--mavlink", "udpout:127.0.0.1:14550"]
    assert main([*args, option, value]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith(f"gcu-async mavlink-bridge: {option}: {parameter}"), err
    assert "system_id" not in err and "max_zoom" not in err and "video_url" not in err


def test_wireshark_without_an_option_writes_the_dissector_and_prints_its_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The bare command does what its one-line help says first (``--print-path``)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert status_of(["wireshark"]) == 0
    out, err = capsys.readouterr()
    path = Path(out.strip())
    assert err == "" and path.is_relative_to(tmp_path) and path.suffix == ".lua"
    assert "Proto(" in path.read_text(encoding="utf-8")
