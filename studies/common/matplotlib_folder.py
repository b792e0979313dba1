"""A writable matplotlib configuration folder for the command line, said in one line.

Matplotlib keeps its font cache in ``$MPLCONFIGDIR``, else ``$XDG_CONFIG_HOME/matplotlib``,
else ``~/.config/matplotlib``. Where that folder cannot be made or written (a HOME that is
not a folder, or read-only), matplotlib makes a temporary one in every process that imports
it and says so in two lines each: four lines on stderr for one ``run`` (the command and its
figure worker). :func:`writable_config_folder` gives the command and its workers one
temporary folder, removed at exit, and one line saying how to keep a cache.
"""

from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

VARIABLE = "MPLCONFIGDIR"


def default_config_folder() -> Path:
    """The folder matplotlib uses when ``MPLCONFIGDIR`` is not set (its ``get_configdir``)."""
    if not sys.platform.startswith(("linux", "freebsd")):
        return Path.home() / ".matplotlib"
    config = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(config) / "matplotlib"


def writable_config_folder() -> None:
    """Nothing when ``MPLCONFIGDIR`` is set or matplotlib's default folder is writable;
    otherwise ``MPLCONFIGDIR`` is set to a temporary folder (removed at exit), inherited by
    worker processes, and one line on stderr says so."""
    if os.environ.get(VARIABLE):
        return
    folder = default_config_folder()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if os.access(folder, os.W_OK | os.X_OK):
            return
        reason = "is not writable"
    except (OSError, RuntimeError) as exc:  # RuntimeError: no home folder to expand
        reason = f"cannot be made ({getattr(exc, 'strerror', None) or exc})"
    try:
        temporary = tempfile.mkdtemp(prefix="engine-studies-matplotlib-")
    except OSError:
        return  # no temporary folder either: matplotlib says what it can
    atexit.register(shutil.rmtree, temporary, ignore_errors=True)
    os.environ[VARIABLE] = temporary
    sys.stderr.write(
        f"note: matplotlib's folder {folder} {reason}: its font cache is rebuilt in a "
        f"temporary folder for this command (set {VARIABLE} to a writable folder to keep it)\n"
    )
