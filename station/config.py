"""The lab's usual settings: ``station.toml`` in the working folder, else ``~/.config/station/station.toml``.

Example::

    # station.toml
    port = "/dev/ttyUSB0"
    protocol = "legacy"
    limit = 200            # controller clamp, DAC counts
    soft_limit = 1500      # encoder counts
    timeout = 0.1          # s
    out_dir = "runs"       # where default run logs go

Keys are ``station step``'s option names with ``_`` for ``-`` (:data:`KEYS`); each value
is checked by the option's own type, so the ranges are the options' ranges. Options given
on the command line win over the file (:func:`apply_config`).
"""

from __future__ import annotations

import argparse
import os
import tomllib
from pathlib import Path
from typing import Any

from station.errors import StationError

FILE_NAME = "station.toml"
KEYS = ("port", "protocol", "baud", "limit", "soft_limit", "timeout", "max_lag", "max_miss", "max_step", "out_dir")
"""What the file may set (``station step``'s options)."""


def config_path(cwd: str | Path | None = None) -> Path | None:
    """The config file in use: ``./station.toml``, else ``$XDG_CONFIG_HOME/station/station.toml``
    (default ``~/.config/station/station.toml``); None when neither exists.

    Parameters
    ----------
    cwd : path, optional
        The working folder (default: the process's).
    """
    here = Path(cwd or ".") / FILE_NAME
    if here.is_file():
        return here
    home = Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config")
    user = home / "station" / FILE_NAME
    return user if user.is_file() else None


def load_config(path: str | Path | None) -> dict[str, Any]:
    """The file's settings as a dict (empty without a file).

    Parameters
    ----------
    path : path or None
        From :func:`config_path`.

    Raises
    ------
    StationError
        Unreadable file, not UTF-8 TOML, or an unknown key (names the file and key).
    """
    if path is None:
        return {}
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise StationError(f"{path}: cannot read the config file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise StationError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise StationError(f"{path}: not valid TOML: {exc}") from None
    unknown = sorted(set(doc) - set(KEYS))
    if unknown:
        raise StationError(f"{path}: {unknown[0]}: unknown setting (expected {', '.join(KEYS)})")
    return doc


def apply_config(parser: argparse.ArgumentParser, cwd: str | Path | None = None) -> None:
    """Make the config file's settings ``parser``'s defaults, each checked by its option's own
    type (so the ranges are the options'); options given on the command line still win.

    A bad file does not stop the parser from being built (``station --help`` works): its
    error is kept as the default ``_config_error`` for the command to raise when it runs;
    ``_config`` names the file in use (None without one).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        ``station step``'s parser, its options added (one per :data:`KEYS` entry).
    cwd : path, optional
        The working folder (default: the process's).
    """
    path = None
    try:
        path = config_path(cwd)
        settings = load_config(path)
        actions = {a.dest: a for a in parser._actions}
        defaults = {}
        for key, value in settings.items():
            action = actions[key]
            if isinstance(value, bool) or not isinstance(value, (str, int, float)):
                raise StationError(f"{path}: {key}: expected a string or a number, got {value!r}")
            text = str(value)
            try:
                converted = action.type(text) if action.type is not None else text
            except (argparse.ArgumentTypeError, ValueError, TypeError) as exc:
                raise StationError(f"{path}: {key} = {value!r}: {exc}") from None
            if action.choices is not None and converted not in action.choices:
                raise StationError(f"{path}: {key} = {value!r}: expected one of {', '.join(action.choices)}")
            defaults[key] = converted
        parser.set_defaults(**defaults, _config=str(path) if path else None, _config_error=None)
    except StationError as exc:
        parser.set_defaults(_config=str(path) if path else None, _config_error=str(exc))
