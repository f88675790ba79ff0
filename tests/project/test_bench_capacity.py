"""The capacity benchmark (benchmarks/bench_capacity.py) runs end to end in ``--quick`` mode
at tiny sizes: every part and series searched, every probe judged by the counting process,
which heard every session, and no wrong packet (exit status 0). A smoke test of the script,
not a measurement: no figure is checked."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "bench_capacity.py"


def test_quick_run_at_tiny_sizes(tmp_path: Path) -> None:
    report = tmp_path / "capacity.json"
    result = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--start", "2", "--max", "4",
         "--warmup", "0.3", "--window", "0.6", "--json", str(report)],
        capture_output=True, text=True, timeout=180, check=False, cwd=ROOT,
    )  # fmt: skip
    out = result.stdout + result.stderr
    assert result.returncode == 0, out
    data = json.loads(report.read_text())
    assert data["failures"] == [], out
    series = {(e["part"], e["kind"]) for e in data["edges"]}
    assert series == {("client", "gcu"), ("client", "bare"), ("sim", "sim"), ("sim", "bare")}
    # from --start 2 up to --max 4, or down to 1 where a loaded machine fails the 2
    assert {p["sessions"] for p in data["probes"]} <= {1, 2, 4}, out
    for probe in data["probes"]:
        # judged, and the counting process heard every one of the probe's sessions
        assert probe["reason"] == "", out
        assert not math.isnan(probe["min_rate"]), out
        assert probe["min_rate"] > 0, out
        assert probe["window"] > 0.5, out
    assert "Targets (capacity ratio" in result.stdout, out
    for part in ("client", "sim"):
        assert f"{part}: the most sessions holding" in result.stdout, out
