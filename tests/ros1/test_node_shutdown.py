"""A rospy node shut down by ``shut_down`` leaves no server thread behind: none polls a closed
socket (taking the GIL in a busy loop, which the interpreter's exit can meet), none is left
listening. Each in a process of its own (one rospy node a process) on the folder's master."""

import json
import socket
import subprocess
import sys

from conftest import needs_ros1

pytestmark = needs_ros1

NODE = """
import json, sys, time
from amr_twin.ros1.installation import import_rospy
from amr_twin.ros1.node_shutdown import server_loops, shut_down
rospy = import_rospy()
rospy.init_node("test_node_shutdown", anonymous=True, disable_signals=True)
before = sorted({kind for _i, kind, _s in server_loops()})
port = rospy.impl.tcpros_base.get_tcpros_server_address()[1]
if sys.argv[1] == "shut_down":
    left = shut_down(rospy, "the test is over")
else:  # what rospy alone leaves
    rospy.signal_shutdown("the test is over")
    left = None
after = sorted({kind for _i, kind, _s in server_loops()})
t0 = time.process_time()
time.sleep(1.0)
cpu_s = time.process_time() - t0
print(json.dumps(dict(before=before, left=left, after=after, port=port, cpu_s=cpu_s)), flush=True)
sys.stdin.read()  # the test tries the TCPROS port while the process lives
"""


def _node(ros_env, how: str) -> tuple[dict, bool]:
    """The node's report after shutting down ``how``, and whether its TCPROS port still takes a
    connection then."""
    proc = subprocess.Popen(
        [sys.executable, "-c", NODE, how],
        env=ros_env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()
        assert line, proc.communicate(timeout=60)[1]
        report = json.loads(line)
        try:
            socket.create_connection(("127.0.0.1", report["port"]), timeout=5).close()
            listening = True
        except OSError:
            listening = False
        _out, err = proc.communicate("", timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    return report, listening


def test_shut_down_ends_rospys_server_threads_and_leaves_no_busy_loop_or_listener(ros_env):
    report, listening = _node(ros_env, "shut_down")
    assert report["before"] == ["serve", "tcpros", "xmlrpc"], report
    assert report["left"] == [] and report["after"] == [], report
    assert report["cpu_s"] < 0.05, report  # idle: nothing polls a closed socket
    assert not listening, report


def test_rospys_own_shutdown_leaves_them_running_which_shut_down_exists_for(ros_env):
    report, listening = _node(ros_env, "signal_shutdown")
    assert report["after"] == ["serve", "tcpros", "xmlrpc"], report
    assert report["cpu_s"] > 0.05, report  # XML-RPC's serve_forever polls its closed socket
    assert listening, report  # the blocked accept keeps the closed socket listening
