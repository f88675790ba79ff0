"""The Wireshark dissector that ships with gcu_async, built from the protocol package.

``xfgcu.lua`` (in this package) dissects the GCU private protocol V2.0.6 over UDP, TCP and
the serial link type of gcu_async's captures; see docs/wireshark.md. The file in the package
is the hand-written part: one marker line stands where the tables go. :func:`dissector_source`
is the complete dissector (the tables generated from :mod:`gcu_async.protocol` by
:mod:`gcu_async.wireshark.tables`), so a command added to the protocol reaches Wireshark with
no file to regenerate. ``gcu-async wireshark --install`` writes it to the personal Lua plugin
folder (:func:`personal_plugin_folder`); ``--print-path`` writes it to the user cache
(:func:`dissector_path`) and prints where.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from importlib.resources import files
from pathlib import Path

from gcu_async.wireshark import tables

DISSECTOR_NAME = "xfgcu.lua"
MARKER = "-- @@XFGCU_TABLES@@"
"""The line of the packaged ``xfgcu.lua`` that the generated tables replace."""
TSHARK_TIMEOUT = 10.0
"""Seconds ``tshark -G folders`` may take to say where the plugins go."""


def template_path() -> Path:
    """The hand-written dissector inside the installed package (its tables not filled in)."""
    return Path(str(files("gcu_async.wireshark").joinpath(DISSECTOR_NAME)))


def dissector_source() -> str:
    """The complete dissector: the packaged ``xfgcu.lua`` with the tables generated from
    :mod:`gcu_async.protocol` in place of its marker line."""
    template = template_path().read_text(encoding="utf-8")
    if template.count(MARKER) != 1:
        raise ValueError(f"{template_path()}: the marker {MARKER!r} must appear exactly once")
    return template.replace(MARKER, tables.render())


def cache_folder() -> Path:
    """Where :func:`dissector_path` writes: ``%LOCALAPPDATA%\\gcu_async\\Cache`` on
    Windows, ``$XDG_CACHE_HOME/gcu_async`` elsewhere (default: ``.cache/gcu_async`` in the
    home folder)."""
    if sys.platform == "win32":
        local = os.environ.get("LOCALAPPDATA")
        base = Path(local) if local else Path.home() / "AppData" / "Local"
        return base / "gcu_async" / "Cache"
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache") / "gcu_async"


def write_atomically(target: Path, text: str) -> Path:
    """Write ``text`` to ``target`` through a temporary file in the same folder and a
    rename, so that a reader (tshark, another writer) never sees a partial file; creates the
    folder. Returns ``target``; raises ``OSError`` if it cannot be written."""
    target.parent.mkdir(parents=True, exist_ok=True)
    data = text.encode("utf-8")
    fd, temp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(temp, 0o644)  # mkstemp's 0600 would hide a plugin from other accounts' tshark
        os.replace(temp, target)
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise
    return target


def dissector_path(folder: Path | None = None) -> Path:
    """The complete dissector as a file, for ``tshark -X lua_script:PATH``: written (once per
    content) to ``folder`` (default :func:`cache_folder`) as ``xfgcu-<hash>.lua``, the hash
    that of its text, so that versions of the package and their protocol tables never share
    a file and concurrent writers write the same bytes. Raises ``OSError`` if the folder
    cannot be written."""
    text = dissector_source()
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]
    target = (folder if folder is not None else cache_folder()) / f"xfgcu-{digest}.lua"
    try:
        if target.read_text(encoding="utf-8") == text:
            return target
    except (OSError, UnicodeDecodeError):
        pass
    return write_atomically(target, text)


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
    """Write the complete dissector (:func:`dissector_source`) into ``folder`` (default
    :func:`personal_plugin_folder`) as ``xfgcu.lua``, creating the folder; returns the
    installed file. Raises ``OSError`` if it cannot be written."""
    target_dir = folder if folder is not None else personal_plugin_folder()
    return write_atomically(target_dir / DISSECTOR_NAME, dissector_source())
