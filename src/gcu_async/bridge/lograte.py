"""Rate-limited logging for the bridge (docs/mavlink-bridge.md, "The bridge contract", BG7):
the shared :class:`gcu_async._lograte.LogLimiter`, its summaries named "bridge" and logged
as warnings."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from gcu_async._lograte import BURST, WINDOW
from gcu_async._lograte import LogLimiter as _LogLimiter

__all__ = ["BURST", "WINDOW", "LogLimiter"]


class LogLimiter(_LogLimiter):
    """:class:`gcu_async._lograte.LogLimiter` with the bridge's summary line."""

    def __init__(self, logger: logging.Logger, *, burst: int = BURST, window: float = WINDOW,
                 clock: Callable[[], float] = time.monotonic) -> None:  # fmt: skip
        super().__init__(logger, burst=burst, window=window, clock=clock, name="bridge",
                         summary_level=logging.WARNING)  # fmt: skip
