"""Host check: the aircraft velocity against the change of the GNSS position over time.

Over windows of at least :data:`VELOCITY_WINDOW_S` in which the sub frame's position moved
between :data:`MIN_SPEED_M_S` and :data:`MAX_SPEED_M_S`, the mean of the velocity fields is
compared with the position's change; a scale off by ≈10 is 0.1 m/s sent for 0.01 m/s.
One window is open at a time: bounded memory.
"""

from __future__ import annotations

import math

from gcu_async.conformance.findings import Deviation, Example
from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame

VELOCITY_WINDOW_S = 1.0
MIN_SPEED_M_S = 0.5
"""The velocity check compares windows of at least :data:`VELOCITY_WINDOW_S` in which the
position moved at least this fast."""
MAX_SPEED_M_S = 300.0
"""Faster than this is a position jump (e.g. the first GNSS fix), not motion."""
MIN_VELOCITY_WINDOWS = 3
EARTH_RADIUS_M = 6_371_000.0
_SCALES = ((10, "the velocity looks like 0.1 m/s (dm/s) units: check the scale (0.01 m/s)"),
           (100, "the velocity looks like m/s: check the scale (0.01 m/s)"),
           (0.1, "the velocity looks like mm/s: check the scale (0.01 m/s)"),
           (-1, "the velocity has the opposite sign: check the axes (up positive)"))  # fmt: skip


class VelocityCheck:
    """Velocity fields against the position's change, window by window."""

    def __init__(self, examples: int) -> None:
        self._examples = examples
        self._window: tuple[float, tuple[float, float, float], list[float], int] | None = None
        self._dot = 0.0
        self._square = 0.0
        self._windows = 0
        self._shown: list[tuple[float, str]] = []

    def add(self, main: HostMainFrame, sub: HostSubFrame, t: float) -> None:
        """A packet with INS valid and a sub frame, at ``t``."""
        pos = (sub.latitude, sub.longitude, sub.altitude)
        v = main.velocity
        if self._window is None:
            self._window = (t, pos, [0.0, 0.0, 0.0], 0)
            return
        t0, p0, vsum, n = self._window
        vsum[0] += v.north
        vsum[1] += v.east
        vsum[2] += v.up
        n += 1
        if t - t0 < VELOCITY_WINDOW_S:
            self._window = (t0, p0, vsum, n)
            return
        dt = t - t0
        k = math.pi / 180 * EARTH_RADIUS_M
        moved = ((pos[0] - p0[0]) * k / dt,
                 (pos[1] - p0[1]) * k * math.cos(math.radians(p0[0])) / dt,
                 (pos[2] - p0[2]) / dt)  # fmt: skip
        mean = tuple(s / n for s in vsum)
        self._window = (t, pos, [0.0, 0.0, 0.0], 0)
        speed = math.hypot(*moved)
        if not MIN_SPEED_M_S <= speed <= MAX_SPEED_M_S or not (p0[0] or p0[1]):
            return  # standing still, or a position jump (the first fix)
        self._windows += 1
        self._dot += sum(a * b for a, b in zip(moved, mean, strict=True))
        self._square += sum(b * b for b in mean)
        if len(self._shown) < self._examples:
            self._shown.append((t0, f"{t0:.1f}–{t:.1f} s: position moved N/E/U "
                                + "/".join(f"{x:+.2f}" for x in moved) + " m/s, velocity "
                                "fields say " + "/".join(f"{x:+.2f}" for x in mean)
                                + " m/s"))  # fmt: skip

    def report(self, devs: dict[str, Deviation], notes: list[str]) -> None:
        if self._windows < MIN_VELOCITY_WINDOWS:
            notes.append(f"velocity scale not checked: {self._windows} windows of "
                         f"{VELOCITY_WINDOW_S:g} s with the position moving ≥ {MIN_SPEED_M_S:g} "
                         f"m/s (needs {MIN_VELOCITY_WINDOWS})")  # fmt: skip
            return
        ratio = math.inf if self._square == 0 else self._dot / self._square
        summary = (f"velocity × {ratio:.2f} matches the change of GNSS position over "
                   f"{self._windows} windows of ≥ {VELOCITY_WINDOW_S:g} s")  # fmt: skip
        if 0.8 <= ratio <= 1.25:
            notes.append(summary + ": consistent")
            return
        d = devs["velocity.scale"] = Deviation(
            "velocity.scale", "velocity disagrees with the change of GNSS position",
            self._windows, self._windows, [Example(t, "", text) for t, text in self._shown])
        guess = next(((f"{factor:g}×", meaning) for factor, meaning in _SCALES
                      if 0.8 <= ratio / factor <= 1.25), None)  # fmt: skip
        d.diagnosis = f"the position changes {ratio:.2f}× as fast as the velocity fields say" + (
            f" (≈{guess[0]}): {guess[1]}"
            if guess
            else ": check the scale (0.01 m/s) and the axes (north, east, up)"
        )
