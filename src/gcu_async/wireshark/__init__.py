"""The Wireshark dissector that ships with gcu_async, and where Wireshark looks for it.

``xfgcu.lua`` (in this package) dissects the GCU private protocol V2.0.6 over UDP, TCP and
the serial link type of gcu_async's captures; see docs/wireshark.md. ``gcu-async wireshark
--install`` copies it to the personal Lua plugin folder (:func:`personal_plugin_folder`).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from importlib.resources import files
from pathlib import Path

DISSECTOR_NAME = "xfgcu.lua"
TSHARK_TIMEOUT = 10.0
"""Seconds ``tshark -G folders`` may take to say where the plugins go."""


def dissector_path() -> Path:
    """The dissector file inside the installed package."""
    return Path(str(files("gcu_async.wireshark").joinpath(DISSECTOR_NAME)))


def default_plugin_folder() -> Path:
    """Wireshark's documented personal Lua plugin folder: ``%APPDATA%\\Wireshark\\plugins``
    on Windows, ``~/.local/lib/wireshark/plugins`` elsewhere (Wireshark 2.5 and later; it
    does not follow ``XDG_CONFIG_HOME``, which only the old ``~/.config/wireshark/plugins``
    did)."""
    if sys.platform == "win32":
        appdata = os.environ.get("APPDATA")
        base = Path(appdata) if appdata else Path.home() / "AppData" / "Roaming"
        return base / "Wireshark" / "plugins"
    return Path.home() / ".local" / "lib" / "wireshark" / "plugins"


def tshark_plugin_folder(tshark: str | None = None) -> Path | None:
    """The "Personal Lua Plugins" folder the installed tshark reports (``tshark -G
    folders``), or ``None`` when there is no tshark or it does not say."""
    program = tshark or shutil.which("tshark")
    if program is None:
        return None
    try:
        done = subprocess.run([program, "-G", "folders"], capture_output=True, text=True,
                              timeout=TSHARK_TIMEOUT, check=False)  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    for line in done.stdout.splitlines():
        name, _, value = line.partition(":")
        if name.strip() == "Personal Lua Plugins" and value.strip():
            return Path(value.strip())
    return None


def personal_plugin_folder() -> Path:
    """Where ``--install`` copies the dissector: what tshark reports, else
    :func:`default_plugin_folder`."""
    return tshark_plugin_folder() or default_plugin_folder()


def install(folder: Path | None = None) -> Path:
    """Copy the dissector into ``folder`` (default :func:`personal_plugin_folder`), creating
    it; returns the installed file. Raises ``OSError`` if it cannot be written."""
    target_dir = folder if folder is not None else personal_plugin_folder()
    target_dir.mkdir(parents=True, exist_ok=True)
    target = target_dir / DISSECTOR_NAME
    shutil.copyfile(dissector_path(), target)
    return target
