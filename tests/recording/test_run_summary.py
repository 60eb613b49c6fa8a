"""The typed summary of a run (amr_twin/recording/run_summary.py) and the ``--json`` object written
from it."""

import json
import math

import pytest

from amr_twin.model.config import load_config
from amr_twin.recording.run_summary import RunSummary, WheelSummary, summary
from amr_twin.assembly.twin import TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command, run_mission

START = (-6.0, 0.0, 0.0)


@pytest.fixture(scope="module")
def backward():
    cfg = load_config()
    result = run_command(
        cfg, Command("linear", speed_m_s=-0.5), 4.0, TwinOptions(world="empty", start_xy_yaw=START)
    )
    return summary(result, True, START)


def test_a_backward_step_is_typed_and_its_metrics_carry_the_reference_sign(backward):
    assert isinstance(backward, RunSummary) and isinstance(backward.wheels["left"], WheelSummary)
    left = backward.wheels["left"]
    assert left.reference_rpm < -30.0 and left.step is not None and left.step_sign == -1.0
    out = backward.as_json()["wheels"]["left"]
    assert out["reference"] == pytest.approx(left.reference_rpm)  # the step's reference, signed
    assert out["final_value"] < -30.0 and out["final_rpm"] < -30.0
    assert out["rise_s"] > 0.0  # times stay positive


def test_the_json_is_strict_and_in_the_documented_order(backward):
    out = backward.as_json()
    text = json.dumps(out, allow_nan=False)  # no NaN: a step without overshoot has no peak
    assert out["wheels"]["left"]["peak_s"] is None
    assert list(out) == [
        "command",
        "wheel_command",
        "code",
        "codes",
        "errors",
        "wheels",
        "final_pose",
        "final_odom_pose",
        "battery",
        "collisions",
        "stopped_by_collision",
        "faults",
        "sim_s",
        "wall_s",
        "start_pose",
        "from_start",
    ]
    assert json.loads(text)["final_pose"]["x_m"] == backward.final_pose.x_m
    assert out["start_pose"] == {"x_m": -6.0, "y_m": 0.0, "yaw_rad": 0.0}


def test_the_distance_from_the_start_and_the_path_length_agree_on_a_straight_run(backward):
    assert backward.final_pose.x_m < START[0] - 0.5  # it went backward
    assert backward.from_start.distance_m == pytest.approx(backward.battery.distance_m, rel=0.02)
    assert abs(backward.from_start.heading_deg) < 5.0


def test_a_mission_has_no_step_metrics_and_no_start_pose_unless_given():
    cfg = load_config()
    steps = [(0.0, Command("linear", speed_m_s=0.3)), (1.0, Command("stop"))]
    s = summary(run_mission(cfg, steps, 2.0, TwinOptions(world="empty")), False)
    out = s.as_json()
    assert [c["kind"] for c in out["command"]] == ["linear", "stop"] and out["command"][1][
        "t_s"
    ] == 1.0
    assert (
        "delay_s" not in out["wheels"]["left"]
        and "start_pose" not in out
        and "from_start" not in out
    )
    assert math.isfinite(out["battery"]["energy_j"]) and out["battery"]["energy_j"] > 0.0
