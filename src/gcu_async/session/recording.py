"""What the session believes about recording, for state-checked record toggles.

Record (``Opcode.RECORD``) is a toggle: sending it twice stops what the first started. The session
therefore serializes record commands and checks the state when a state-checked one is
about to be sent (docs/client.md, "Recording"). The state comes from the camera flags of
the replies (sub frame bit B4), with one correction: right after a toggle executed, a camera
may report the old state for a moment, so the expected state wins until a reply shows it
or ``settle`` seconds have passed. After a toggle whose outcome is unknown nothing is
believed until ``settle`` has passed.
"""

from __future__ import annotations

import math


class RecordingBelief:
    """Observed recording flag, corrected by toggles not yet visible in the replies."""

    def __init__(self, settle: float = 1.0) -> None:
        self.settle = settle
        self.observed: bool | None = None
        """The flag in the latest sub frame (None before the first)."""
        self._expected: bool | None = None
        self._unknown = False
        self._until = -math.inf

    def reset(self) -> None:
        self.observed = None
        self._expected = None
        self._unknown = False
        self._until = -math.inf

    def observe(self, recording: bool, now: float) -> None:
        """A reply's camera flags say ``recording``."""
        self.observed = recording
        if self._expected is not None and recording == self._expected:
            self._expected = None  # the camera shows it: trust the flag again

    def toggled(self, expected: bool | None, now: float) -> None:
        """A toggle executed (success feedback); the camera should now be ``expected``
        (None: the state before was not known)."""
        self._expected = expected
        self._unknown = expected is None
        self._until = now + self.settle

    def uncertain(self, now: float) -> None:
        """A toggle was sent, but whether it executed is not known."""
        self._expected = None
        self._unknown = True
        self._until = now + self.settle

    def value(self, now: float) -> bool | None:
        """True/False: recording or not, as far as the session can tell; None: not known
        (no sub frame yet, or a toggle is settling without a known result)."""
        if now < self._until:
            if self._unknown:
                return None
            if self._expected is not None:
                return self._expected
        return self.observed

    def settles_at(self) -> float:
        """When :meth:`value` may change without a new reply."""
        return self._until
