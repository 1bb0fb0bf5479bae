"""Every file the station writes: one rule, checked before anything starts, and files that
are written whole or not at all (docs/logs.md "Output files").

Where: a file a command names itself (a run log's default name, a figure named after a
log) goes into the output folder, ``--out-dir``: by default ``station.toml``'s ``out_dir``,
else ``runs/`` in the working folder (:data:`DEFAULT_OUT_DIR`); a file the user names
(``--out``, ``--png``, ``--json``, a ``--report`` folder, ...) goes where they say.

The rule, the same for every command:

0. Every output's name can be made: no part of its path longer than the file system allows
   (with room for the temporary name of rule 4), the whole path within its limit, no NUL byte.
1. No output is an input of the same command, and no two outputs are the same file.
   Paths are compared as files: an existing file by its device and inode (so a hard link
   or a symbolic link to an input is that input), a new one by its resolved path.
   Derived files count: the figure ``station step`` draws beside its log, the pages and
   figures of a report folder, the figures ``station compare`` names after its logs.
2. An existing file is replaced only with ``--force`` (every command that writes has it).
3. Names a command makes up are unique within the command (:func:`unique_names`).
4. A file is written under a temporary name in its own folder (a hidden
   ``.NAME.XXXX.part``) and renamed over its target (:func:`os.replace`) once it is
   complete and on disk, so a full disk, an error or a signal leaves the old file or no
   file, never a part of one. A device (``/dev/null``, ``/dev/full``) is written in place.

The run log is the exception to 4: ``station step`` streams it while the run goes (a run
must be on disk while it runs, for a crash or a power cut), so a log cut by a full disk
keeps the rows that fit (the run log writer saves the rest to a rescue file). Rules 1 and
2 hold for it too: it is never created over an input or another output, and over an
existing file only with ``--force``.

:func:`check_outputs` applies rules 0, 1 and 2 and checks that every folder can be written,
before a command starts its work; :class:`Transaction` writes a command's files by rule
4, renaming them into place together at the end.
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, BinaryIO, NamedTuple

from station.errors import StationError
from station.jsonio import to_jsonable

FORCE_HELP = "replace output files that exist (never an input of the command)"
"""``--force``'s help, the same in every command that writes files."""

PART_SUFFIX = ".part"
"""Suffix of the temporary file a :class:`Transaction` writes before renaming it (hidden: it
starts with a dot)."""

PART_EXTRA_BYTES = 1 + 1 + 8 + len(PART_SUFFIX)
"""How much longer the temporary name is than its target's (``.NAME.XXXXXXXX.part``), bytes: an
output's name must leave room for it."""

DEFAULT_OUT_DIR = "runs"
"""The output folder when neither ``--out-dir`` nor ``station.toml``'s ``out_dir`` names one."""


class Output(NamedTuple):
    """A file a command will write.

    Attributes
    ----------
    option : str
        How messages name it: the option (``"--json"``) or the derived file
        (``"the figure beside --out"``).
    path : str, Path or None
        The file (None: not asked for; ignored).
    remedy : str
        What else the user can do when the file exists, after "use --force to replace it, or"
        (default "another name"; a file named in the output folder: another folder).
    """

    option: str
    path: str | Path | None
    remedy: str = "another name"


class Input(NamedTuple):
    """A file a command reads (an output may never be one).

    Attributes
    ----------
    label : str
        How messages name it (``"RUN"``, ``"--model"``).
    path : str, Path or None
        The file (None, a missing path or a built-in name: nothing to protect; ignored).
    """

    label: str
    path: str | Path | None


def _identity(path: Path) -> tuple:
    """What makes two paths the same file: device and inode when it exists, else its resolved path."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return ("new", os.path.normcase(os.path.realpath(path)))
    return ("file", st.st_dev, st.st_ino)


def _kind(path: Path) -> str:
    """"file", "folder", "device" (anything else that exists: a device, a pipe) or "none"."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return "none"
    return "file" if stat.S_ISREG(mode) else "folder" if stat.S_ISDIR(mode) else "device"


def _probe_folder(folder: Path, what: str, probed: dict[Path, None]) -> None:
    """Refuse a folder that cannot be created or written: a real probe (a temporary file in
    the nearest existing folder), as permission bits say nothing for root or read-only mounts."""
    existing = folder
    while _kind(existing) == "none" and existing.parent != existing:
        existing = existing.parent
    if existing in probed:
        return
    if _kind(existing) != "folder":
        raise StationError(f"{what}: {existing} is a file, not a folder")
    import tempfile  # lazy: start-up time (the CLI imports this module before it can answer a signal)

    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        raise StationError(f"{what}: {existing} is not writable ({exc.strerror or exc})") from None
    probed[existing] = None


def _limit(folder: Path, name: str, default: int) -> int:
    try:
        value = os.pathconf(folder, name)
    except (OSError, ValueError):
        return default
    return default if value is None or value <= 0 else value


def _short(text: str, width: int = 48) -> str:
    return text if len(text) <= width else text[:width - 3] + "..."


def check_name(path: str | Path, what: str, written_whole: bool = True) -> None:
    """Refuse an output name the file system cannot hold (rule 0), before any work: a NUL byte,
    a part of the path longer than the folder's name limit (``NAME_MAX``, 255 bytes on most
    file systems; less :data:`PART_EXTRA_BYTES` for a file written under a temporary name), or a
    whole path past ``PATH_MAX``.

    Parameters
    ----------
    path : str or Path
        The output (a file or a folder; it need not exist).
    what : str
        How messages name it (the option or the derived file, and the path).
    written_whole : bool
        The last part is a file written through a :class:`Transaction` (its temporary name is
        longer); False for a folder.

    Raises
    ------
    StationError
        ``WHAT: ...`` saying which part is too long, by how much, and the limit.
    """
    text = os.fspath(path)
    if "\0" in text:
        raise StationError(f"{what}: holds a NUL byte; a file name cannot")
    existing = Path(os.path.abspath(text))
    while _kind(existing) == "none" and existing.parent != existing:
        existing = existing.parent
    name_max = _limit(existing, "PC_NAME_MAX", 255)
    parts = Path(text).parts
    for i, part in enumerate(parts):
        size = len(os.fsencode(part))
        last = i == len(parts) - 1
        room = name_max - (PART_EXTRA_BYTES if last and written_whole else 0)
        if size > room:
            extra = (f" (it is written first under a temporary name {PART_EXTRA_BYTES} bytes longer)"
                     if last and written_whole else "")
            raise StationError(f"{_short(what)}: the name {_short(part)!r} is {size} bytes; a "
                               f"{'file' if last and written_whole else 'folder or file'} name here is at most "
                               f"{room} bytes{extra}")
    path_max = _limit(existing, "PC_PATH_MAX", 4096)
    size = len(os.fsencode(os.path.abspath(text))) + (PART_EXTRA_BYTES if written_whole else 0)
    if size >= path_max:
        raise StationError(f"{_short(what)}: the path is {size} bytes; at most {path_max - 1} here")


def is_device(path: str | Path) -> bool:
    """True for an existing path that is neither a regular file nor a folder (``/dev/null``, a pipe).

    Parameters
    ----------
    path : str or Path
        Any path.
    """
    return _kind(Path(path)) == "device"


def check_folder(folder: str | Path | None, option: str) -> None:
    """Refuse an output folder that is a file or cannot be created or written.

    Parameters
    ----------
    folder : str, Path or None
        The folder (None: nothing to check); it need not exist yet.
    option : str
        The option that names it, for the message.

    Raises
    ------
    StationError
        ``OPTION FOLDER: ...`` naming what is in the way.
    """
    if folder is not None:
        check_name(folder, f"{option} {folder}", written_whole=False)
        if _kind(Path(folder)) not in ("folder", "none"):
            raise StationError(f"{option} {folder}: is a file, expected a folder")
        _probe_folder(Path(folder), f"{option} {folder}", {})


def check_outputs(outputs: Iterable[Output | tuple], inputs: Iterable[Input | tuple] = (),
                  force: bool = False, parser=None) -> None:
    """Refuse, before anything starts, outputs that would destroy an input, each other or an
    existing file, or that cannot be written (the module's rules 1 and 2).

    Parameters
    ----------
    outputs : iterable of Output or (option, path[, remedy])
        Every file the command will write, derived files included; None paths are skipped.
    inputs : iterable of Input or (label, path)
        Every file the command reads; paths that are not existing files are skipped.
    force : bool
        ``--force``: an existing file may be replaced (an input never).
    parser : argparse.ArgumentParser, optional
        A script's parser: a refusal is then its one-line usage error (exit 2).

    Raises
    ------
    StationError
        One line starting with the option and path: a name the file system cannot hold, the
        output is a folder, an input, the same file as another output, an existing file
        without ``force`` (the message says what else to do: the output's ``remedy``), an
        existing file that is not writable, or in a folder that cannot be created or written.
    """
    if parser is not None:
        try:
            return check_outputs(outputs, inputs, force)
        except StationError as exc:
            parser.error(str(exc))
    protected = []
    for label, p in inputs:
        if p is not None and _kind(Path(p)) in ("file", "device"):
            protected.append((label, Path(p), _identity(Path(p))))
    claimed: list[tuple[str, Path, tuple]] = []
    probed: dict[Path, None] = {}
    for out in outputs:
        option, p, remedy = (tuple(out) + ("another name",))[:3]
        if p is None:
            continue
        path = Path(p)
        what = f"{option} {path}"
        kind = _kind(path)
        if kind == "none":
            check_name(path, what)
        if kind == "folder":
            raise StationError(f"{what}: is a folder, expected a file")
        ident = _identity(path)
        for label, ipath, iid in protected:
            if ident == iid:
                also = "" if os.path.abspath(ipath) == os.path.abspath(path) else f" {ipath}"
                raise StationError(f"{what}: is an input of this command ({label}{also}); "
                                   "an output never replaces an input")
        for other, opath, oid in claimed:
            if ident == oid:
                raise StationError(f"{what}: is the same file as {other} {opath}; each output needs its own file")
        claimed.append((option, path, ident))
        if kind == "device":  # /dev/null and the like are written in place: nothing to keep
            if not os.access(path, os.W_OK):
                raise StationError(f"{what}: is not writable")
            continue
        if kind == "file":
            if not force:
                raise StationError(f"{what}: exists; use --force to replace it, or {remedy}")
            if not os.access(path, os.W_OK):
                raise StationError(f"{what}: exists and is read-only")
        _probe_folder(path.parent, f"{what}: its folder", probed)


def unique_names(names: Sequence[str]) -> list[str]:
    """``names`` with ``-2``, ``-3``, ... added to repeats so that no two are equal.

    The first of equal names keeps it; a repeat gets the smallest suffix that is neither
    taken nor one of the given names. The result depends only on ``names`` and their order.

    Parameters
    ----------
    names : sequence of str
        Names a command made up (e.g. figure stems after its logs' stems).

    Returns
    -------
    list of str
        Same length and order.
    """
    given, used, out = set(names), set(), []
    for name in names:
        new, k = name, 2
        while new in used:
            new, k = f"{name}-{k}", k + 1
            if new in given:
                new = name  # a later name owns it: keep looking
        used.add(new)
        out.append(new)
    return out


def _new_file_mode() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


_NEW_FILE_MODE = _new_file_mode()  # read once, at import (os.umask can only be read by setting it)


def part_file(target: Path) -> tuple[int, Path]:
    """Create the temporary file that will become ``target``: beside it, hidden, with the mode
    ``target`` has (a new file: what the umask gives, as ``open`` would).

    Parameters
    ----------
    target : Path
        The file to write (its folder exists).

    Returns
    -------
    fd : int
        Open for writing; the caller closes it.
    path : Path
        The temporary file, to rename over ``target`` (:func:`os.replace`) or remove.

    Raises
    ------
    OSError
        It cannot be created.
    """
    import tempfile  # lazy: start-up time (tempfile)

    mode = stat.S_IMODE(os.stat(target).st_mode) if _kind(target) == "file" else _NEW_FILE_MODE
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=PART_SUFFIX, dir=target.parent)
    try:
        os.fchmod(fd, mode)
    except OSError:
        os.close(fd)
        os.unlink(name)
        raise
    return fd, Path(name)


class Transaction:
    """Files written under temporary names and renamed into place together (rule 4).

    Use as a context manager: on a normal exit every file is renamed over its target
    (:func:`os.replace`); on an exception (a write error, a signal) every temporary file
    is removed, with the folders the transaction created, and nothing is renamed.

    Examples
    --------
    >>> with Transaction() as tx:                                   # doctest: +SKIP
    ...     tx.write("result.json", text, "the JSON")
    ...     with tx.open("figure.png", "the figure") as fh:
    ...         fig.savefig(fh, format="png")
    """

    def __init__(self) -> None:
        self._pending: list[tuple[Path, Path]] = []
        self._made: list[Path] = []
        self.written: list[Path] = []

    def _mkdir(self, folder: Path) -> None:
        missing = []
        while _kind(folder) == "none" and folder.parent != folder:
            missing.append(folder)
            folder = folder.parent
        for f in reversed(missing):
            f.mkdir()
            self._made.append(f)

    @contextmanager
    def open(self, path: str | Path, what: str = "") -> Iterator[BinaryIO]:
        """A binary file to write ``path``'s content into: a temporary file beside it.

        Parameters
        ----------
        path : str or Path
            The target (a symbolic link's target is replaced, the link kept).
        what : str, optional
            What the file is, for the message (e.g. "the figure").

        Yields
        ------
        file object
            Binary, writable; closed and flushed to disk when the block ends.

        Raises
        ------
        StationError
            ``PATH: cannot write WHAT: REASON`` (full disk, read-only folder, ...); the
            temporary file is gone.
        """
        target = Path(os.path.realpath(path))
        label = f"{path}: cannot write{' ' + what if what else ''}"
        if _kind(target) == "device":  # written in place: there is no file to keep whole
            try:
                with open(target, "wb") as fh:
                    yield fh
            except OSError as exc:
                raise StationError(f"{label}: {exc.strerror or exc}") from None
            return
        tmp = None
        try:
            self._mkdir(target.parent)
            fd, tmp = part_file(target)
            self._pending.append((tmp, target))
            with open(fd, "wb") as fh:
                yield fh
                fh.flush()
                os.fsync(fh.fileno())
        except OSError as exc:
            self._discard(tmp)
            raise StationError(f"{label}: {exc.strerror or exc}") from None
        except BaseException:
            self._discard(tmp)
            raise

    def write(self, path: str | Path, data: bytes | str, what: str = "") -> None:
        """Write ``data`` to ``path`` (renamed into place at commit).

        Parameters
        ----------
        path : str or Path
            The target file.
        data : bytes or str
            Its whole content (text is written as UTF-8).
        what : str, optional
            What the file is, for the message.

        Raises
        ------
        StationError
            The file cannot be written (see :meth:`open`).
        """
        with self.open(path, what) as fh:
            fh.write(data.encode("utf-8") if isinstance(data, str) else data)

    def write_json(self, path: str | Path, doc: Any, what: str = "the JSON", indent: int = 1) -> None:
        """Write ``doc`` as JSON (one trailing newline) to ``path``: NaN and infinities as null,
        numpy numbers and arrays as JSON numbers and lists (:func:`station.jsonio.to_jsonable`,
        the one conversion), never the invalid ``NaN`` of ``json.dumps``.

        Parameters
        ----------
        path : str or Path
            The target file.
        doc : JSON-able
            What to write.
        what : str
            What the file is, for the message.
        indent : int
            JSON indentation.

        Raises
        ------
        StationError
            The file cannot be written (see :meth:`open`).
        """
        self.write(path, json.dumps(to_jsonable(doc), indent=indent, allow_nan=False) + "\n", what)

    def _discard(self, tmp: Path | None) -> None:
        if tmp is None:
            return
        self._pending = [(t, target) for t, target in self._pending if t != tmp]
        try:
            tmp.unlink()
        except OSError:
            pass

    def commit(self) -> list[Path]:
        """Rename every written file into place; returns the targets.

        Raises
        ------
        StationError
            A rename failed (the files not yet renamed are removed).
        """
        try:
            while self._pending:
                tmp, target = self._pending[0]
                os.replace(tmp, target)
                self._pending.pop(0)
                self.written.append(target)
        except OSError as exc:
            self.abort()
            raise StationError(f"{target}: cannot write: {exc.strerror or exc}") from None
        self._made.clear()
        return list(self.written)

    def abort(self) -> None:
        """Remove every temporary file and the folders this transaction created (when empty)."""
        for tmp, _ in self._pending:
            try:
                tmp.unlink()
            except OSError:
                pass
        self._pending.clear()
        for folder in reversed(self._made):
            try:
                folder.rmdir()
            except OSError:
                pass
        self._made.clear()

    def __enter__(self) -> Transaction:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.abort()


def write_bytes(path: str | Path, data: bytes, what: str = "") -> Path:
    """Write one file whole or not at all (a :class:`Transaction` of one file).

    Parameters
    ----------
    path : str or Path
        The target file.
    data : bytes
        Its whole content.
    what : str, optional
        What the file is, for the message.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    StationError
        ``PATH: cannot write WHAT: REASON``; the old file (if any) is unchanged.
    """
    with Transaction() as tx:
        tx.write(path, data, what)
    return Path(path)


def write_json(path: str | Path, doc: Any, indent: int = 1) -> Path:
    """Write ``doc`` as JSON whole or not at all (``--json``).

    Parameters
    ----------
    path : str or Path
        The ``--json`` file.
    doc : JSON-able
        What to write.
    indent : int
        JSON indentation.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    StationError
        ``PATH: cannot write the JSON: REASON``; the old file (if any) is unchanged.
    """
    with Transaction() as tx:
        tx.write_json(path, doc, indent=indent)
    return Path(path)


# what the station writes that is not a run log, by suffix (station survey lists them apart)
WRITTEN_SUFFIXES = {".png": "a figure (PNG)", ".json": "a JSON report", ".rrd": "a rerun recording",
                    ".html": "a report page (HTML)", ".toml": "a model or compensator file (TOML)",
                    PART_SUFFIX: "an unfinished output (.part)"}
"""Suffixes of the files the station writes besides run logs, and what each is."""
