"""The vendor's example packets (corrected, see shared/spec/NOTES.md) and spec text.

``shared/`` lives beside the repository (CI clones it there), so it is located relative to
this file, never to the working directory.
"""

from __future__ import annotations

from pathlib import Path

SPEC_DIR = Path(__file__).resolve().parents[2] / "shared" / "spec"
SPEC_TEXT_PATH = SPEC_DIR / "gcu-private-protocol-v2.0.6.zh.md"


def load_hex(name: str) -> bytes:
    """Bytes of ``SPEC_DIR / name``: whitespace-separated hex."""
    path = SPEC_DIR / name
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} is missing: the tests need the shared/ directory beside the repository"
        )
    return bytes.fromhex(path.read_text(encoding="ascii"))


def all_vectors() -> dict[str, bytes]:
    """Every ``*.hex`` vector in the spec directory, by file name."""
    vectors = {p.name: load_hex(p.name) for p in sorted(SPEC_DIR.glob("*.hex"))}
    if not vectors:
        raise FileNotFoundError(f"no *.hex vectors in {SPEC_DIR}")
    return vectors


def spec_text() -> str:
    """The protocol document (Chinese markdown)."""
    return SPEC_TEXT_PATH.read_text(encoding="utf-8")


HOST_EXAMPLE = load_hex("host-example.hex")
"""Appendix 1, corrected: host → GCU, 72 bytes, null command."""
GCU_EXAMPLE = load_hex("gcu-example.hex")
"""Appendix 2, corrected: GCU → host, 73 bytes, take-photo success."""
