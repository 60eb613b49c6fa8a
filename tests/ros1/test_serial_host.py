"""The project's rosserial host: unit checks of its protocol handling (a fake rospy on a pipe), then
listing 4.1's launch file on a real roscore pointed at the twin's pseudo-terminal (the emulated
Mega)."""

import json
import os
import re
import struct
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import MISSING, in_workspace, needs_ros1, stop
from amr_twin.controllers.avr_build import missing_tools
from amr_twin.ros.rosserial_frame import ID_PUBLISHER, ID_TIME, FrameParser

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
needs_avr = pytest.mark.skipif(missing_tools() is not None, reason=missing_tools() or "")


class _Time:
    def __init__(self, secs=0.0):
        self.t = secs
        self.secs, self.nsecs = int(secs), int(round((secs % 1) * 1e9))

    def is_zero(self):
        return self.t == 0

    def __sub__(self, other):
        return SimpleNamespace(to_sec=lambda: self.t - other.t)


class _FakeRospy:
    """What SerialHost uses of rospy, with a clock the test sets."""

    def __init__(self):
        self.now = 1.0
        self.errors, self.published = [], []
        self.Time = SimpleNamespace(now=lambda: _Time(self.now))

    def Publisher(self, topic, cls, queue_size):  # noqa: N802 - rospy's name
        return SimpleNamespace(publish=lambda msg: self.published.append((topic, msg)))

    def Subscriber(self, topic, cls, callback, queue_size):  # noqa: N802
        return SimpleNamespace(topic=topic, callback=callback)

    def loginfo(self, *a):
        pass

    logwarn = logwarn_once = loginfo

    def logerr(self, *a):
        self.errors.append(a[0] % a[1:])


def _topic_info(topic_id: int, name: str, typ: str, md5: str) -> bytes:
    def s(x):
        return struct.pack("<I", len(x)) + x.encode()

    return struct.pack("<H", topic_id) + s(name) + s(typ) + s(md5) + struct.pack("<i", 512)


@pytest.fixture
def host():
    if MISSING:
        pytest.skip(MISSING)
    from amr_twin.ros1.installation import import_rospy

    import_rospy()
    from amr_twin.ros1.serial_host import SerialHost

    rospy = _FakeRospy()
    theirs, mine = os.pipe()
    h = SerialHost(rospy, mine)
    h.frames = lambda: FrameParser().feed(os.read(theirs, 65536))
    yield h
    os.close(theirs)
    os.close(mine)


def test_the_host_configures_the_clients_topics_and_answers_the_time(host):
    from std_msgs.msg import Float64

    host.handle(ID_PUBLISHER, _topic_info(125, "wheel0_Vel", "std_msgs/Float64", Float64._md5sum))
    host.handle(125, struct.pack("<d", 53.25))
    assert [(t, m.data) for t, m in host.rospy.published] == [("wheel0_Vel", 53.25)]
    host.rospy.now = 7.25
    host.handle(ID_TIME, b"")
    (answer,) = host.frames()
    assert answer.topic_id == ID_TIME and struct.unpack("<II", answer.message) == (7, 250_000_000)
    # a type whose md5sum differs from Debian's is refused, one line
    host.handle(ID_PUBLISHER, _topic_info(126, "wheel1_Vel", "std_msgs/Float64", "0" * 32))
    assert 126 not in host.publishers and "md5sum" in host.rospy.errors[-1]


def test_a_frame_before_negotiation_or_no_time_request_for_15_s_makes_the_host_ask_again(host):
    host.handle(130, struct.pack("<d", 1.0))  # a client that publishes before it was configured
    assert [f.topic_id for f in host.frames()] == [ID_PUBLISHER] and host.topic_requests == 1
    host.check_sync()  # starts counting
    host.rospy.now += 14.0
    host.handle(ID_TIME, b"")
    host.rospy.now += 14.0
    host.check_sync()  # 14 s since the last time request: still in sync
    assert host.renegotiations == 0
    host.rospy.now += 1.5
    host.check_sync()  # 15.5 s: serial_node's 3 x 5 s
    assert host.renegotiations == 1 and [f.topic_id for f in host.frames()][-1] == ID_PUBLISHER


DRIVE = """
import sys
import rospy
from amr_idea_control.srv import RequestPacket
from std_msgs.msg import Float64
rospy.init_node("test_drive")
print("ready", flush=True)
# the host has configured the board and is connected to the service's wheel_Command
sys.stdin.readline()
rospy.ServiceProxy("/wheel_Command_Service", RequestPacket)(1, 40.0, 1, 40.0)
# the board's speed, through the pseudo-terminal and the host, on the graph
while not rospy.is_shutdown():
    speed = rospy.wait_for_message("/wheel0_Vel", Float64, timeout=120).data
    if speed > 20.0:
        print(speed, flush=True)
        break
"""


@needs_ros1
@needs_avr
def test_listing_4_1s_launch_on_the_twins_serial_port_moves_the_emulated_board(
    ros_env, catkin_setup, tmp_path
):
    from conftest import connected_subscribers, services, wait_for

    pty = tmp_path / "ttyACM0"
    # the launch file first: its host waits for the port (as upstream's does); the twin then creates
    # it
    launch = subprocess.Popen(
        in_workspace(
            catkin_setup,
            f"roslaunch amr_idea_bringup amr_idea.launch port:={pty} "
            "serial_pkg:=amr_idea_bringup serial_type:=rosserial_host",
        ),
        env=ros_env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    drive = twin = None
    try:
        (tmp_path / "drive.py").write_text(DRIVE)
        drive = subprocess.Popen(
            in_workspace(catkin_setup, f"/usr/bin/python3 {tmp_path / 'drive.py'}"),
            env=ros_env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        assert drive.stdout.readline().strip() == "ready"
        wait_for(
            lambda: "/wheel_Command_Service" in services(ros_env),
            "the launch file's service on the graph",
        )
        twin = subprocess.Popen(
            [
                AMR_TWIN,
                "run",
                "stop",
                "--firmware",
                "avr",
                "--serial-pty",
                str(pty),
                "--ros1",
                "--rate",
                "4",
                "--duration-s",
                "30",
                "--world",
                "empty",
                "--json",
            ],
            env=ros_env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        wait_for(
            lambda: (
                "/serial_node"
                in connected_subscribers(ros_env, "/wheel_Command_Service", "/wheel_Command")
            ),
            "the host negotiated the board's topics and connected to the service",
        )
        speed, why = drive.communicate("go\n", timeout=120)
        assert speed and float(speed) > 20.0, why
        out, err = twin.communicate(timeout=120)
    finally:
        for proc in (drive, twin):
            if proc is not None and proc.poll() is None:
                proc.kill()
        stop(launch)
    assert twin.returncode == 0, err
    assert not pty.exists() and not pty.is_symlink()  # the link goes with the run
    wheels = json.loads(out)["wheels"]
    assert all(abs(wheels[w]["true_final_rpm"] - 40.0) < 4.0 for w in ("left", "right"))
    # one negotiation in 30 simulated s: the board's time requests (every 5 s) kept serial_node's 15
    # s watchdog quiet, so the host never renegotiated
    found = re.search(r"answered (\d+) topic negotiation\(s\) and asked the time (\d+) time", err)
    assert found and int(found.group(1)) == 1 and int(found.group(2)) >= 4, err
