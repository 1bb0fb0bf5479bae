"""One answer per input: a pure function's recent results kept by the content of its arguments.

An audit asks the same identification more than once: a column check identifies a log, then
each rewrite of it, and a rewrite's own rewrites return to the log itself
(:func:`station.logged.columns.check_columns`). :func:`functools.lru_cache` keys on hashable
arguments only; numpy arrays are not, so the key here is a digest of the arguments' content
(an array's dtype, shape and every value; anything else pickled). Equal content is the same
input; a list and an array of the same numbers are not (a second computation, never a wrong
answer).
"""

from __future__ import annotations

import collections
import functools
import hashlib
import io
import pickle
import threading

import numpy as np

MAXSIZE = 16
"""Results kept per function (a few logs' rewrites)."""


def by_content(maxsize: int = MAXSIZE):
    """Decorate a pure function to keep its last ``maxsize`` results, keyed by its arguments'
    content.

    Parameters
    ----------
    maxsize : int
        Results kept; the least recently used goes first.

    Returns
    -------
    callable
        The decorator. The decorated function has ``cache_clear()`` and ``cache_info()``
        (hits, misses, size), as :func:`functools.lru_cache`'s. Arguments that cannot be
        pickled are computed every time. The result is shared between calls: the function's
        results must not be changed in place by their users (a stateful controller in one is
        reset by each user before it runs: :func:`station.control.rerun.replay_commands`).
    """
    def decorate(fn):
        kept: collections.OrderedDict[bytes, object] = collections.OrderedDict()
        lock = threading.Lock()
        counts = {"hits": 0, "misses": 0}

        @functools.wraps(fn)
        def wrapper(*args, **kwargs):
            try:
                key = _digest(args, kwargs)
            except (pickle.PicklingError, TypeError, AttributeError):
                return fn(*args, **kwargs)
            with lock:
                if key in kept:
                    kept.move_to_end(key)
                    counts["hits"] += 1
                    return kept[key]
                counts["misses"] += 1
            result = fn(*args, **kwargs)
            with lock:
                kept[key] = result
                while len(kept) > maxsize:
                    kept.popitem(last=False)
            return result

        def cache_clear() -> None:
            with lock:
                kept.clear()
                counts.update(hits=0, misses=0)

        def cache_info() -> dict:
            with lock:
                return {**counts, "size": len(kept)}

        wrapper.cache_clear, wrapper.cache_info = cache_clear, cache_info
        return wrapper
    return decorate


def _digest(args: tuple, kwargs: dict) -> bytes:
    """The arguments' content: an array's dtype, shape and bytes read in place (a long log's
    columns are not copied), anything else pickled."""
    h = hashlib.blake2b()
    arrays = []

    def persistent_id(obj):  # pickle's hook: an array is hashed beside the pickle, not copied into it
        if isinstance(obj, np.ndarray) and obj.dtype != object:
            arrays.append(obj)
            return len(arrays) - 1
        return None

    buffer = io.BytesIO()
    pickler = pickle.Pickler(buffer, protocol=5)
    pickler.persistent_id = persistent_id
    pickler.dump((args, sorted(kwargs.items())))
    h.update(buffer.getvalue())
    for a in arrays:
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(memoryview(np.ascontiguousarray(a)).cast("B"))
    return h.digest()
