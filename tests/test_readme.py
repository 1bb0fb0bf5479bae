"""The README's examples (and the compensator file's in docs/compensator-files.md) stay true."""

import re
from pathlib import Path

from station.control import make_controller

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
COMPENSATOR_FILES = ROOT / "docs" / "compensator-files.md"


def test_readme_compensator_file_example_loads(tmp_path):
    block = re.search(r"```toml\n(.*?)```", COMPENSATOR_FILES.read_text(), re.S).group(1)
    path = tmp_path / "example.toml"
    path.write_text(block)
    ctrl = make_controller(str(path))
    assert ctrl.limit == 200.0 and ctrl.ga is None
    # Tustin of (31.4159 s + 986.96)/(s + 125.66) at 0.002 s keeps the DC gain 986.96/125.66
    assert abs(sum(ctrl.gth.num) / sum(ctrl.gth.den) - 986.96 / 125.66) < 1e-9


def test_readme_starts_with_the_two_setup_commands():
    first_block = README.read_text().split("```")[1]
    lines = [line for line in first_block.splitlines() if line.strip() and not line.startswith("sh")]
    assert lines[0].endswith(".venv/bin/station step")
    assert ".venv/bin/python -m pytest -n 2 -m 'not realtime'" in lines[1]  # both cores for the rest,
    assert lines[1].endswith(".venv/bin/python -m pytest -m realtime")     # then the real-time runs alone
