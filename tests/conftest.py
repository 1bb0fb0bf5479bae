"""Shared fixtures: where the rig logs and protocol vectors live.

Tests that need `../shared` (rig logs, protocol vectors) use the `shared_dir` or
`rig_data` fixtures; they skip with a clear reason when the folder is absent, except
when STATION_REQUIRE_SHARED=1 (CI), where a missing folder is a failure.
"""

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _require(path: Path, what: str) -> Path:
    if path.exists():
        return path
    msg = f"{what} not found at {path} (set STATION_RIG_DATA or put ../shared beside the repo)"
    if os.environ.get("STATION_REQUIRE_SHARED") == "1":
        pytest.fail(msg + "; STATION_REQUIRE_SHARED=1 forbids skipping")
    pytest.skip(msg)


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """The shared folder (DESIGN.md, spec/, data/) beside the repository."""
    return _require(REPO.parent / "shared", "shared folder")


@pytest.fixture(scope="session")
def rig_data() -> Path:
    """Folder of the rig's logs: $STATION_RIG_DATA or ../shared/data/rig."""
    env = os.environ.get("STATION_RIG_DATA")
    path = Path(env) if env else REPO.parent / "shared" / "data" / "rig"
    return _require(path, "rig data")


@pytest.fixture(scope="session")
def v1_vectors(shared_dir: Path) -> dict:
    """The protocol v1 test vectors (spec/protocol-v1-vectors.json)."""
    import json

    return json.loads(_require(shared_dir / "spec" / "protocol-v1-vectors.json", "protocol vectors").read_text())


@pytest.fixture(autouse=True)
def _no_user_station_config(monkeypatch, tmp_path_factory):
    """A developer's ~/.config/station/station.toml must not change what the tests run
    (station.config reads $XDG_CONFIG_HOME/station/station.toml)."""
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path_factory.getbasetemp() / "no-user-config"))


REALTIME_MODULES = {"test_failsafe.py", "test_catch_up.py", "test_faults.py", "test_bench_loop.py",
                    "test_bench_tick.py", "test_sim_pty.py", "test_firmware_fil.py", "test_sim_reproducible.py",
                    "test_loop.py", "test_link.py"}
"""Modules whose tests time a real-time run over a pty or a simulated device: marked
``realtime``, so the README's test command runs them alone after the others (which run on
both cores, ``-n 2``): a second worker's load would be the machine, not the station."""


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: takes minutes (e.g. the blind diagnosis tests); still run in CI")
    config.addinivalue_line("markers", "realtime: times a real-time run; run alone (tests/conftest.py)")


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.path.name in REALTIME_MODULES:
            item.add_marker(pytest.mark.realtime)


@pytest.fixture
def stall_watch():
    """Watch this try for a frozen machine (tests/stalls.py: the timing tests' rerun condition)."""
    from tests.stalls import try_started

    try_started()


@pytest.fixture
def device_factory():
    """Start scripted devices on ptys (tests/scripted_device.py): ``make(**options)``; all are
    closed after the test."""
    from tests.scripted_device import LIVE, ScriptedDevice

    LIVE.clear()
    made = []

    def make(**kw):
        dev = ScriptedDevice(**kw).start()
        made.append(dev)
        return dev

    yield make
    for dev in made:
        dev.close()
