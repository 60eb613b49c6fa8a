"""The simulator's interface a ROS engineer scripts against (docs/how-to/ros1.md, "The simulator's
interface"): pause, reset and teleport services, namespaces, ROS command-line arguments, roslaunch,
runs until stopped, /use_sim_time put back, and a master's restart. Each on a real master; skipped
without Debian's ROS 1."""

import json
import os
import signal
import subprocess
import sys
import xmlrpc.client
from pathlib import Path


from conftest import needs_ros1, services, stop, wait_for

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
PROBE = Path(__file__).with_name("sim_probe.py")
LAUNCH_PACKAGE = Path(__file__).resolve().parents[2] / "amr_twin" / "ros1" / "roslaunch"
pytestmark = needs_ros1


def _state(env):
    _code, _msg, (pubs, subs, srvs) = xmlrpc.client.ServerProxy(
        env["ROS_MASTER_URI"]
    ).getSystemState("/test")
    return {t: set(n) for t, n in pubs}, {t: set(n) for t, n in subs}, {s: set(n) for s, n in srvs}


def _twin(args, env, **kw):
    return subprocess.Popen(
        [AMR_TWIN, *args], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw
    )


def _services_or_none(env):
    """The master's services; none while it is not up yet."""
    try:
        return services(env)
    except OSError:
        return set()


def _param(env, key):
    code, _msg, value = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"]).getParam("/test", key)
    return value if code == 1 else "absent"


def _end(proc, sig=signal.SIGTERM, timeout_s=60):
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=timeout_s)
    return proc.returncode, out, err


def test_two_twins_in_namespaces_share_only_one_clock_and_stop_on_sigterm_with_their_outputs(
    ros_env, tmp_path
):
    run = ["run", "stop", "--duration-s", "inf", "--world", "empty", "--ros1", "--rate", "1"]
    a = _twin([*run, "--csv", str(tmp_path / "a.csv")], dict(ros_env, ROS_NAMESPACE="r1"))
    b = _twin(
        [*run, "--json", "__ns:=r2", "__name:=twin_b", f"__log:={tmp_path / 'b.log'}"], ros_env
    )
    try:
        wait_for(
            lambda: (
                {"/r1/amr_twin/reset_simulation", "/r2/twin_b/reset_simulation"}
                <= services(ros_env)
            ),
            "both twins on the graph (their services come after their topics)",
        )
        pubs = _state(ros_env)[0]
        assert pubs["/r1/odom"] == {"/r1/amr_twin"} and pubs["/r2/odom"] == {"/r2/twin_b"}
        assert pubs["/r1/tf_static"] == {"/r1/amr_twin"} and "/r2/joint_states" in pubs
        assert {"/r1/amr_twin", "/r2/twin_b"} <= pubs["/clock"]  # one global /clock, no /r1/clock
        assert not any(t in pubs for t in ("/r1/clock", "/odom", "/tf", "/twin/ground_truth"))
        subs, srvs = _state(ros_env)[1:]
        assert "/r1/amr_twin" in subs["/r1/cmd_vel"] and "/r2/twin_b" in subs["/r2/cmd_vel"]
        assert {"/r1/amr_twin/pause_physics", "/r2/twin_b/reset_world", "/r2/twin_b/set_pose"} <= (
            set(srvs) | set(subs)
        )
        assert a.poll() is None and b.poll() is None  # no node-name clash shut one down
        code_a, _out, err_a = _end(a)
        code_b, out_b, err_b = _end(b)
    finally:
        for p in (a, b):
            if p.poll() is None:
                p.kill()
    assert code_a == 0 and "stopped by SIGTERM" in err_a, err_a
    assert code_b == 0 and json.loads(out_b)["sim_s"] > 0, err_b
    assert (tmp_path / "a.csv").stat().st_size > 0 and (tmp_path / "b.log").exists()


def test_pause_stops_the_clock_reset_and_set_pose_teleport_and_time_runs_on(ros_env):
    twin = _twin(
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.4",
            "--duration-s",
            "inf",
            "--world",
            "empty",
            "--ros1",
            "--rate",
            "1",
            "--actor",
            "person:-3,2.5;-3,-2.5@1.2/loop",
            "__ns:=r3",
        ],
        ros_env,
    )
    try:
        probe = subprocess.run(
            ["/usr/bin/python3", str(PROBE), "r3", "amr_twin"],
            env=ros_env,
            capture_output=True,
            text=True,
            timeout=180,
        )
        assert probe.returncode == 0, probe.stderr
        got = json.loads(probe.stdout.splitlines()[-1])
    finally:
        code, _out, err = _end(twin)
    assert code == 0, err
    assert got["running_hz"] > 60 and got["resumed_hz"] > 60, got  # 100 Hz paced at --rate 1
    assert got["paused_hz"] == 0, got
    assert got["before_reset"][0] > 0.5 and got["actor_before"][1] < 0.0, got  # driven, walked
    x, y, yaw = got["after_reset_world"]
    assert (
        abs(x) < 0.02 and abs(y) < 0.02 and abs(yaw) < 1.0 and got["speed_after_reset_world"] < 0.05
    ), got
    assert abs(got["actor_after"][0] + 3) < 0.05 and 2.5 - 0.15 < got["actor_after"][1] <= 2.5, (
        got
    )  # 100 ms walked
    x, y, yaw = got["after_set_pose"]
    assert abs(x - 2.0) < 0.1 and abs(y - 1.0) < 0.1 and abs(yaw - 90) < 3, got
    ox, oy, _ = got["odom_after_reset_simulation"]
    assert (
        abs(ox) < 0.02
        and abs(oy) < 0.02
        and max(map(abs, got["gt_after_reset_simulation"][:2])) < 0.02
    ), got
    assert got["speed_2s_after_reset_simulation"] < 0.02, got  # braked
    assert got["clock_went_back"] == 0, got  # simulated time is monotonic across the resets


def test_use_sim_time_is_put_back_as_it_was(ros_env):
    xmlrpc.client.ServerProxy(ros_env["ROS_MASTER_URI"]).setParam("/test", "/use_sim_time", False)
    out = subprocess.run(
        [AMR_TWIN, "run", "stop", "--duration-s", "1", "--world", "empty", "--ros1", "__ns:=r4"],
        env=ros_env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert _param(ros_env, "/use_sim_time") is False
    assert _param(ros_env, "/r4/robot_description").startswith("<?xml")  # in the namespace


def test_roslaunch_starts_the_twin_as_a_node_with_its_remaps_and_stops_it_with_its_outputs(
    tmp_path,
):
    from amr_twin.ros1.master import free_port

    port = free_port()
    env = dict(
        os.environ,
        ROS_MASTER_URI=f"http://127.0.0.1:{port}",
        ROS_IP="127.0.0.1",
        PYTHONUNBUFFERED="1",
        ROS_PACKAGE_PATH=str(LAUNCH_PACKAGE),
        AMR_TWIN=AMR_TWIN,
        ROS_LOG_DIR=str(tmp_path / "log"),
    )
    launch = tmp_path / "twin.launch"
    launch.write_text(f"""<launch>
  <group ns="r5">
    <node pkg="amr_twin" type="twin" name="sim" output="screen"
          args="run stop --duration-s inf --world empty --ros1 --rate 1 --csv {tmp_path}/run.csv">
      <remap from="cmd_vel" to="teleop/cmd_vel"/>
    </node>
  </group>
</launch>
""")
    proc = subprocess.Popen(
        ["roslaunch", "-p", str(port), str(launch)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        wait_for(
            lambda: "/r5/sim/reset_simulation" in _services_or_none(env),
            "the launched twin on the graph",
            90,
        )
        assert "/r5/sim" in _state(env)[0]["/clock"]
        subs = _state(env)[1]
        assert subs.get("/r5/teleop/cmd_vel") == {"/r5/sim"} and "/r5/cmd_vel" not in subs
        assert "/r5/sim/pause_physics" in services(env)
    finally:
        stop(proc, timeout_s=60)
        out = proc.stdout.read()
    assert "stopped by SIGINT" in out, out
    assert (tmp_path / "run.csv").stat().st_size > 0, out


def test_the_twin_says_once_that_the_master_is_gone_and_registers_again_with_a_new_one(tmp_path):
    from amr_twin.ros1.master import start_roscore

    master = start_roscore(log_dir=str(tmp_path))
    env = dict(os.environ, ROS_MASTER_URI=master.uri, ROS_IP="127.0.0.1", PYTHONUNBUFFERED="1")
    twin = _twin(
        ["run", "stop", "--duration-s", "inf", "--world", "empty", "--ros1", "--rate", "1"], env
    )
    lines = []
    try:
        lines.append(twin.stderr.readline())
        assert "the twin is /amr_twin" in lines[-1], lines
        port = master.uri.rsplit(":", 1)[1]
        master.stop()
        while (
            "does not answer" not in lines[-1] and len(lines) < 4
        ):  # within the watch's period; rospy may warn
            lines.append(twin.stderr.readline())  # once of the connection roscore's rosout dropped
        assert "does not answer" in lines[-1] and "simulates on" in lines[-1], lines
        master = start_roscore(log_dir=str(tmp_path), port=int(port))  # restarted where it was
    except BaseException:
        twin.kill()
        master.stop()
        raise
    try:
        while "registered again" not in lines[-1] and len(lines) < 6:
            lines.append(twin.stderr.readline())
        assert "registered again" in lines[-1], lines
        pubs, subs, srvs = _state(env)
        assert "/amr_twin" in pubs["/clock"] and "/amr_twin" in subs["/cmd_vel"], (pubs, subs)
        assert "/amr_twin/pause_physics" in srvs and _param(env, "/use_sim_time") is True
        echo = subprocess.run(
            ["rostopic", "echo", "-n", "1", "/odom/header/frame_id"],
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
        )  # a node started after the restart is connected
        assert "odom" in echo.stdout, echo.stderr
        code, _out, err = _end(twin, signal.SIGINT)
    finally:
        if twin.poll() is None:
            twin.kill()
        master.stop()
    assert code == 0, err
    assert "stopped by SIGINT" in err and len(lines) + err.count("\n") <= 6, (
        lines,
        err,
    )  # no stream of warnings
