"""``-v`` / ``-vv``: the one logging option every sub-command takes."""

from __future__ import annotations

import logging
import sys

VERBOSE_HELP = ("log the library's lifecycle to stderr (INFO); -vv: every packet in and out "
                "too (DEBUG, the gcu_async.wire logger)")  # fmt: skip


def configure_logging(verbose: int) -> None:
    """``-v``: the ``gcu_async`` loggers at INFO on stderr; ``-vv``: DEBUG (every packet)."""
    if verbose <= 0:
        return
    logging.basicConfig(stream=sys.stderr, level=logging.WARNING,
                        format="%(asctime)s %(name)s %(levelname)s %(message)s")  # fmt: skip
    logging.getLogger("gcu_async").setLevel(logging.DEBUG if verbose >= 2 else logging.INFO)
