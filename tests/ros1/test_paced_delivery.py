"""Paced at real time, the twin writes each message when it is stamped, as a ROS node does: a
queue_size=1 rospy subscriber (Debian's rospy, a process of its own) gets nearly every IMU message
and every /clock, /clock arrives at 100 Hz, and an IMU stamp is ahead of the latest /clock the
subscriber had only when its clock thread handled that clock late (never by more than one clock
period; see below)."""

import json
import subprocess
import sys
from pathlib import Path


from conftest import needs_ros1, stop, subscribers, wait_for

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
WINDOW = (0.5, 5.5)
"""The stamps counted, simulated s: 500 IMU messages and 500 clocks of a 6 s run at --rate 1."""

SUBSCRIBER = """
import json, sys, threading, time
import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
lock, latest, clocks, imus = threading.Lock(), [-1.0], [], []
rospy.init_node("test_paced_delivery")
def on_clock(m):
    with lock:
        latest[0] = max(latest[0], m.clock.to_sec())
        clocks.append((m.clock.to_sec(), time.perf_counter()))
def on_imu(m):
    with lock:
        imus.append((m.header.stamp.to_sec(), m.header.stamp.to_sec() - latest[0]))
rospy.Subscriber("/clock", Clock, on_clock, queue_size=1)
rospy.Subscriber("/imu/data_raw", Imu, on_imu, queue_size=1)
print("ready", flush=True)
sys.stdin.read()  # the test closes it once the twin has exited
with lock:
    print(json.dumps({"clocks": clocks, "imus": imus}), flush=True)
"""


@needs_ros1
def test_paced_messages_go_one_by_one_at_their_stamps_behind_the_clock(ros_env):
    sub = subprocess.Popen(
        ["/usr/bin/python3", "-c", SUBSCRIBER],
        env=ros_env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert sub.stdout.readline().strip() == "ready"
        wait_for(
            lambda: "/test_paced_delivery" in subscribers(ros_env, "/imu/data_raw"),
            "the subscriber on the graph",
        )
        run = subprocess.run(
            [
                AMR_TWIN,
                "run",
                "stop",
                "--duration-s",
                "6",
                "--world",
                "empty",
                "--sensors",
                "--ros1",
                "--rate",
                "1",
            ],
            env=ros_env,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert run.returncode == 0, run.stderr
        got = json.loads(sub.communicate("", timeout=30)[0].splitlines()[-1])
    finally:
        stop(sub)
    lo, hi = WINDOW
    imus = [(s, lead) for s, lead in got["imus"] if lo <= s < hi]
    clocks = [(s, w) for s, w in got["clocks"] if lo <= s < hi]
    # per tick bursts (two IMU messages and two clocks in one write every 20 ms) kept half of each
    assert len(imus) >= 450, len(imus)
    assert len(clocks) >= 450, len(clocks)
    hz = (len(clocks) - 1) / (
        clocks[-1][1] - clocks[0][1]
    )  # as rostopic hz: arrivals over wall time
    assert 95.0 <= hz <= 105.0, hz
    # The twin writes each /clock before the messages of its instant (tests/ros1/test_outbox.py).
    # The subscriber reads each topic in a thread of its own, and on a busy machine its clock thread
    # is sometimes woken after the IMU's (1 to 4 % of the messages here): that IMU message then sees
    # the previous clock, one period (10 ms) back. Never more, and rarely; the burst per tick put 80
    # % of them ahead, by up to 20 ms.
    ahead = [lead for _s, lead in imus if lead > 1e-9]
    assert all(lead <= 0.010 + 1e-6 for lead in ahead), max(ahead)
    assert len(ahead) <= 0.1 * len(imus), len(ahead)
