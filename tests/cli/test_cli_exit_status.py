"""One exit-status rule for every sub-command (docs/cli.md, "Exit status"): 0 done,
1 failed, 2 usage, 130 ended by Ctrl-C or SIGTERM — through the real entry point."""

from __future__ import annotations

import json
import signal
import subprocess

import pytest

from helpers.sim.process import CLI, SimProcess

DEAD = "udp://127.0.0.1:9?local_port=0"  # discard port: nothing answers


@pytest.mark.parametrize(("args", "status"), [
    (["decode", "zz"], 2),
    (["decode", "00 11"], 1),
    (["send", DEAD, "take-photo", "--timeout", "0.3"], 1),
    (["send", DEAD, "no-such-command"], 2),
    (["monitor", DEAD, "--timeout", "0.3"], 1),
    (["monitor", DEAD, "--interval", "0"], 2),
    (["sim", "--listen", "ftp://x"], 2),
    (["demo", "--speed", "0"], 2),
])  # fmt: skip
def test_statuses(args: list[str], status: int) -> None:
    done = subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=60,
                          check=False)  # fmt: skip
    assert done.returncode == status, (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_send_interrupted_closes_cleanly_with_130(sig: signal.Signals) -> None:
    sim = SimProcess("--listen", "udp://127.0.0.1:0")
    try:
        # a rate mode holds its rates for --hold seconds (no target to stop early at)
        proc = subprocess.Popen([*CLI, "send", f"{sim.url}?local_port=0", "enter-pointing-lock",
                                 "0", "5", "--hold", "60"], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)  # fmt: skip
        try:
            sim.wait_for("executed POINTING_LOCK")  # connected, command sent, holding
            running = proc.poll() is None
            proc.send_signal(sig)
            out, err = proc.communicate(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    finally:
        log = sim.stop()
    assert running, (out, err)
    assert proc.returncode == 130, err
    assert json.loads(out) == {"ok": False, "error": "interrupted"}
    assert "Traceback" not in err
    assert "executed POINTING_LOCK" in log
