"""docs/your-turbine.md runs as written: every ``steamtwin`` line of its bash blocks, in order, in
one folder, on the shipped kit of an independent unit (issue 17, item 7).

A line ending in ``# exits N: ...`` must exit with N; every other line with 0.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from typer.testing import CliRunner

from steamtwin.cli.main import app

pytestmark = pytest.mark.slow  # 16 s of the full suite (2026-11-27): not in the quick loop

DOC = Path(__file__).resolve().parents[1] / "docs" / "your-turbine.md"
_EXPECTED = re.compile(r"#\s*exits\s+(\d+)")


def doc_commands() -> list[tuple[list[str], int]]:
    """(argv after 'steamtwin', expected exit code) of every command line in the bash blocks."""
    commands, inside = [], False
    for line in DOC.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            inside = line.strip() == "```bash"
            continue
        if inside and line.startswith("steamtwin "):
            command, _, comment = line.partition("#")
            expected = _EXPECTED.search("#" + comment) if comment else None
            commands.append((shlex.split(command)[1:], int(expected.group(1)) if expected else 0))
    return commands


def test_the_page_has_the_whole_chain_on_the_independent_unit():
    commands = [argv for argv, _ in doc_commands()]
    steps = [" ".join(argv[:2]) if argv[0] in ("turbine", "dcs", "rom") else argv[0]
             for argv in commands]
    chain = ["turbine derive", "turbine check", "turbine fit", "dcs check", "calibrate",
             "rom build", "validate"]
    positions = [steps.index(step) for step in chain]
    assert positions == sorted(positions)
    assert commands[0][2] == "example-600mw"  # not the reference unit
    for argv in commands:
        assert "reference" not in argv
        if argv[0] in ("calibrate", "validate") or argv[:2] == ["rom", "build"]:
            assert argv[argv.index("--turbine") + 1] == "fitted.toml"


def test_every_command_of_the_page_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    for argv, expected in doc_commands():
        result = runner.invoke(app, argv)
        assert result.exit_code == expected, f"steamtwin {shlex.join(argv)}\n{result.output}"
    assert Path("fitted.toml").is_file() and Path("validation/report.html").is_file()
