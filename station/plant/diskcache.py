"""An on-disk cache of the plant's derived arrays (the modal form), so a run starts at once.

Building a model's modal form needs scipy (seconds to import) and an eigen-decomposition;
its result depends only on the parameter values, the element count, dt, the sub-steps, the
plant's own code and the numerical libraries. :func:`cached_arrays` keeps such results in
the user's cache folder (``$XDG_CACHE_HOME/station``, default ``~/.cache/station``; off
with ``STATION_NO_CACHE=1``), one ``.npz`` per key, named by a SHA-256 of the key, of every
source file of :mod:`station.plant` and of the numpy and scipy versions: an edited plant
module or an upgraded library never reads an old entry. The arrays come back bit for bit
as they were computed. A missing, corrupt or foreign entry is computed again (and
rewritten); a cache folder that cannot be written costs only the time (nothing is raised).

(joblib.Memory would hash the function's own code, not the modules it calls; here any
change under ``station/plant`` invalidates every entry.)
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import logging
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

logger = logging.getLogger("station.plant.cache")
"""DEBUG: cache hits, misses and entries that could not be read or written."""

FORMAT = "station-plant-cache 1"
"""Part of every key: bump it when what an entry holds changes."""


def cache_dir() -> Path | None:
    """The cache folder: ``$XDG_CACHE_HOME/station`` (default ``~/.cache/station``), or None
    when ``STATION_NO_CACHE`` is set to anything but "" or "0"."""
    if os.environ.get("STATION_NO_CACHE", "") not in ("", "0"):
        return None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "station"


@functools.lru_cache(maxsize=1)
def _code_digest() -> bytes:
    """SHA-256 of the plant's sources and of the numpy / scipy versions (read, not imported)."""
    h = hashlib.sha256(FORMAT.encode())
    for path in sorted(Path(__file__).resolve().parent.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(np.__version__.encode())
    spec = importlib.util.find_spec("scipy")
    if spec is not None and spec.origin:
        version = Path(spec.origin).with_name("version.py")
        h.update(version.read_bytes() if version.is_file() else b"?")
    return h.digest()


def cache_key(kind: str, parts: tuple) -> str:
    """The file name of an entry: ``<kind>-<sha256 of the parts and the code>.npz``.

    Parameters
    ----------
    kind : str
        What is cached (e.g. "linear-form"), a file-name-safe word.
    parts : tuple
        Everything the result depends on besides the code: floats are taken by their
        exact value (``float.hex``), everything else by ``repr``.
    """
    h = hashlib.sha256(_code_digest())
    for part in parts:
        h.update((part.hex() if isinstance(part, float) else repr(part)).encode())
        h.update(b"\x00")
    return f"{kind}-{h.hexdigest()[:32]}.npz"


_BULK = 0  # how many bulk() blocks are open (threads of one process share it)


@contextlib.contextmanager
def bulk() -> Iterator[None]:
    """Within: forms are computed, never read from or written to the disk cache.

    The disk cache serves start-up (a warm ``station step`` reads its model's form instead
    of importing scipy). A diagnosis builds thousands of forms (every fitted drive damping
    is a new one): reading a small form's ``.npz`` costs about 2.5 ms where computing it,
    scipy loaded, costs about 0.5 ms (4 elements), and storing them all filled the disk (it
    had grown to 120 000 files, 1.8 GB). The diagnosis (:func:`station.diagnosis.diagnose`,
    the sessions) runs inside this block.
    """
    global _BULK
    _BULK += 1
    try:
        yield
    finally:
        _BULK -= 1


def use_disk() -> bool:
    """False inside :func:`bulk`: the caller computes instead of consulting the disk cache."""
    return _BULK == 0


def cached_arrays(kind: str, parts: tuple, compute: Callable[[], dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """``compute()``'s arrays, from the cache when an entry for ``(kind, parts)`` is there.

    Parameters
    ----------
    kind, parts
        As :func:`cache_key`.
    compute : callable
        Returns a dict of name -> numpy array (numbers, no objects); called on a miss.

    Returns
    -------
    dict of str to numpy.ndarray
        The same names, dtypes, shapes and bits as ``compute()`` returns.
    """
    folder = cache_dir()
    if folder is None:
        return compute()
    path = folder / cache_key(kind, parts)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
        logger.debug("cache hit %s", path)
        return arrays
    except FileNotFoundError:
        logger.debug("cache miss %s", path)
    except Exception as exc:  # noqa: BLE001 - a corrupt or foreign entry: compute it again
        logger.debug("cache entry %s unreadable (%s): computed again", path, exc)
    arrays = compute()
    _store(path, arrays)
    return arrays


def _store(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write an entry atomically (a temporary file renamed over it); failures are only logged."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".npz")
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
        tmp = None
    except OSError as exc:
        logger.debug("cache entry %s not written: %s", path, exc)
    finally:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
