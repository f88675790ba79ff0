"""What machine a benchmark ran on (shared by the benchmark scripts)."""

from __future__ import annotations

import os
import platform
import sys


def cpu_model() -> str:
    """CPU model string from /proc/cpuinfo (Linux), else whatever ``platform`` knows."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.lower().startswith(("model name", "hardware", "cpu model")):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def load_average() -> str:
    """The 1, 5 and 15 minute load averages, or ``?`` where the OS has none."""
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except (AttributeError, OSError):
        return "?"


def virtualization() -> str | None:
    """``hypervisor`` when /proc/cpuinfo shows the CPU flag of a guest (Linux), else None."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return "hypervisor" if " hypervisor" in line else None
    except OSError:
        pass
    return None


def machine_lines() -> list[str]:
    """Human-readable lines: Python, OS, CPU (model, logical CPUs, guest or not), load."""
    guest = virtualization()
    return [
        f"python : {platform.python_implementation()} {platform.python_version()}"
        f" ({sys.executable})",
        f"os     : {platform.system()} {platform.release()} ({platform.machine()})",
        f"cpu    : {cpu_model()}, {os.cpu_count()} logical CPUs"
        + (f" ({guest}: a virtual machine)" if guest else ""),
        f"load   : {load_average()} (1, 5, 15 min)",
    ]
