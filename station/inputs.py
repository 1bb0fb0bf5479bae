"""Reading the files the station is given, bounded: one way for every kind.

Model files, parameter sets, compensator files and ``station.toml`` are small TOML files
(:func:`load_toml`); run logs are large text files whose rows numpy reads
(:func:`check_regular` before they are opened). Whatever a file holds, reading it ends
in bounded time and memory with either its contents or one
:class:`~station.errors.StationError` line naming the file (and the line and key where
known):

- only a regular file is read: a folder, a FIFO, a device such as ``/dev/zero`` or a
  socket is refused before it is opened (opening a FIFO would block; ``/dev/zero`` never
  ends);
- a TOML file larger than :data:`MAX_TOML_BYTES` is refused before it is read (and no
  more than that is ever read, should it grow meanwhile);
- the text is UTF-8; a byte that is not names its line;
- tables and arrays nest at most :data:`MAX_DEPTH` deep (``tomllib`` recurses once per
  level: a file nested thousands deep would end in a RecursionError).

What the fields mean, their types and ranges is each loader's own (``station.plant.model``,
``station.plant.parameters``, ``station.control.designs``, ``station.config``); they name a
field's line with :meth:`TomlDoc.line_of`.

Imports only :mod:`station.errors`.
"""

from __future__ import annotations

import os
import re
import stat
import tomllib
from pathlib import Path
from typing import Any, NamedTuple

from station.errors import StationError, one_line

MAX_TOML_BYTES = 1_000_000
"""Largest TOML file read, bytes (a model, parameter set, compensator or config file is a few hundred)."""

MAX_DEPTH = 8
"""Deepest nesting of tables and arrays in a TOML file read (the formats need 2)."""

MAX_MESSAGE = 600
"""Longest description of what is wrong in a field error, characters (a file may hold a
megabyte where a number belongs: the message stays one readable line)."""

_BARE_KEY = re.compile(r"[A-Za-z0-9_:.\-]{1,60}")


def key_text(key: str) -> str:
    """A TOML key as a message shows it: as written when it is a short bare key
    (``param:drive_c`` included), else quoted, escaped and cut (it may hold a newline or
    be a megabyte long).

    Parameters
    ----------
    key : str
        The key.
    """
    if _BARE_KEY.fullmatch(key):
        return key
    text = repr(key)
    return text if len(text) <= 40 else text[:37] + "..."


_HEADER = re.compile(r"^[ \t]*\[\[?[ \t]*(\"[^\"\n]*\"|'[^'\n]*'|[^\]\s]+)[ \t]*\]", re.M)
"""A table header line, ``[name]`` or ``[[name]]``; group 1 the name as written."""

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def exists(path: str | Path) -> bool:
    """Whether ``path`` names something that exists; False (never an exception) for a name
    the system cannot even look up (too long, a NUL byte): the loader then says "not found".

    Parameters
    ----------
    path : str or Path
        A name a user gave.
    """
    try:
        os.stat(path)
    except (OSError, ValueError):
        return False
    return True


def check_regular(path: str | Path, what: str) -> os.stat_result:
    """Refuse anything but an existing regular file (symbolic links followed).

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file should be, for the message (e.g. "model file").

    Returns
    -------
    os.stat_result
        The file's status (``st_size`` its size in bytes).

    Raises
    ------
    StationError
        ``PATH: WHAT not found`` or ``PATH: is a folder, not a WHAT`` (a FIFO, a device, a
        socket likewise), or it cannot be examined; ``file`` is set.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise StationError(f"{path}: {what} not found", file=path) from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the name
        raise StationError(f"{path}: cannot read the {what}: {getattr(exc, 'strerror', None) or exc}",
                           file=path) from None
    if not stat.S_ISREG(st.st_mode):
        kind = next((name for test, name in _KINDS if test(st.st_mode)), "not a regular file")
        raise StationError(f"{path}: is {kind}, not a {what} (a regular file)", file=path)
    return st


def read_text(path: str | Path, what: str, max_bytes: int = MAX_TOML_BYTES) -> str:
    """A small text file's contents: a regular file of at most ``max_bytes``, UTF-8.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file should be, for the message (e.g. "compensator file").
    max_bytes : int
        The largest size read, bytes.

    Returns
    -------
    str
        The text (universal newlines not applied: ``\\r\\n`` stays).

    Raises
    ------
    StationError
        As :func:`check_regular`; larger than ``max_bytes``; a byte that is not UTF-8
        (``PATH: line N: not UTF-8 text ...``, ``line`` set).
    """
    st = check_regular(path, what)
    if st.st_size > max_bytes:
        raise StationError(f"{path}: {st.st_size} bytes; a {what} is at most {max_bytes} bytes", file=path)
    try:
        with open(path, "rb") as fh:
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise StationError(f"{path}: cannot read the {what}: {exc.strerror or exc}", file=path) from None
    if len(data) > max_bytes:  # it grew since it was examined
        raise StationError(f"{path}: more than {max_bytes} bytes; a {what} is at most {max_bytes} bytes", file=path)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise StationError(f"{path}: line {line}: not UTF-8 text ({exc.reason} at byte {exc.start}); "
                           f"a {what} is UTF-8 TOML", file=path, line=line) from None


def _depth(value: Any) -> int:
    """Nesting depth of parsed TOML (a scalar 0, a table or array 1 + its deepest member)."""
    depth, level = 0, [value]
    while level:  # breadth-first: no recursion, whatever the file
        level = [v for item in level if isinstance(item, (dict, list))
                 for v in (item.values() if isinstance(item, dict) else item)]
        depth += 1
    return depth - 1


class TomlDoc(NamedTuple):
    """A TOML file read by :func:`load_toml`.

    Attributes
    ----------
    path : Path
        The file.
    text : str
        Its text.
    data : dict
        What ``tomllib`` made of it.
    """

    path: Path
    text: str
    data: dict[str, Any]

    def line_of(self, key: str, table: str | None = None) -> int | None:
        """The 1-based line where ``key`` is set (in ``[table]`` when given), None when not found.

        Parameters
        ----------
        key : str
            A key as written, bare or quoted (``n_elements``, ``"param:drive_c"``).
        table : str, optional
            The table the key is in (``gth`` for ``[gth]``; a dotted ``gth.num = ...`` is
            found too); without ``key`` in it, the table's header line.
        """
        text = self.text
        k = re.escape(key)
        assign = re.compile(rf"^[ \t]*(?:\"{k}\"|'{k}'|{k})[ \t]*=", re.M)
        headers = list(_HEADER.finditer(text))
        if table is None:
            m = assign.search(text, 0, headers[0].start() if headers else len(text))
        else:
            own = next((i for i, h in enumerate(headers) if h.group(1).strip("\"'") == table), None)
            m = None
            if own is not None:
                end = headers[own + 1].start() if own + 1 < len(headers) else len(text)
                m = assign.search(text, headers[own].end(), end) or headers[own]
            t = re.escape(table)
            m = m or re.search(rf"^[ \t]*(?:\"{t}\"|{t})[ \t]*\.[ \t]*(?:\"{k}\"|{k})[ \t]*=", text, re.M)
        return None if m is None else text.count("\n", 0, m.start()) + 1

    def error(self, key: str, what: str, table: str | None = None, index: int | None = None) -> StationError:
        """The one-line error about a field: ``PATH: line N: [TABLE].KEY[INDEX]: WHAT``.

        Parameters
        ----------
        key : str
            The field (as :meth:`line_of`).
        what : str
            What is wrong and what was expected.
        table : str, optional
            The table the field is in.
        index : int, optional
            The element of an array field at fault.
        """
        line = self.line_of(key, table)
        where = f" line {line}:" if line else ""
        name = key_text(key) if table is None else f"[{key_text(table)}].{key_text(key)}"
        if index is not None:
            name += f"[{index}]"
        what = one_line(what)  # whatever a key held
        if len(what) > MAX_MESSAGE:
            what = what[:MAX_MESSAGE - 3] + "..."
        return StationError(f"{self.path}:{where} {name}: {what}", file=self.path, line=line, key=name)


def load_toml(path: str | Path, what: str, max_bytes: int = MAX_TOML_BYTES, max_depth: int = MAX_DEPTH) -> TomlDoc:
    """Read a small TOML file, bounded (see the module docstring): the one reading of every
    model, parameter-set, compensator and config file.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file should be, for the message (e.g. "model file").
    max_bytes : int
        The largest size read, bytes.
    max_depth : int
        The deepest nesting of tables and arrays accepted.

    Returns
    -------
    TomlDoc
        The path, the text and the parsed document.

    Raises
    ------
    StationError
        As :func:`read_text`; not valid TOML (``tomllib``'s message names the line and
        column); nested deeper than ``max_depth``.
    """
    path = Path(path)
    text = read_text(path, what, max_bytes)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StationError(f"{path}: not valid TOML: {exc}", file=path) from None
    except RecursionError:
        raise StationError(f"{path}: not a {what}: tables or arrays nested too deeply "
                           f"(at most {max_depth} levels)", file=path) from None
    depth = _depth(data)
    if depth > max_depth:
        raise StationError(f"{path}: not a {what}: tables or arrays nested {depth} levels deep "
                           f"(at most {max_depth})", file=path)
    return TomlDoc(path, text, data)
