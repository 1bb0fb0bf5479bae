"""The lab's usual settings: ``station.toml`` in the working folder, else ``~/.config/station/station.toml``.

Example::

    # station.toml
    port = "/dev/ttyUSB0"
    protocol = "legacy"
    limit = 200            # controller clamp, DAC counts
    soft_limit = 1500      # encoder counts
    timeout = 0.1          # s
    out_dir = "runs"       # the output folder: default run logs, figures named after logs

Keys are ``station step``'s option names with ``_`` for ``-`` (:data:`KEYS`); each value
is checked by the option's own type, so the ranges are the options' ranges. Options given
on the command line win over the file (:func:`apply_config`). Every command that names
files itself (step, identify, compare, bode, plot) puts them in ``out_dir``
(:mod:`station.outputs`); the device settings are step's and identify's.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from station.errors import StationError
from station.inputs import TomlDoc, load_toml
from station.ranges import shown

FILE_NAME = "station.toml"
KEYS = ("port", "protocol", "baud", "limit", "soft_limit", "timeout", "max_lag", "max_miss", "max_step", "out_dir")
"""What the file may set (``station step``'s options)."""


def config_path(cwd: str | Path | None = None) -> Path | None:
    """The config file in use: ``./station.toml``, else ``$XDG_CONFIG_HOME/station/station.toml``
    (default ``~/.config/station/station.toml``); None when neither exists.

    Anything by that name counts (a folder, a FIFO, a dangling or looping symbolic link too:
    :func:`load_config` refuses it, rather than the station silently using the other file or
    none).

    Parameters
    ----------
    cwd : path, optional
        The working folder (default: the process's).
    """
    here = Path(cwd or ".") / FILE_NAME
    if os.path.lexists(here):  # (not Path.exists: it follows a link, and a dangling one would pass as no file)
        return here
    home = Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config")
    user = home / "station" / FILE_NAME
    return user if os.path.lexists(user) else None


def load_config(path: str | Path | None) -> dict[str, Any]:
    """The file's settings as a dict (empty without a file), read bounded
    (:func:`station.inputs.load_toml`: a regular UTF-8 file of at most 1 MB, nested at most
    8 deep).

    Parameters
    ----------
    path : path or None
        From :func:`config_path`.

    Raises
    ------
    StationError
        Not a regular file, unreadable, too large, not UTF-8, not valid or too deeply
        nested TOML, or an unknown key (names the file, line and key).
    """
    return {} if path is None else _read(path).data


def _read(path: str | Path) -> TomlDoc:
    doc = load_toml(path, "config file")
    unknown = sorted(set(doc.data) - set(KEYS))
    if unknown:
        raise doc.error(unknown[0], f"unknown setting (expected {', '.join(KEYS)})")
    return doc


def apply_config(parser: argparse.ArgumentParser, cwd: str | Path | None = None, skip: tuple[str, ...] = ()) -> None:
    """Make the config file's settings ``parser``'s defaults, each checked by its option's own
    type (so the ranges are the options'); options given on the command line still win.

    A bad file does not stop the parser from being built (``station --help`` works): its
    error is kept as the default ``_config_error`` for the command to raise when it runs;
    ``_config`` names the file in use (None without one) and ``_config_values`` holds what
    it set (so a message can say a value came from the file, not from an option). A key the
    command has no option for is checked as a known key and not applied.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        ``station step``'s parser, its options added (one per :data:`KEYS` entry).
    cwd : path, optional
        The working folder (default: the process's).
    skip : tuple of str, optional
        Keys of :data:`KEYS` that mean something else to this command (``station identify``'s
        ``--out-dir`` is its experiments' folder, not the output folder they are made in): the
        file's value is not applied as the option's default (still checked, and in
        ``_config_values``).
    """
    path = None
    try:
        path = config_path(cwd)
        doc = None if path is None else _read(path)
        actions = {a.dest: a for a in parser._actions}
        defaults = {}
        for key, value in ({} if doc is None else doc.data).items():
            action = actions.get(key)
            if action is None:  # not this command's (a device setting for compare)
                continue
            if isinstance(value, bool) or not isinstance(value, (str, int, float)):
                raise doc.error(key, f"expected a string or a number, got {shown(value)}")
            text = str(value)
            line = doc.line_of(key)
            where = f"{path}: line {line}: {key} = {shown(value)}" if line else f"{path}: {key} = {shown(value)}"
            try:
                converted = action.type(text) if action.type is not None else text
            except (argparse.ArgumentTypeError, ValueError, TypeError) as exc:
                raise StationError(f"{where}: {exc}", file=path, line=line, key=key) from None
            if action.choices is not None and converted not in action.choices:
                raise StationError(f"{where}: expected one of {', '.join(action.choices)}", file=path, line=line,
                                   key=key)
            defaults[key] = converted
        applied = {k: v for k, v in defaults.items() if k not in skip}
        parser.set_defaults(**applied, _config=str(path) if path else None, _config_error=None,
                            _config_values=defaults)
    except StationError as exc:
        parser.set_defaults(_config=str(path) if path else None, _config_error=str(exc), _config_values={})
