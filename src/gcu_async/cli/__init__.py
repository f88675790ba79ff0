"""``gcu-async`` command line: one sub-command per module, all on the public API."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from gcu_async import __version__
from gcu_async.cli import decode, demo, monitor, send, sim, wireshark


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gcu-async",
        description="Drive, simulate and decode XF Robot gimbal GCUs (protocol V2.0.6).",
    )
    parser.add_argument("--version", action="version", version=f"gcu-async {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    decode.register(sub)
    send.register(sub)
    monitor.register(sub)
    sim.register(sub)
    demo.register(sub)
    wireshark.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gcu-async`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    status: int = args.run(args)
    return status


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
