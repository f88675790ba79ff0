"""docs/client.md's example of ``as_dict()`` JSON ("Frames as JSON") is what the frames give:
the example is parsed and compared with the ``as_dict()`` of the frames it describes."""

from __future__ import annotations

import json
import re
from pathlib import Path

from gcu_async import Feedback, GcuMainFrame, Mode, Opcode

PAGE = Path(__file__).resolve().parents[2] / "docs" / "client.md"


def _example() -> dict[str, object]:
    text = PAGE.read_text(encoding="utf-8")
    section = text[text.index("### Frames as JSON"):]
    block = re.search(r"```json\n(.*?)\n```", section, re.S)
    assert block is not None
    parsed: dict[str, object] = json.loads(block[1])
    return parsed


def test_the_as_dict_example_is_what_the_frames_give() -> None:
    status = GcuMainFrame.build(mode=Mode.EULER_CONTROL, attitude=(0.0, -30.0, 45.0),
                                relative_angles=(30.0, 0.0, 45.0))  # fmt: skip
    feedback = Feedback(Opcode.EULER_CONTROL, 0)
    expected = {"status": status.as_dict(), "feedback": feedback.as_dict()}
    assert _example() == json.loads(json.dumps(expected))
    assert "EULER_CONTROL (0x14)" in str(status) and "pitch -30" in str(status)
