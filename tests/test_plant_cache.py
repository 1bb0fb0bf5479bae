"""The on-disk cache of the plant's modal form (station.plant.diskcache): same bits, robust."""

from __future__ import annotations

import os

import numpy as np
import pytest

from station.plant import load_params
from station.plant import modal
from station.plant.diskcache import cache_key, cached_arrays


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("STATION_NO_CACHE", raising=False)
    modal.linear_form.cache_clear()
    yield tmp_path / "station"
    modal.linear_form.cache_clear()


def _same(a, b):
    for x, y in zip(a, b):
        x, y = np.asarray(x), np.asarray(y)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


@pytest.mark.parametrize("substeps", [0, 10])
def test_a_cached_form_is_the_computed_one_bit_for_bit(cache, substeps):
    params = load_params("tmm-fit")
    fresh = modal._linear_form(params, 4, 0.002, substeps)
    first = modal.linear_form(params, 4, 0.002, substeps)  # computed and stored
    assert len(list(cache.glob("linear-form-*.npz"))) == 1
    modal.linear_form.cache_clear()
    again = modal.linear_form(params, 4, 0.002, substeps)  # read back
    _same(fresh, first)
    _same(fresh, again)
    assert type(again.gw_v) is float and type(again.substeps) is int


def test_the_key_follows_every_input():
    params = load_params("tmm-fit")
    base = (*vars(params).values(), 4, 0.002, 0)
    keys = {cache_key("linear-form", base),
            cache_key("linear-form", (*vars(params).values(), 5, 0.002, 0)),
            cache_key("linear-form", (*vars(params).values(), 4, 0.002 * (1 + 1e-16) + 1e-18, 0)),
            cache_key("linear-form", (*vars(params).values(), 4, 0.002, 10)),
            cache_key("linear-form", (params.mu * (1 + 2**-52), *list(vars(params).values())[1:], 4, 0.002, 0))}
    assert len(keys) == 5


def test_a_corrupt_entry_is_computed_again_and_rewritten(cache):
    calls = []

    def compute():
        calls.append(1)
        return {"x": np.arange(3.0)}

    cached_arrays("test", (1,), compute)
    path = next(cache.glob("test-*.npz"))
    path.write_bytes(b"not an npz at all")
    got = cached_arrays("test", (1,), compute)
    assert np.array_equal(got["x"], np.arange(3.0)) and len(calls) == 2
    got = cached_arrays("test", (1,), compute)  # the rewritten entry is read
    assert len(calls) == 2


def test_an_unwritable_cache_folder_costs_only_the_time(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder should go")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    got = cached_arrays("test", (2,), lambda: {"x": np.ones(2)})
    assert np.array_equal(got["x"], np.ones(2))


def test_station_no_cache_turns_it_off(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("STATION_NO_CACHE", "1")
    cached_arrays("test", (3,), lambda: {"x": np.ones(2)})
    assert not (tmp_path / "station").exists()


def test_in_bulk_forms_are_computed_not_stored(tmp_path, monkeypatch):
    # a diagnosis builds thousands of forms: none is read from or written to the disk
    from station.plant.diskcache import bulk, use_disk

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("STATION_NO_CACHE", raising=False)
    modal.linear_form.cache_clear()
    params = load_params("tmm-fit")
    with bulk():
        assert not use_disk()
        _same(modal.linear_form(params, 4, 0.002, 10), modal._linear_form(params, 4, 0.002, 10))
    assert use_disk()
    assert not list(tmp_path.rglob("*.npz"))
    modal.linear_form.cache_clear()
