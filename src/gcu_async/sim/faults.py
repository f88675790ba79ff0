"""Seeded fault injection (sans-I/O): what happens to each packet on its way.

A :class:`FaultPlan` holds one :class:`FaultConfig` for requests (host → GCU) and one for
replies (GCU → host); each direction has its own :class:`FaultInjector` with its own
``random.Random(seed)``. The injector draws the same number of random values for every
packet, so the fate of the *n*-th packet in a direction depends only on the seed and *n*:
a run is reproducible for a given seed and packet sequence.

Faults, each with its own probability: ``drop`` (lost), ``corrupt`` (one bit flipped at a
random position), ``duplicate`` (sent twice), ``reorder`` (held back for ``reorder_hold``
seconds, so that the packets sent meanwhile overtake it: reordering as real networks do it,
by a bounded extra delay), plus ``delay``: an extra delay drawn uniformly from [0, delay]
seconds.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, replace


def _probability(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= 1:
        raise ValueError(f"{name}: {value!r} is outside the allowed range [0, 1] (probability)")
    return float(value)


@dataclass(frozen=True)
class FaultConfig:
    """Fault probabilities for one direction; ``delay`` is the maximum extra delay (s)."""

    drop: float = 0.0
    corrupt: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    delay: float = 0.0
    seed: int = 0
    reorder_hold: float = 0.005
    """Seconds a reordered packet is held back (packets sent meanwhile overtake it)."""

    def __post_init__(self) -> None:
        for name in ("drop", "corrupt", "duplicate", "reorder"):
            _probability(name, getattr(self, name))
        for name in ("delay", "reorder_hold"):
            d = getattr(self, name)
            if isinstance(d, bool) or not isinstance(d, (int, float)) or not 0 <= d < math.inf:
                raise ValueError(f"{name}: {d!r} is outside the allowed range [0, inf) s")

    @property
    def active(self) -> bool:
        """Does this configuration change anything?"""
        return bool(self.drop or self.corrupt or self.duplicate or self.reorder or self.delay)


@dataclass(frozen=True)
class FaultPlan:
    """Faults for both directions, applied independently."""

    requests: FaultConfig = FaultConfig()
    """Host → GCU packets (before the model sees them)."""
    replies: FaultConfig = FaultConfig()
    """GCU → host packets (after the model answered)."""

    @classmethod
    def both(cls, config: FaultConfig) -> FaultPlan:
        """The same probabilities in both directions; replies use ``seed + 1`` so the two
        directions do not fail in lockstep."""
        return cls(config, replace(config, seed=config.seed + 1))

    @property
    def active(self) -> bool:
        return self.requests.active or self.replies.active


@dataclass(frozen=True)
class FaultDecision:
    """The fate of one packet."""

    drop: bool = False
    corrupt_at: tuple[int, int] | None = None
    """(byte index, bit mask) to flip."""
    copies: int = 1
    hold: bool = False
    """Reorder: deliver after the next packet of the same direction."""
    delay: float = 0.0


@dataclass
class FaultStats:
    packets: int = 0
    dropped: int = 0
    corrupted: int = 0
    duplicated: int = 0
    reordered: int = 0
    delayed: int = 0


class FaultInjector:
    """Decides, deterministically for its seed, what happens to each packet."""

    def __init__(self, config: FaultConfig) -> None:
        self.config = config
        self._rng = random.Random(config.seed)
        self.stats = FaultStats()

    def decide(self, length: int) -> FaultDecision:
        """The fate of the next packet, of ``length`` bytes."""
        c = self.config
        r = self._rng
        # always draw the same values, so decisions depend only on (seed, packet number)
        u_drop, u_corrupt, u_dup, u_reorder, u_delay = (r.random() for _ in range(5))
        position, bit = r.randrange(max(length, 1)), 1 << r.randrange(8)
        s = self.stats
        s.packets += 1
        if u_drop < c.drop:
            s.dropped += 1
            return FaultDecision(drop=True)
        corrupt_at = (position, bit) if u_corrupt < c.corrupt and length > 0 else None
        copies = 2 if u_dup < c.duplicate else 1
        hold = u_reorder < c.reorder
        delay = u_delay * c.delay
        s.corrupted += corrupt_at is not None
        s.duplicated += copies > 1
        s.reordered += hold
        s.delayed += delay > 0
        return FaultDecision(False, corrupt_at, copies, hold, delay)

    @staticmethod
    def apply(data: bytes, decision: FaultDecision) -> bytes:
        """``data`` with the decision's corruption (if any) applied."""
        if decision.corrupt_at is None:
            return data
        index, bit = decision.corrupt_at
        buf = bytearray(data)
        buf[index] ^= bit
        return bytes(buf)
