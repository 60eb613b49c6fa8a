"""``amr-twin fleet --record DIR`` and ``--live``: refusals in one line before any work, and
the recording of one and of two robots."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

CLI = [sys.executable, "-c", "from amr_twin.cli.main import main; main()", "fleet"]
TWO = ["--robots", "2", "--starts", "0,0,0;2,0,0", "--world", "aisles"]
WORLDS = Path(__file__).resolve().parents[2] / "models" / "worlds"


def _refused(args) -> str:
    done = subprocess.run(CLI + args, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def test_bad_outputs_and_live_options_are_refused(tmp_path):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    assert "--record" in _refused(TWO + ["--record", str(a_file)])
    said = _refused(TWO + ["--record", str(WORLDS)])
    assert "--record" in said and "input" in said
    assert "Foxglove only" in _refused(TWO + ["--live", "rerun"])
    assert "--port is an option of --live" in _refused(TWO + ["--port", "9000"])
    assert not (tmp_path / "fleet.mcap").exists()


@pytest.mark.parametrize("robots", [1, 2])
def test_the_recording_holds_every_robot(tmp_path, robots):
    pytest.importorskip("amqtt")
    args = TWO if robots == 2 else ["--world", "aisles", "--starts", "0,0,0"]
    out = tmp_path / "rec"
    done = subprocess.run(
        CLI + args + ["--duration-s", "1", "--rate", "0", "--record", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    from mcap.reader import make_reader

    with open(out / "fleet.mcap", "rb") as f:
        topics = {c.topic for c in make_reader(f).get_summary().channels.values()}
    for i in range(1, robots + 1):
        assert {f"/amr-{i}/odom", f"/amr-{i}/scan", f"/amr-{i}/twin/ground_truth"} <= topics
    assert "/odom" not in topics and "/clock" in topics
    assert (out / "fleet.rrd").stat().st_size > 10_000


def test_the_managers_events_are_recorded_on_the_worlds_clock(tmp_path):
    pytest.importorskip("amqtt")
    import json

    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    done = subprocess.run(
        CLI
        + ["--robots", "2", "--world", "warehouse", "--starts", "-6,0,0;-3,0,0", "--manager"]
        + ["--jobs", "1", "--duration-s", "2", "--rate", "0", "--record", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    with open(tmp_path / "fleet.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        events = [
            (m.log_time, json.loads(msg.data))
            for _s, _c, m, msg in reader.iter_decoded_messages(topics=["/fleet_manager/events"])
        ]
    placed = {e["vehicle"] for _t, e in events if e["event"] == "placed"}
    assert placed == {"amr-1", "amr-2"}
    assert all(0 <= t <= 2.1e9 for t, _e in events)  # simulated ns, within the run
