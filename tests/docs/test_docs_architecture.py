"""docs/architecture.md's counts of the public surface are those of ``gcu_async.__all__``."""

from __future__ import annotations

import enum
import re
from pathlib import Path

import gcu_async

PAGE = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"


def test_the_export_counts_are_true() -> None:
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    names = int(re.search(r"That is (\d+) names and `__version__`", text)[1])  # type: ignore[index]
    exceptions = int(re.search(r"the (\d+) exceptions", text)[1])  # type: ignore[index]
    enums = re.search(r"the (\d+) enums that describe them: ([^)]*)\)", text)
    assert enums is not None
    exported = [getattr(gcu_async, n) for n in gcu_async.__all__ if n != "__version__"]
    assert names == len(exported)
    assert exceptions == sum(isinstance(o, type) and issubclass(o, BaseException)
                             for o in exported)  # fmt: skip
    described = re.findall(r"`(\w+)`", enums[2])
    assert int(enums[1]) == len(described)
    assert all(issubclass(getattr(gcu_async, n), enum.Enum)
               and getattr(gcu_async, n).__module__ == "gcu_async.errors"
               for n in described)  # fmt: skip
    error_enums = {n for n in gcu_async.__all__ if n != "__version__"
                   and isinstance(getattr(gcu_async, n), type)
                   and issubclass(getattr(gcu_async, n), enum.Enum)
                   and getattr(gcu_async, n).__module__ == "gcu_async.errors"}  # fmt: skip
    assert set(described) == error_enums
