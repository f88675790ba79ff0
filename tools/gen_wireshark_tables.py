"""Write the complete Wireshark dissector (the packaged ``xfgcu.lua`` with its tables).

The tables (names, flag bits, command rows) are generated from :mod:`gcu_async.protocol`
whenever the dissector is written (``gcu-async wireshark --install`` / ``--print-path``,
:func:`gcu_async.wireshark.dissector_source`); nothing generated is checked in. This tool
writes the same text to a file of your choice, to read or to hand to ``tshark -X
lua_script:FILE``:

    python tools/gen_wireshark_tables.py --write build/xfgcu.lua
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gcu_async.wireshark import dissector_source, write_atomically


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", type=Path, metavar="FILE", required=True,
                        help="write the complete dissector to FILE")  # fmt: skip
    args = parser.parse_args(argv)
    try:
        print(write_atomically(args.write, dissector_source()))
    except OSError as exc:
        print(f"gen_wireshark_tables: cannot write {args.write}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
