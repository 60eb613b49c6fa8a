"""``amr-twin experiment fleet``: bad input is one line and exit 2 before any episode."""

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app


@pytest.mark.parametrize(
    "args, message",
    [
        (["--robots", "1,x"], "--robots 1,x: expected A-B or A,B,C"),
        (["--robots", "25"], "--robots 25: distinct whole numbers in [1, 20]"),
        (["--payload-kg", "0-70"], "--payload-kg 0-70: LOW-HIGH with 0 <= LOW <= HIGH"),
        (["--payload-kg", "a-b"], "--payload-kg a-b: expected LOW-HIGH kg"),
        (["--seeds", "3-1"], "--seeds 3-1: expected A-B or A,B,C"),
        (["--duration-s", "-5"], "--duration-s -5: must be in (0, 86400] s"),
        (["--robots", "0,2"], "--robots 0,2: distinct whole numbers in [1, 20]"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, args, message):
    out = tmp_path / "out"
    if "--robots" not in args:
        args = ["--robots", "1", *args]
    result = CliRunner().invoke(app, ["experiment", "fleet", "--out", str(out), *args])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and message in lines[0], result.output
    assert not out.exists()


def test_a_short_run_writes_the_report_the_json_and_the_plots(tmp_path):
    out = tmp_path / "out"
    args = ["--robots", "1", "--seeds", "0", "--duration-s", "30", "--jobs", "1", "--no-progress"]
    result = CliRunner().invoke(app, ["experiment", "fleet", "--out", str(out), *args])
    assert result.exit_code == 0, result.output
    assert "0-30 kg: one fleet size: saturation not determined" in result.output
    assert sorted(p.name for p in out.iterdir()) == [
        "metrics.json",
        "report.md",
        "throughput.png",
        "tracks_1.png",
    ]
    assert "| 1 | 0.0 (0.0) |" in (out / "report.md").read_text()  # no order done in 30 s
