"""``amr-twin run goto`` and navigation missions: refusals before the build, outcomes,
recordings."""

import json
import math
import shutil
import subprocess

import numpy as np
import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app

RUN = CliRunner()


@pytest.mark.parametrize(
    "args, text",
    [
        (
            ["--goal", "-20,-6.4", "--world", "aisles"],
            "goal -20,-6.4: ",
        ),  # inside a rack row: cut off
        (
            ["--goal", "-3,3.0"],
            "lies inside an obstacle of the map",
        ),  # on the warehouse north rack's beam
        (["--goal", "-3,3.25"], "closer than the robot's half width"),
        (["--goal", "100,3", "--world", "aisles"], "lies outside the map"),
        (["--goal", "3"], "--goal '3': expected X_M,Y_M"),
        (["--goal", "1,nan"], "each value must be finite"),
        (["--goal", "1,1", "--controller", "dwb"], "--controller 'dwb'"),
        (["--goal", "1,1", "--localisation", "amcl"], "--localisation 'amcl'"),
        (["--goal", "1,1", "--map", "nowhere.yaml"], "--map nowhere.yaml: no such file"),
    ],
)
def test_a_goal_that_cannot_be_reached_is_refused_in_one_line_before_the_run(
    args, text, monkeypatch
):
    import amr_twin.navigation.navigation_run as navigation_run

    monkeypatch.setattr(navigation_run, "navigate", lambda *a, **k: pytest.fail("the run started"))
    res = RUN.invoke(app, ["run", "goto", *args])
    assert res.exit_code == 2, res.output
    assert text in res.output and len(res.output.strip().splitlines()) == 1, res.output


def test_a_start_off_the_map_is_named_as_the_start(tmp_path, monkeypatch):
    """A map file covering 2 x 2 m at the origin; the aisles world's start (-23.5, 0) lies off
    it."""
    import amr_twin.navigation.navigation_run as navigation_run

    monkeypatch.setattr(navigation_run, "navigate", lambda *a, **k: pytest.fail("the run started"))
    (tmp_path / "m.pgm").write_bytes(b"P5\n40 40\n255\n" + bytes([254]) * 1600)
    (tmp_path / "m.yaml").write_text(
        "image: m.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    res = RUN.invoke(
        app,
        ["run", "goto", "--goal", "1,1", "--world", "aisles", "--map", str(tmp_path / "m.yaml")],
    )
    assert res.exit_code == 2, res.output
    assert "the start (-23.5, 0) lies outside the map of --map" in res.output, res.output
    assert len(res.output.strip().splitlines()) == 1 and "goal" not in res.output, res.output


def test_a_goal_inside_a_rack_is_named_as_cut_off(monkeypatch):
    res = RUN.invoke(app, ["run", "goto", "--goal", "-20,-6.4", "--world", "aisles"])
    assert (
        "cut off" in res.output
    )  # the rack's inside is enclosed by its beams at the robot's height


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("goto")
    res = RUN.invoke(
        app,
        [
            "run",
            "goto",
            "--goal",
            "-6,0,180",
            "--start=-9,0,0",
            "--localisation",
            "truth",
            "--controller",
            "rpp",
            "--json",
            "--mcap",
            str(out / "g.mcap"),
            "--record",
            str(out / "g.rrd"),
        ],
    )
    return res, out


def test_goto_reaches_the_goal_and_reports_it(recorded):
    res, _ = recorded
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    goal = info["goals"][0]
    assert goal["status"] == "succeeded" and info["collisions"] == []
    x, y, yaw = info["final_pose"]
    # the goal checker latches within 0.25 m (nav2's stateful SimpleGoalChecker), then the robot
    # brakes at decel_m_s2 and turns to the goal's heading: it stops up to a few cm further (0.240 m
    # before the LiDAR's beams were cast from their own origins, 0.256 m since, on this drive)
    assert (
        math.hypot(x + 6.0, y) <= 0.30 and abs(math.remainder(yaw - math.pi, 2 * math.pi)) <= 0.25
    )


def test_the_mcap_holds_the_plan_map_costmap_and_footprint_as_ros_reads_them(recorded):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _, out = recorded
    last, counts = {}, {}
    with open(out / "g.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, _msg, decoded in reader.iter_decoded_messages(
            topics=["/plan", "/map", "/local_costmap/costmap", "/local_costmap/published_footprint"]
        ):
            last[channel.topic] = (schema.name, decoded)
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    assert {t: s for t, (s, _) in last.items()} == {
        "/plan": "nav_msgs/msg/Path",
        "/map": "nav_msgs/msg/OccupancyGrid",
        "/local_costmap/costmap": "nav_msgs/msg/OccupancyGrid",
        "/local_costmap/published_footprint": "geometry_msgs/msg/PolygonStamped",
    }
    plan = last["/plan"][1]
    assert plan.header.frame_id == "map" and abs(plan.poses[-1].pose.position.x + 6.0) < 1e-9
    grid = last["/map"][1]
    assert (
        len(grid.data) == grid.info.width * grid.info.height
        and max(grid.data) == 100
        and min(grid.data) == 0
    )
    assert counts["/map"] == 1 and counts["/local_costmap/costmap"] >= 10  # 2 Hz over the run
    corners = last["/local_costmap/published_footprint"][1].polygon.points
    sides = [math.dist((a.x, a.y), (b.x, b.y)) for a, b in zip(corners, corners[1:] + corners[:1])]
    assert sorted(round(s, 3) for s in sides) == [0.53, 0.53, 0.7, 0.7]


def test_the_rrd_holds_the_navigation_entities(recorded):
    from rerun.chunk import RrdReader

    _, out = recorded
    paths = {str(ch.entity_path) for ch in RrdReader(str(out / "g.rrd")).stream().to_chunks()}
    assert {
        "/world/navigation/plan",
        "/world/navigation/map",
        "/world/navigation/costmap",
        "/world/navigation/footprint",
    } <= paths
    rerun = shutil.which("rerun")
    if rerun:
        assert (
            subprocess.run(
                [rerun, "rrd", "verify", str(out / "g.rrd")], capture_output=True
            ).returncode
            == 0
        )


def test_a_navigation_mission_visits_its_goals_in_turn(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "goals:\n  - [-6, 0]\n  - {x_m: -8, y_m: 0, yaw_deg: 180}\nlocalisation: "
        "truth\ncontroller: rpp\n"
    )
    res = RUN.invoke(app, ["run", "--mission", str(mission), "--start=-9,0,0", "--json"])
    assert res.exit_code == 0, res.output
    goals = json.loads(res.stdout)["goals"]
    assert [g["status"] for g in goals] == ["succeeded", "succeeded"]
    assert goals[0]["t_end_s"] < goals[1]["t_start_s"] + 1e-9


def test_a_goal_not_reached_exits_5_with_its_reason(tmp_path):
    res = RUN.invoke(
        app,
        [
            "run",
            "goto",
            "--goal",
            "-3,0",
            "--start=-9,0,0",
            "--localisation",
            "truth",
            "--controller",
            "rpp",
            "--duration-s",
            "3",
        ],
    )
    assert res.exit_code == 5
    assert "timed out" in res.output.splitlines()[-1]


def test_the_mcap_holds_the_map_match_the_ekf_fused(tmp_path):
    """With the EKF held to the map (the default localisation) the matched poses go into the MCAP as
    AMCL's amcl_pose would: geometry_msgs/PoseWithCovarianceStamped in map, read by the mcap
    library's ROS 2 decoder, each near the EKF's pose of its stamp (across the aisle within 3 cm,
    along it within the match's standard deviation), with the fit's covariance (a 2 m aisle: across
    it tighter than along it)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    res = RUN.invoke(
        app,
        [
            "run",
            "goto",
            "--world",
            "aisles",
            "--goal",
            "-10,-4.8,0",
            "--start=-13,-4.8,0",
            "--controller",
            "rpp",
            "--json",
            "--mcap",
            str(tmp_path / "g.mcap"),
        ],
    )
    assert res.exit_code == 0, res.output
    matched, filtered = [], {}
    with open(tmp_path / "g.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        topics = ["/map_match/pose", "/odometry/filtered"]
        for schema, channel, _msg, m in reader.iter_decoded_messages(topics=topics):
            stamp = (m.header.stamp.sec, m.header.stamp.nanosec)
            if channel.topic == "/map_match/pose":
                assert schema.name == "geometry_msgs/msg/PoseWithCovarianceStamped"
                matched.append((stamp, m))
            else:
                filtered[stamp] = m
    assert len(matched) >= 20, len(matched)
    for stamp, m in matched:
        cov = np.array(m.pose.covariance).reshape(6, 6)
        assert m.header.frame_id == "map" and cov[0, 0] > cov[1, 1] > 0 and cov[5, 5] > 0
        ekf = filtered[
            stamp
        ].pose.pose.position  # the EKF's pose of that instant, after it took the match in
        # across the aisle the match holds the EKF to a few cm; along it (the aisle's length, poorly
        # held by a scan) within the match's own standard deviation
        assert abs(m.pose.pose.position.y - ekf.y) < 0.03
        assert abs(m.pose.pose.position.x - ekf.x) < math.sqrt(cov[0, 0])


def test_goto_reports_its_faults_and_writes_json_without_nan():
    """A goal at the start has no plan: its plan_length_m is null, not NaN (which is not JSON); the
    fault is reported with its effect, as run linear reports it, in the JSON and in the text."""
    args = [
        "run",
        "goto",
        "--goal=-9,0",
        "--start=-9,0,0",
        "--localisation",
        "truth",
        "--fault",
        "lidar-dead@0.5",
    ]
    res = RUN.invoke(app, [*args, "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))
    assert info["goals"][0]["plan_length_m"] is None
    assert [f["kind"] for f in info["faults"]] == ["lidar-dead"]
    assert info["faults"][0]["effect"]["scan_published_after"] == 0
    res = RUN.invoke(app, args)
    assert res.exit_code == 0 and "no plan" in res.stdout
    assert "fault lidar-dead at 0.5 s: " in res.stdout and "; 0 scan published after" in res.stdout


def test_the_goto_json_writer_refuses_what_is_not_json(monkeypatch):
    """A NaN that reaches the writer is an error, never a NaN in the output."""
    from amr_twin.cli import goto_report

    monkeypatch.setattr(goto_report, "_finite", lambda value: value)
    res = RUN.invoke(
        app, ["run", "goto", "--goal=-9,0", "--start=-9,0,0", "--localisation", "truth", "--json"]
    )
    assert res.exit_code != 0 and "NaN" not in res.stdout


@pytest.mark.parametrize("seed", [0, 1])
def test_a_goal_the_estimate_reached_but_the_truth_missed_is_not_reached(tmp_path, seed):
    """Wheel odometry that takes the 0.125 m tyres for 0.15 m ones (localisation odom): the
    navigator stops where its estimate is within 0.25 m of the goal, the robot really 0.3-0.4 m
    short: not reached, exit 5, the reason and the JSON give both errors."""
    calibration = tmp_path / "odometry.yaml"
    calibration.write_text(
        "wheel_odometry:\n  left_wheel_radius_m: 0.15\n  right_wheel_radius_m: 0.15\n"
        "  wheel_separation_m: 0.48\n"
    )
    res = RUN.invoke(
        app,
        [
            "run",
            "goto",
            "--goal=-6,0",
            "--start=-9,0,0",
            "--localisation",
            "odom",
            "--controller",
            "rpp",
            "--odometry",
            str(calibration),
            "--seed",
            str(seed),
            "--json",
        ],
    )
    assert res.exit_code == 5, res.output
    goal = json.loads(res.stdout)["goals"][0]
    error = goal["final_error"]
    assert error["estimate_xy_m"] <= 0.25 < error["true_xy_m"], error
    assert goal["status"] == "aborted"
    assert goal["reason"].startswith(
        f"reached by the estimate, true pose {error['true_xy_m']:.3f} m from the goal"
    )
    assert res.stderr.strip().splitlines()[-1] == f"error: {goal['reason']}"


def test_goto_gives_the_least_clearance_and_both_final_errors(recorded):
    """Down the warehouse's central aisle: the least clearance of the true footprint to the racks
    (0.60 m measured), and the truth's final error is the final pose's, the one the success was
    judged by."""
    res, _ = recorded
    info = json.loads(res.stdout)
    assert (
        0.3 < info["min_clearance_m"] < 0.95 and 0.0 <= info["min_clearance_t_s"] <= info["sim_s"]
    )
    error = info["goals"][0]["final_error"]
    x, y, yaw = info["final_pose"]
    assert error["true_xy_m"] == pytest.approx(math.hypot(x + 6.0, y), abs=1e-9)
    assert error["true_yaw_deg"] == pytest.approx(
        abs(math.degrees(math.remainder(yaw - math.pi, 2 * math.pi)))
    )
    assert (
        abs(error["estimate_xy_m"] - error["true_xy_m"]) < 0.02
    )  # localisation truth: the same pose


def test_goal_tolerance_options_set_what_the_navigator_judges_by(monkeypatch):
    """--xy-tolerance-m, --yaw-tolerance-deg, --inflation-radius-m reach the stack as the parameter
    file's keys."""
    import amr_twin.navigation.navigation_run as navigation_run

    seen = {}

    def fake(cfg, *a, **k):
        seen["cfg"] = cfg
        raise SystemExit(0)

    monkeypatch.setattr(navigation_run, "navigate", fake)
    RUN.invoke(
        app,
        [
            "run",
            "goto",
            "--goal=-6,0",
            "--start=-9,0,0",
            "--xy-tolerance-m",
            "0.1",
            "--yaw-tolerance-deg",
            "5",
            "--inflation-radius-m",
            "0.8",
        ],
    )
    nav = seen["cfg"].navigation
    assert nav.navigator.xy_tolerance_m == 0.1 and nav.costmap.inflation_radius_m == 0.8
    assert nav.navigator.yaw_tolerance_rad == pytest.approx(math.radians(5))


@pytest.mark.parametrize(
    "args, text",
    [
        (
            ["--xy-tolerance-m", "5"],
            "--xy-tolerance-m 5: navigation.navigator.xy_tolerance_m: 5.0 is out of range",
        ),
        (["--yaw-tolerance-deg", "0"], "--yaw-tolerance-deg 0: must be in (0, 180] deg"),
        (["--inflation-radius-m", "-1"], "--inflation-radius-m -1: "),
        (
            ["--xy-tolerance-m", "0.3", "--set", "navigation.navigator.xy_tolerance_m=0.2"],
            "both set",
        ),
    ],
)
def test_bad_goal_options_are_refused_in_one_line(args, text, monkeypatch):
    import amr_twin.navigation.navigation_run as navigation_run

    monkeypatch.setattr(navigation_run, "navigate", lambda *a, **k: pytest.fail("the run started"))
    res = RUN.invoke(app, ["run", "goto", "--goal=-6,0", "--start=-9,0,0", *args])
    assert (
        res.exit_code == 2 and text in res.output and len(res.output.strip().splitlines()) == 1
    ), res.output
