"""Reading the files the station is given, bounded: one way for every kind.

Model files, parameter sets, compensator files and ``station.toml`` are small TOML files
(:func:`load_toml`); diagnosis JSONs are small JSON files (:func:`load_json`); run logs are
large text files whose rows numpy reads. Every one of them is opened by :func:`open_regular`,
the one way the station opens a file it is given. Whatever a file holds, reading it ends
in bounded time and memory with either its contents or one
:class:`~station.errors.StationError` line naming the file (and the line and key where
known):

- only a regular file is read: a folder, a FIFO, a device such as ``/dev/zero`` or a
  socket is refused (opening a FIFO would block; ``/dev/zero`` never ends). The check is
  made on the opened file itself (opened without blocking, then examined), so nothing
  can be swapped in between the check and the read; a dangling or looping symbolic link
  is named as such;
- a TOML file larger than :data:`MAX_TOML_BYTES` is refused before it is read (and no
  more than that is ever read, should it grow meanwhile);
- the text is UTF-8; a byte that is not names its line;
- tables and arrays nest at most :data:`MAX_DEPTH` deep (``tomllib`` recurses once per
  level: a file nested thousands deep would end in a RecursionError); a JSON file's
  objects and arrays at most :data:`MAX_JSON_DEPTH`.

What the fields mean, their types and ranges is each loader's own (``station.plant.model``,
``station.plant.parameters``, ``station.control.designs``, ``station.config``); they name a
field's line with :meth:`TomlDoc.line_of`.

Imports only :mod:`station.errors`.
"""

from __future__ import annotations

import fcntl
import io
import json
import os
import re
import stat
import tomllib
import urllib.parse
from pathlib import Path
from typing import Any, BinaryIO, NamedTuple, TextIO

from station.errors import StationError, one_line

MAX_TOML_BYTES = 1_000_000
"""Largest TOML file read, bytes (a model, parameter set, compensator or config file is a few hundred)."""

MAX_DEPTH = 8
"""Deepest nesting of tables and arrays in a TOML file read (the formats need 2)."""

MAX_JSON_BYTES = 50_000_000
"""Largest JSON file read, bytes (a diagnosis JSON of many runs is a few hundred kB)."""

MAX_JSON_DEPTH = 64
"""Deepest nesting of objects and arrays in a JSON file read (a diagnosis JSON needs 5)."""

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
    """Whether ``path`` names something that is there, a symbolic link included even when it
    points nowhere or at itself (then the loader reading it says so, rather than the name being
    taken for something else: a built-in model, a controller kind); False, never an exception,
    for a name the system cannot even look up (too long, a NUL byte): the loader then says
    "not found".

    Parameters
    ----------
    path : str or Path
        A name a user gave.
    """
    try:
        os.lstat(path)
    except (OSError, ValueError):
        return False
    return True


def sim_model_file(url: str | None) -> str | None:
    """The model file a ``sim://?model=FILE`` port serves (None for another port, a port
    without ``model`` or a built-in model's name is returned as written: the caller's
    output check compares paths, and a name that is no file there matches none).

    A file the simulated rig reads is an input of the command that opens the port, like
    ``--model``'s: no output of that command may replace it.

    Parameters
    ----------
    url : str or None
        The port, as ``--port`` gave it.
    """
    if not isinstance(url, str) or not url.lower().startswith("sim://"):
        return None
    return dict(urllib.parse.parse_qsl(urllib.parse.urlsplit(url).query)).get("model")


def is_folder(path: str | Path) -> bool:
    """Whether ``path`` names a folder (symbolic links followed); False, never an exception, for
    a name the system cannot look up (too long, a NUL byte, a looping link).

    Parameters
    ----------
    path : str or Path
        A name a user gave.
    """
    try:
        return stat.S_ISDIR(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


def _refusal(path: str | Path, what: str, exc: BaseException) -> StationError:
    """The one line for a file that cannot be opened or examined."""
    if isinstance(exc, FileNotFoundError):
        if os.path.islink(path):
            return StationError(f"{path}: is a symbolic link to {os.readlink(path)}, which does not exist; "
                                f"expected a {what}", file=path)
        return StationError(f"{path}: {what} not found", file=path)
    if isinstance(exc, OSError) and exc.errno == getattr(os, "ELOOP", 40):
        return StationError(f"{path}: is a symbolic link that loops (it points back at itself); expected a {what}",
                            file=path)
    try:  # a socket cannot be opened at all (ENXIO): say what it is
        _refuse_kind(path, what, os.stat(path).st_mode)
    except StationError as kind:
        return kind
    except (OSError, ValueError):
        pass
    reason = getattr(exc, "strerror", None) or exc  # ValueError: a NUL byte in the name
    return StationError(f"{path}: cannot read the {what}: {reason}", file=path)


def _refuse_kind(path: str | Path, what: str, mode: int) -> None:
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _KINDS if test(mode)), "not a regular file")
        raise StationError(f"{path}: is {kind}, not a {what} (a regular file)", file=path)


def check_regular(path: str | Path, what: str) -> os.stat_result:
    """Refuse anything but an existing regular file (symbolic links followed), without opening it.

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
        socket likewise), a dangling or looping symbolic link, or it cannot be examined;
        ``file`` is set.
    """
    try:
        st = os.stat(path)
    except (OSError, ValueError) as exc:
        raise _refusal(path, what, exc) from None
    _refuse_kind(path, what, st.st_mode)
    return st


def open_regular(path: str | Path, what: str, text: bool = False, errors: str = "strict",
                 newline: str | None = "") -> BinaryIO | TextIO:
    """Open a file the station was given for reading, refusing anything but a regular file:
    the one way every loader opens its input.

    The file is opened without blocking (``O_NONBLOCK``: a FIFO with no writer opens at
    once) and then examined through the open descriptor, so the file read is the file
    checked; a regular file's descriptor is then made blocking again.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file should be, for the message (e.g. "run log").
    text : bool
        Text (UTF-8) instead of bytes.
    errors : str
        The text decoder's error handling (``text`` only).
    newline : str or None
        As :func:`open`'s (``text`` only; default "": lines as written).

    Returns
    -------
    file object
        Open for reading, binary or text; the caller closes it (a context manager).

    Raises
    ------
    StationError
        As :func:`check_regular`, or the file cannot be opened (permissions).
    """
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except (OSError, ValueError) as exc:
        raise _refusal(path, what, exc) from None
    try:
        _refuse_kind(path, what, os.fstat(fd).st_mode)
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
        raw = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    # utf-8-sig: a byte-order mark (Windows editors, Excel's "CSV UTF-8") is no part of the text
    return io.TextIOWrapper(raw, encoding="utf-8-sig", errors=errors, newline=newline) if text else raw


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
    try:
        with open_regular(path, what) as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > max_bytes:
                raise StationError(f"{path}: {size} bytes; a {what} is at most {max_bytes} bytes", file=path)
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise StationError(f"{path}: cannot read the {what}: {exc.strerror or exc}", file=path) from None
    if len(data) > max_bytes:  # it grew since it was examined
        raise StationError(f"{path}: more than {max_bytes} bytes; a {what} is at most {max_bytes} bytes", file=path)
    try:
        return data.decode("utf-8-sig")  # a byte-order mark (Windows editors) is no part of the text
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise StationError(f"{path}: line {line}: not UTF-8 text ({exc.reason} at byte {exc.start}); "
                           f"a {what} is UTF-8 text", file=path, line=line) from None


def _depth(value: Any) -> int:
    """Nesting depth of parsed TOML (a scalar 0, a table or array 1 + its deepest member)."""
    depth, level = 0, [value]
    while True:  # breadth-first: no recursion, whatever the file
        level = [item for item in level if isinstance(item, (dict, list))]
        if not level:
            return depth
        depth += 1  # (an empty table or array counts: [[]] is 2 deep)
        level = [v for item in level for v in (item.values() if isinstance(item, dict) else item)]


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


def json_depth(value: Any) -> int:
    """Nesting depth of parsed JSON or TOML (a scalar 0, an object or array 1 + its deepest
    member), counted without recursion whatever the document.

    Parameters
    ----------
    value : object
        What ``json.loads`` or ``tomllib`` made of a file.

    Returns
    -------
    int
        The depth.
    """
    return _depth(value)


def parse_json(text: str, where: str, max_depth: int = MAX_JSON_DEPTH) -> Any:
    """JSON text parsed, its nesting bounded: the one JSON reading of everything the station is
    given (diagnosis JSONs, a log header's metadata and end record).

    Parameters
    ----------
    text : str
        The JSON.
    where : str
        The file (and line) for the message.
    max_depth : int
        The deepest nesting of objects and arrays accepted.

    Returns
    -------
    object
        The parsed document, nested at most ``max_depth`` deep.

    Raises
    ------
    StationError
        Not JSON (the decoder's message: line and column), or nested deeper than
        ``max_depth`` (``json`` recurses once per level: thousands of levels would end in a
        RecursionError, in the decoder or in whatever walks the document next).
    """
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise StationError(f"{where}: not valid JSON ({exc})") from None
    except RecursionError:
        raise StationError(f"{where}: JSON nested too deeply (at most {max_depth} levels)") from None
    depth = _depth(doc)
    if depth > max_depth:
        raise StationError(f"{where}: JSON nested {depth} levels deep (at most {max_depth})")
    return doc


def load_json(path: str | Path, what: str, max_bytes: int = MAX_JSON_BYTES, max_depth: int = MAX_JSON_DEPTH) -> Any:
    """Read a JSON file, bounded: a regular UTF-8 file of at most ``max_bytes``, nested at most
    ``max_depth`` deep (:func:`read_text`, :func:`parse_json`).

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file should be, for the message (e.g. "diagnosis JSON").
    max_bytes : int
        The largest size read, bytes.
    max_depth : int
        The deepest nesting of objects and arrays accepted.

    Returns
    -------
    object
        The parsed document.

    Raises
    ------
    StationError
        As :func:`read_text` and :func:`parse_json`; ``file`` is set.
    """
    text = read_text(path, what, max_bytes)
    try:
        return parse_json(text, str(path), max_depth)
    except StationError as exc:
        raise StationError(str(exc), file=path) from None
