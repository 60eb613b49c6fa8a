"""``amr-twin fleet``: refusals in one line before the model is built, and a short run on the
embedded broker."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

CLI = [sys.executable, "-c", "from amr_twin.cli.main import main; main()", "fleet"]


@pytest.mark.parametrize(
    "args, says",
    [
        (["--robots", "21"], "--robots 21: must be in 1..20"),
        (["--robots", "0"], "--robots 0: must be in 1..20"),
        (["--robots", "2"], "--starts: needed with --robots 2"),
        (["--robots", "2", "--starts", "0,0,0"], "--starts '0,0,0': 1 poses for --robots 2"),
        (
            ["--robots", "2", "--starts", "0,0,0;0.6,0.1,90"],
            "--starts: robots amr-1 and amr-2 overlap at their starts",
        ),
        (
            ["--vda5050", "http://localhost:1883"],
            "--vda5050 'http://localhost:1883': expected mqtt://HOST:PORT",
        ),
        (
            ["--interface", "u/agv"],
            "--interface 'u/agv': only letters, digits and _ . : - are allowed",
        ),
        (["--starts", "1,2"], "--starts '1,2': expected X_M,Y_M,YAW_DEG"),
        (["--rate", "-1"], "--rate -1: must be a finite number in [0, 1000]"),
        (["--jobs", "3"], "--jobs 3: only with --manager"),
        (["--manager", "--charge-below", "90"], "--charge-below 90: must be in [0, 80) %"),
    ],
)
def test_bad_options_are_refused_in_one_line(args, says):
    done = subprocess.run(CLI + args, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        f"error: {says}" + done.stderr.split(says, 1)[1].rstrip()
    ]


def test_a_short_run_on_the_embedded_broker_reports_what_it_sent():
    pytest.importorskip("amqtt")
    done = subprocess.run(
        CLI
        + [
            "--world",
            "warehouse",
            "--starts",
            "-6,0,0",
            "--duration-s",
            "2",
            "--rate",
            "0",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["embedded_broker"] and out["serialNumber"] == "amr-1"
    assert out["messages_sent"]["state"] >= 2 and out["messages_sent"]["visualization"] >= 19
    assert out["last_state"]["agvPosition"]["mapId"] == "warehouse"
    assert abs(out["true_pose"]["x_m"] + 6.0) < 0.05


def test_the_fleet_manager_beside_the_vehicle_places_it_on_the_roadmap():
    pytest.importorskip("amqtt")
    done = subprocess.run(
        CLI
        + ["--world", "warehouse", "--manager", "--jobs", "0", "--duration-s", "2", "--rate", "0"]
        + ["--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    manager = json.loads(done.stdout)["manager"]
    assert manager["roadmap"]["nodes"] == 50 and manager["jobs_done"] == 0  # 49 + home
    assert [e["event"] for e in manager["events"]] == ["placed"]
    assert manager["messages_sent"] == {"instantActions": 1}  # the factsheetRequest
