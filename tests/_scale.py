"""How big the heavy generated tests run, from ``GCU_TEST_SIZE``: ``full`` (the default) or
``reduced``.

``make test`` runs the suite on every CPython 3.10–3.13 it finds: at full size on the main
interpreter (the one that also lints and builds the docs), reduced on the others, so every
CI run has one full-size run and stays well inside its time budget (.ci/pythons.py).
Reduced: the 100,000-command session contract runs 10,000 commands, the 500-command bad-link
test one seed instead of two, the UDP exactly-once test over real sockets 200 commands at the
10 ms hold instead of 500 at each of 5 and 10 ms, and Hypothesis tests without their own
``max_examples`` 25 examples instead of 100.
"""

from __future__ import annotations

import os

SIZE = os.environ.get("GCU_TEST_SIZE", "full").strip().lower() or "full"
if SIZE not in ("full", "reduced"):
    raise RuntimeError(f"GCU_TEST_SIZE: {SIZE!r} is not 'full' or 'reduced'")
FULL = SIZE == "full"


def scaled(full: int, reduced: int) -> int:
    """``full`` in a full-size run, else ``reduced``."""
    return full if FULL else reduced
