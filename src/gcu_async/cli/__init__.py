"""``gcu-async`` command line: one sub-command per module, all on the public API."""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from typing import NoReturn

from gcu_async import __version__
from gcu_async._checks import did_you_mean
from gcu_async.cli import decode, demo, mavlink_bridge, monitor, send, sim, wireshark
from gcu_async.cli._exit import EXIT_USAGE
from gcu_async.cli._logging import VERBOSE_HELP, configure_logging
from gcu_async.cli._parser import CliParser

_INVALID_CHOICE = re.compile(r"argument COMMAND: invalid choice: '(?P<given>[^']*)'")


class OneLineParser(CliParser):
    """A parser whose usage errors are one line on stderr, exit status 2 (docs/cli.md, "Exit
    status"); its sub-command parsers are of the same class."""

    def error(self, message: str) -> NoReturn:
        match = _INVALID_CHOICE.match(message)
        if match and self._subparsers is not None:
            names = [n for a in self._subparsers._group_actions
                     for n in getattr(a, "choices", None) or ()]  # fmt: skip
            hint = did_you_mean(match["given"], names)
            if hint:
                message = f"unknown command {match['given']!r}: {hint}"
        self.exit(EXIT_USAGE, f"{self.prog}: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
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
    mavlink_bridge.register(sub)
    for command in sub.choices.values():
        command.add_argument("-v", "--verbose", action="count", default=0, help=VERBOSE_HELP)
        command.set_defaults(command_parser=command)
    return parser


def parse(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> argparse.Namespace:
    """``parser.parse_args(argv)``, except that an argument no parser knows is reported by
    the sub-command it was given to (``gcu-async demo: unrecognized arguments: --bogus``),
    not by ``gcu-async``: each sub-command's usage errors carry its own name."""
    args, extra = parser.parse_known_args(argv)
    if extra:
        given = list(sys.argv[1:] if argv is None else argv)
        before = given[: given.index(args.command)] if args.command in given else given
        owner = parser if any(arg in before for arg in extra) else args.command_parser
        owner.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gcu-async`` console script; returns the exit status."""
    args = parse(build_parser(), argv)
    configure_logging(args.verbose)
    status: int = args.run(args)
    return status


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
