"""``gcu-async wireshark``: where the Wireshark dissector is, and install it.

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
        help="print the path of the Wireshark dissector, or install it",
        description="The package ships a Wireshark dissector (xfgcu.lua) for the GCU protocol "
        "over UDP, TCP and the serial captures gcu_async writes. --install copies it to your "
        "personal Lua plugin folder (the one `tshark -G folders` reports, else "
        "~/.local/lib/wireshark/plugins, or %APPDATA%\\Wireshark\\plugins on Windows); "
        "Wireshark loads it at its next start (or Analyze > Reload Lua Plugins). For one run: "
        "tshark -X lua_script:$(gcu-async wireshark --print-path) -r capture.pcapng",
    )
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument("--print-path", action="store_true",
                       help="print the path of the dissector file in the package")  # fmt: skip
    group.add_argument("--install", action="store_true",
                       help="copy it to the personal Lua plugin folder")  # fmt: skip
    group.add_argument("--print-folder", action="store_true",
                       help="print the folder --install copies to")  # fmt: skip
    p.add_argument("--dest", type=Path, metavar="DIR",
                   help="with --install: copy into DIR instead")  # fmt: skip
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.dest is not None and not args.install:
        print("gcu-async wireshark: --dest: only with --install", file=sys.stderr)
        return 2
    if args.print_path:
        print(dissector_path())
        return 0
    if args.print_folder:
        print(personal_plugin_folder())
        return 0
    try:
        target = install(args.dest)
    except OSError as exc:
        print(f"gcu-async wireshark: cannot install the dissector: {exc}", file=sys.stderr)
        return 1
    print(target)
    return 0
