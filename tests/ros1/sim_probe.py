"""A rospy node (Debian's Python) that exercises a running twin's simulator interface and prints one
JSON object.

``python3 sim_probe.py NS NODE``: the twin is ``/NS/NODE``, driving (``run linear``) with one actor.
It counts ``/clock`` over wall windows before, during and after ``pause_physics``; reads the ground
truth, the odometry and the actors' poses stamped after ``reset_world``, a ``set_pose`` and
``reset_simulation``; keeps every ``/clock`` value it got (to check that time never goes back).
"""

import json
import math
import sys
import threading
import time

import rospy
from geometry_msgs.msg import PoseArray, PoseStamped
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Empty

ns, node = sys.argv[1], sys.argv[2]
rospy.init_node("sim_probe", disable_signals=True)
lock = threading.Lock()
clock, last = [], {}


def keep(name):
    def cb(msg):
        with lock:
            last.setdefault(name, []).append(msg)

    return cb


rospy.Subscriber("/clock", Clock, lambda m: clock.append(m.clock.to_sec()), queue_size=1000)
rospy.Subscriber(f"/{ns}/twin/ground_truth", Odometry, keep("gt"), queue_size=1000)
rospy.Subscriber(f"/{ns}/odom", Odometry, keep("odom"), queue_size=1000)
rospy.Subscriber(f"/{ns}/actors/poses", PoseArray, keep("actors"), queue_size=1000)
set_pose = rospy.Publisher(f"/{ns}/{node}/set_pose", PoseStamped, queue_size=1, latch=True)
call = {
    name: rospy.ServiceProxy(f"/{ns}/{node}/{name}", Empty)
    for name in ("pause_physics", "unpause_physics", "reset_world", "reset_simulation")
}
for proxy in call.values():
    proxy.wait_for_service(timeout=60)


def count_clock(window_s=1.0):
    n0 = len(clock)
    time.sleep(window_s)
    return len(clock) - n0


def first_after(name, t_s, timeout_s=20.0):
    """The first message of ``name`` stamped after simulated ``t_s``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with lock:
            for msg in last.get(name, []):
                stamp = msg.header.stamp.to_sec()
                if stamp > t_s:
                    return msg
        time.sleep(0.02)
    raise SystemExit(f"no {name} after t={t_s}")


def pose(msg):
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    return [
        p.x,
        p.y,
        math.degrees(math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))),
    ]


def speed(msg):
    v = msg.twist.twist.linear
    return math.hypot(v.x, v.y)


while not clock or clock[-1] < 4.0:  # driving for a while, the actor walking
    time.sleep(0.05)
out = {"running_hz": count_clock()}
call["pause_physics"]()
time.sleep(0.2)
out["paused_hz"] = count_clock()
call["unpause_physics"]()
out["resumed_hz"] = count_clock()
now = clock[-1]
out["before_reset"] = pose(first_after("gt", now))
out["actor_before"] = [
    first_after("actors", now).poses[0].position.x,
    first_after("actors", now).poses[0].position.y,
]
call["reset_world"]()
now = clock[-1]
gt = first_after("gt", now)
out["after_reset_world"], out["speed_after_reset_world"] = pose(gt), speed(gt)
actor = first_after("actors", now).poses[0].position
out["actor_after"] = [actor.x, actor.y]
msg = PoseStamped()
msg.header.frame_id = "map"
msg.pose.position.x, msg.pose.position.y = 2.0, 1.0
msg.pose.orientation.z, msg.pose.orientation.w = math.sin(math.pi / 4), math.cos(math.pi / 4)
set_pose.publish(msg)
deadline = time.monotonic() + 20
while time.monotonic() < deadline:
    with lock:
        seen = pose(last["gt"][-1])
    if abs(seen[0] - 2.0) < 0.1 and abs(seen[1] - 1.0) < 0.1:
        break
    time.sleep(0.02)
out["after_set_pose"] = seen
time.sleep(1.0)
call["reset_simulation"]()
now = clock[-1]
out["odom_after_reset_simulation"] = pose(first_after("odom", now))
out["gt_after_reset_simulation"] = pose(first_after("gt", now))
later = first_after("gt", now + 2.0)
out["speed_2s_after_reset_simulation"] = speed(later)
out["clock_went_back"] = sum(1 for a, b in zip(clock, clock[1:]) if b < a)
out["clock_last"] = clock[-1]
print(json.dumps(out), flush=True)
rospy.signal_shutdown("done")
