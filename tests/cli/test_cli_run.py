"""amr-twin run: the thesis conversions through the CLI JSON, refusals, --csv/--json, missions."""

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.recording.run_report import CSV_COLUMNS, CSV_COMMENT
from amr_twin.assembly.mission import MissionError, parse_mission

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()


def _run(*args):
    return runner.invoke(app, ["run", *args])


def _json(*args):
    result = _run(*args, "--json")
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_linear_conversion_printed_by_the_thesis():
    info = _json("linear", "--speed-m-s", "0.5", "--duration-s", "0.2")
    assert info["code"] == 0
    assert info["wheel_command"] == pytest.approx([1, 38.197, 1, 38.197], abs=1e-3)
    assert info["command"] == {"kind": "linear", "speed_m_s": 0.5, "t_s": 0.0}
    back = _json("linear", "--speed-m-s", "-1.2", "--duration-s", "0.2")
    assert back["wheel_command"] == pytest.approx([-1, 91.67, -1, 91.67], abs=1e-2)


def test_angular_conversion_rep103():
    # the thesis' numbers: 60 deg/s about an ICC 1 m to the right -> left 99.20, right 60.80
    info = _json("angular", "--speed-deg-s", "60", "--icc-m", "-1", "--duration-s", "0.2")
    assert info["wheel_command"][1::2] == pytest.approx([99.20, 60.80], abs=1e-4)
    assert info["wheels"]["left"]["reference_rpm"] == pytest.approx(
        -99.20, abs=1e-4
    )  # signed: backward
    # REP-103: +60 deg/s is counter-clockwise, so about an ICC on the right both wheels go
    # backward; the chapter-5 clockwise run (both forward) is -60 deg/s
    assert info["wheel_command"][0::2] == [-1, -1]
    cw = _json("angular", "--speed-deg-s", "-60", "--icc-m", "-1", "--duration-s", "0.2")
    assert cw["wheel_command"] == pytest.approx([1, 99.20, 1, 60.80], abs=1e-4)


def test_out_of_range_speed_is_code_1_with_the_thesis_message(tmp_path):
    out = tmp_path / "never.csv"
    result = _run("linear", "--speed-m-s", "20", "--duration-s", "0.2", "--csv", str(out), "--json")
    assert result.exit_code == 1
    assert "ERROR: linear velocity not valid" in result.stderr
    assert json.loads(result.stdout)["code"] == 1


@pytest.mark.parametrize(
    "args, text",
    [
        (["linear", "--speed-m-s", "nan"], "--speed-m-s nan: must be a finite number"),
        (
            ["angular", "--speed-deg-s", "inf", "--icc-m", "0"],
            "--speed-deg-s inf: must be a finite number",
        ),
        (["linear"], "--speed-m-s is required"),
        (["angular", "--speed-deg-s", "60"], "--icc-m is required"),
        (["motor", "--wheel", "left", "--speed-m-s", "1"], "--direction is required"),
        (["motor", "--wheel", "middle", "--direction", "forward", "--speed-m-s", "1"], "wheel"),
        ([], "give a command"),
    ],
)
def test_bad_input_is_refused_in_one_line(args, text, tmp_path):
    out = tmp_path / "never.csv"
    result = _run(*args, "--csv", str(out)) if args else _run()
    assert result.exit_code == 2
    assert text in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_csv_and_json_agree_with_the_simulation(tmp_path):
    out = tmp_path / "run.csv"
    info = _json(
        "motor",
        "--wheel",
        "left",
        "--direction",
        "forward",
        "--speed-m-s",
        "1",
        "--duration-s",
        "4",
        "--csv",
        str(out),
    )
    assert set(info) >= {
        "command",
        "wheel_command",
        "code",
        "wheels",
        "final_pose",
        "sim_s",
        "wall_s",
    }
    assert info["wheel_command"] == pytest.approx([1, 76.394, 1, 0.0], abs=1e-3)
    left = info["wheels"]["left"]
    assert {"reference_rpm", "final_rpm"} <= set(left) and left["samples"] >= 2
    with out.open() as f:
        assert (
            f.readline().startswith("# ") and "signed" in CSV_COMMENT
        )  # the convention, first line
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == CSV_COLUMNS
    last = {k: float(v) for k, v in rows[-1].items()}
    assert last["t_s"] == pytest.approx(info["sim_s"])
    pose = info["final_pose"]
    assert (last["x_m"], last["y_m"], last["yaw_rad"]) == pytest.approx(
        (pose["x_m"], pose["y_m"], pose["yaw_rad"]), rel=1e-6, abs=1e-9
    )
    assert last["pub_rpm_left"] == pytest.approx(left["final_rpm"], rel=1e-6)
    assert last["ref_rpm_left"] == pytest.approx(76.394, abs=1e-3) and last["ref_rpm_right"] == 0.0
    assert last["true_rpm_left"] > 60 and last["pwm_counts_left"] > 0
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())


def test_one_sign_convention_in_json_and_csv(tmp_path):
    """Backward at 1.2 m/s (ch. 5 run 4): every RPM negative in --json and --csv, as the true speed
    is."""
    out = tmp_path / "back.csv"
    info = _json(
        "linear", "--speed-m-s", "-1.2", "--duration-s", "4", "--world", "empty", "--csv", str(out)
    )
    assert info["wheel_command"][:2] == pytest.approx(
        [-1, 91.67], abs=0.01
    )  # the message: code and |speed|
    table = np.genfromtxt(out, delimiter=",", names=True, skip_header=1)  # after the "# ..." line
    for name in ("left", "right"):
        w = info["wheels"][name]
        assert w["reference_rpm"] == pytest.approx(-91.67, abs=0.01) and w["true_final_rpm"] < -80
        assert w["final_rpm"] < -80 and w["reference"] == pytest.approx(w["reference_rpm"])
        assert w["final_value"] < -80 and w["overshoot"] >= 0
        assert w["steady_error"] == pytest.approx(
            w["final_value"] - w["reference"]
        )  # the offset, signed
        assert (
            w["peak_value"] is None or w["peak_value"] < w["final_value"]
        )  # a peak lies beyond it
        assert table[f"ref_rpm_{name}"][-1] == pytest.approx(w["reference_rpm"], rel=1e-6)
        assert table[f"pub_rpm_{name}"][-1] == pytest.approx(w["final_rpm"], rel=1e-6)
        assert table[f"true_rpm_{name}"][-1] == pytest.approx(w["true_final_rpm"], rel=1e-6)


def test_square_mission_runs(tmp_path):
    out = tmp_path / "square.csv"
    info = _json("--mission", str(ROOT / "experiments/missions/square.yaml"), "--csv", str(out))
    assert info["codes"] == [0] * 9 and info["sim_s"] == 14
    assert [c["kind"] for c in info["command"]][-1] == "stop"
    assert out.exists()


def test_square_mission_says_where_it_ended_and_that_its_speeds_are_old():
    """After the stop the last published speeds are seconds old (nothing is
    published at rest), and the timed "square" does not close: both are said."""
    square = str(ROOT / "experiments/missions/square.yaml")
    info = _json("--mission", square, "--world", "empty")
    start, end = info["start_pose"], info["final_pose"]
    moved = info["from_start"]
    assert moved["distance_m"] == pytest.approx(
        math.dist((start["x_m"], start["y_m"]), (end["x_m"], end["y_m"]))
    )
    assert moved["heading_deg"] == pytest.approx(
        math.degrees(end["yaw_rad"] - start["yaw_rad"])
    )  # within +-180
    assert (
        moved["distance_m"] > 0.2 and abs(moved["heading_deg"]) > 20
    )  # timed commands: it does not close
    text = _run("--mission", square, "--world", "empty")
    assert text.exit_code == 0
    assert (
        f"ended {moved['distance_m']:.2f} m from its start pose, heading "
        f"{moved['heading_deg']:+.1f} deg" in text.stdout
    )
    for name, wheel in info["wheels"].items():
        assert (
            wheel["final_rpm"] != 0 and wheel["final_rpm_t_s"] < info["sim_s"] - 1.0
        )  # the stop came at 12 s
        line = next(x for x in text.stdout.splitlines() if x.startswith(name))
        assert (
            f"last published {wheel['final_rpm']:8.3f} RPM at {wheel['final_rpm_t_s']:.2f} s"
            in line
        )
        assert "nothing is published at rest" in line
    single = _run("linear", "--speed-m-s", "0.5", "--duration-s", "3", "--world", "empty")
    assert (
        "at rest" not in single.stdout and "ended" not in single.stdout
    )  # a wheel still turning; one command


def test_mission_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("duration_s: 5\nsteps:\n  - {t_s: 1, lineer: {speed_m_s: 0.5}}\n")
    result = _run("--mission", str(bad))
    assert result.exit_code == 2 and "steps[0]: unknown key 'lineer'" in result.stderr
    for tree, text in [
        ({"duration_s": 5, "steps": [{"t_s": 6, "stop": {}}]}, "must lie in [0, 5.0]"),
        ({"duration_s": 5, "steps": [{"t_s": 0, "linear": {}}]}, "linear.speed_m_s is missing"),
        ({"duration_s": 5, "steps": [{"t_s": 0, "linear": {"speed_m_s": math.nan}}]}, "finite"),
        (
            {"duration_s": 5, "steps": [{"t_s": 0, "stop": {}, "linear": {"speed_m_s": 1}}]},
            "exactly one",
        ),
        ({"steps": []}, "duration_s is missing"),
    ]:
        with pytest.raises(MissionError, match=None) as exc:
            parse_mission(tree)
        assert text in str(exc.value)
    duration_s, steps = parse_mission(
        {
            "duration_s": 3,
            "steps": [{"t_s": 2, "stop": None}, {"t_s": 0, "angular": {"speed_deg_s": 30}}],
        }
    )
    assert duration_s == 3 and [t for t, _ in steps] == [0, 2] and steps[0][1].icc_m == 0.0


def test_sensors_switch_records_scan_and_imu(tmp_path):
    from mcap.reader import make_reader

    def topics(path):
        with open(path, "rb") as f:
            counts = {}
            for _schema, channel, _message in make_reader(f).iter_messages():
                counts[channel.topic] = counts.get(channel.topic, 0) + 1
        return counts

    with_sensors, without = tmp_path / "s.mcap", tmp_path / "n.mcap"
    args = ("linear", "--speed-m-s", "0.3", "--duration-s", "0.5")
    info = _json(*args, "--sensors", "--mcap", str(with_sensors))
    plain = _json(*args, "--mcap", str(without))
    counts = topics(with_sensors)
    # 0.5 s: IMU at 100 Hz from t = 0 (51 samples), LiDAR scans of 182 ms (2 complete)
    assert counts["/imu/data_raw"] == counts["/imu/mag"] == 51
    assert counts["/scan"] == 2
    assert "/scan" not in topics(without) and "/imu/data_raw" not in topics(without)
    # the sensors only observe: the run is the same
    assert info["final_pose"] == plain["final_pose"] and info["wheels"] == plain["wheels"]


def test_world_and_start_pose(tmp_path):
    data = _json(
        "linear", "--speed-m-s", "0.5", "--duration-s", "2", "--world", "empty", "--start=2,1,90"
    )
    pose = data["final_pose"]
    assert pose["x_m"] == pytest.approx(2.0, abs=0.05)  # facing +y: x unchanged
    assert 1.6 < pose["y_m"] < 2.1  # ~0.7 m driven along +y
    assert pose["yaw_rad"] == pytest.approx(math.pi / 2, abs=0.05)
    odom = data["final_odom_pose"]  # odometry starts at its own origin (REP-105)
    # along its own x the distance driven (0.92 m; the node estimates the first revolution from the
    # command)
    assert odom["x_m"] == pytest.approx(pose["y_m"] - 1.0, abs=0.1) and abs(odom["y_m"]) < 0.05


def test_a_saved_ros_map_is_a_world(tmp_path):
    from amr_twin.model.pgm import write_pgm
    import numpy as np

    image = np.full((60, 60), 254, np.uint8)  # 3 m x 3 m room at 0.05 m, walls all round
    image[:2, :] = image[-2:, :] = image[:, :2] = image[:, -2:] = 0
    write_pgm(tmp_path / "room.pgm", image)
    (tmp_path / "room.yaml").write_text(
        "image: room.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    data = _json(
        "linear",
        "--speed-m-s",
        "0.5",
        "--duration-s",
        "6",
        "--world",
        str(tmp_path / "room.yaml"),
        "--start=1.5,1.5,0",
    )
    assert data["final_pose"]["x_m"] < 2.9 - 0.25  # stopped by the east wall, not through it


def test_unknown_world_is_one_line():
    res = _run("linear", "--speed-m-s", "0.5", "--world", "nowhere")
    assert (
        res.exit_code == 2
        and "--world nowhere" in res.output
        and len(res.output.strip().splitlines()) == 1
    )


def test_a_mission_carries_faults(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "duration_s: 3\nsteps:\n  - {t_s: 0, linear: {speed_m_s: 0.5}}\n"
        "faults: [motor-left-stall@1, 'estop@2:for=0.5']\n"
    )
    info = _json("--mission", str(mission), "--world", "empty", "--fault", "battery-sag@2.5")
    assert [f["kind"] for f in info["faults"]] == ["motor-left-stall", "estop", "battery-sag"]
    assert info["faults"][1]["until_s"] == 2.5
    bad = tmp_path / "bad.yaml"
    bad.write_text("duration_s: 3\nsteps:\n  - {t_s: 0, stop: {}}\nfaults: [hall-left-dead]\n")
    res = _run("--mission", str(bad))
    assert res.exit_code == 2 and "faults 'hall-left-dead': expected KIND@T" in res.stderr
    assert str(bad) in res.stderr


@pytest.mark.parametrize(
    "args, text",
    [
        (["--actor", "robot:0,0;1,1"], "--actor 'robot:0,0;1,1': expected KIND:X1,Y1;X2,Y2"),
        (
            ["--actor", "person:-3,2;-3,-2@2.5"],
            "actor 0 (person_0): speed 2.5 m/s outside the person's [0.5, 1.8] m/s",
        ),
        (["--actor", "person:-4.5,2;-4.5,5"], "actor 0 (person_0): its path runs into rack_n_"),
        (
            ["--actor", "pallet_jack:-3,2;-3,-2", "--actor", "person:-3,2;-3,2"],
            "waypoints 0 and 1 coincide",
        ),
        (["--actors-random", "0"], "--actors-random '0': expected N[/stop=M] with N in 1..50"),
        (["--actors-random", "many"], "--actors-random 'many'"),
        (["--actor", "person:-5.8,0"], "the robot overlaps person_0 there"),
    ],
)
def test_bad_actors_are_refused_before_the_run_in_one_line(args, text, tmp_path):
    out = tmp_path / "never.csv"
    result = _run("stop", *args, "--csv", str(out))
    assert result.exit_code == 2, result.output
    assert text in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_driving_into_a_person_is_reported_naming_them():
    result = _run(
        "linear", "--speed-m-s", "0.5", "--duration-s", "4", "--actor", "person:-4.6,0", "--json"
    )
    assert result.exit_code == 0
    (hit,) = json.loads(result.stdout)["collisions"]
    assert hit["hit"] == "person_0" and "base_link" in hit["robot_parts"]
    assert "warning: collision at t = " in result.stderr and "with person_0" in result.stderr
    text = _run(
        "linear", "--speed-m-s", "0.5", "--duration-s", "4", "--actor", "person:-4.6,0"
    ).stdout
    assert "base_link hit person_0" in text


def test_a_mission_places_actors_and_the_person_waits_for_the_robot(tmp_path):
    info = _json("--mission", str(ROOT / "experiments/missions/person_crossing.yaml"))
    assert info["collisions"] == [] and info["codes"] == [0, 0]
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "duration_s: 5\nsteps: [{t_s: 0, stop: {}}]\nactors: [{kind: person, waypoints_xy_m: "
        "[[0, 0]]}]\n"
    )
    result = _run("--mission", str(bad))
    assert result.exit_code == 2 and "actors[0].speed_m_s is missing" in result.stderr


def test_random_actors_follow_the_seed(tmp_path):
    """--actors-random N draws from --seed: the same poses on /actors/poses for the same seed,
    others for another."""
    from mcap.reader import make_reader

    def poses(seed, name):
        path = tmp_path / name
        result = _run(
            "stop",
            "--duration-s",
            "1",
            "--actors-random",
            "3",
            "--seed",
            str(seed),
            "--mcap",
            str(path),
        )
        assert result.exit_code == 0, result.output
        with open(path, "rb") as f:
            return [
                m.data for _s, c, m in make_reader(f).iter_messages() if c.topic == "/actors/poses"
            ]

    a, b, c = poses(5, "a.mcap"), poses(5, "b.mcap"), poses(6, "c.mcap")
    assert len(a) == 11 and a == b and a != c


STIFF_TYRE = (
    "--payload-kg",
    "50",
    "--set",
    "wheel.slip_stiffness_per_n=25",
    "--set",
    "wheel.relaxation_length_longitudinal_m=0.02",
    "--set",
    "wheel.tyre_loss_time_s=0.01",
)


def test_tyre_guard_said_in_the_json_and_absent_when_nominal():
    assert "tyre_timestep" not in _json("linear", "--speed-m-s", "0.7", "--duration-s", "0.2")
    result = _run("linear", "--speed-m-s", "0.7", "--duration-s", "0.2", "--json", *STIFF_TYRE)
    assert result.exit_code == 0, result.output
    step = json.loads(result.stdout)["tyre_timestep"]
    assert step["timestep_s"] == 0.00025 and step["configured_timestep_s"] == 0.001
    assert (
        max(step["stability_number_configured"])
        > step["stability_limit"]
        > max(step["stability_number"])
    )


def test_tyre_guard_refuses_a_timestep_it_cannot_halve_on_whole_microseconds():
    result = _run(
        "linear",
        "--speed-m-s",
        "0.7",
        "--duration-s",
        "0.2",
        "--set",
        "sim.timestep_s=0.00125",
        *STIFF_TYRE,
    )
    assert result.exit_code == 2
    assert (
        "sim.timestep_s: 0.00125 s cannot be halved" in result.output
        and "S = 4.73" in result.output
    )
