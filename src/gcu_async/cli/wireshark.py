"""``gcu-async wireshark``: write the Wireshark dissector and say where, or install it.

Exit status: 0 done, 1 the file could not be written, 2 usage error.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from gcu_async.wireshark import dissector_path, install, personal_plugin_folder


def register(sub: Any) -> None:
    p = sub.add_parser(
        "wireshark",
        help="write the Wireshark dissector and print its path (the default), or install it",
        description="The package ships a Wireshark dissector (xfgcu.lua) for the GCU protocol "
        "over UDP, TCP and the serial captures gcu_async writes; its tables (names, command "
        "parameters) are generated from the installed package when it is written. --install "
        "writes it to your personal Lua plugin folder (the one `tshark -G folders` reports, "
        "else ~/.local/lib/wireshark/plugins, or %APPDATA%\\Wireshark\\plugins on Windows); "
        "Wireshark loads it at its next start (or Analyze > Reload Lua Plugins). --print-path "
        "(the default without an option) writes it to your user cache ($XDG_CACHE_HOME/gcu_async, "
        "default .cache/gcu_async in your home folder; %LOCALAPPDATA%\\gcu_async\\Cache on "
        "Windows) and prints its path; "
        "for one run: "
        "tshark -X lua_script:$(gcu-async wireshark --print-path) -r capture.pcapng",
    )
    group = p.add_mutually_exclusive_group()
    group.add_argument("--print-path", action="store_true",
                       help="write the dissector to the user cache (or --cache-dir) and print "
                       "its path (the default)")  # fmt: skip
    group.add_argument("--install", action="store_true",
                       help="write it to the personal Lua plugin folder")  # fmt: skip
    group.add_argument("--print-folder", action="store_true",
                       help="print the folder --install writes to")  # fmt: skip
    p.add_argument("--dest", type=Path, metavar="DIR",
                   help="with --install: write into DIR instead")  # fmt: skip
    p.add_argument("--cache-dir", type=Path, metavar="DIR",
                   help="with --print-path: write into DIR instead of the user cache")  # fmt: skip
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if not (args.install or args.print_folder):
        args.print_path = True
    if args.dest is not None and not args.install:
        print("gcu-async wireshark: --dest: only with --install", file=sys.stderr)
        return 2
    if args.cache_dir is not None and not args.print_path:
        print("gcu-async wireshark: --cache-dir: only with --print-path", file=sys.stderr)
        return 2
    if args.print_folder:
        print(personal_plugin_folder())
        return 0
    try:
        target = install(args.dest) if args.install else dissector_path(args.cache_dir)
    except OSError as exc:
        print(f"gcu-async wireshark: cannot write the dissector: {exc}", file=sys.stderr)
        return 1
    print(target)
    return 0
