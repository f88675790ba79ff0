"""How big the heavy generated tests run, from ``GCU_TEST_SIZE``: ``full`` (the default) or
``reduced``.

``make test`` runs every test at full size once, on the main interpreter; the fast tier on the
other CPythons 3.10–3.13, and ``make check``, run at reduced size (.ci/pythons.py, Makefile).
Reduced: the 100,000-command session contract runs 5,000 commands (1 shard instead of 8),
the 500-command bad-link test one seed instead of two, the UDP exactly-once test over real
sockets 200 commands at the 10 ms hold instead of 500 at each of 5 and 10 ms, the boundary
properties (arbitrary values accepted iff valid) a tenth of their examples, the deframer's
split and byte-by-byte contracts 25 examples instead of 200, the session contract's boundary
tests find their violation without shrinking it, Hypothesis tests without their own
``max_examples`` 25 examples instead of 100, and those with their own a tenth of them (at
least 25)."""

from __future__ import annotations

import os

SIZE = os.environ.get("GCU_TEST_SIZE", "full").strip().lower() or "full"
if SIZE not in ("full", "reduced"):
    raise RuntimeError(f"GCU_TEST_SIZE: {SIZE!r} is not 'full' or 'reduced'")
FULL = SIZE == "full"


def scaled(full: int, reduced: int) -> int:
    """``full`` in a full-size run, else ``reduced``."""
    return full if FULL else reduced
