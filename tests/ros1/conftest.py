"""What the ROS 1 tests share: one private roscore for the folder's tests (a free port, stopped at
the end), the environment that points a process at it, and the catkin workspace built once (cached
by its sources' hash in the session's cache folder), and waits for conditions of the graph (bounded)
in place of fixed sleeps. Without Debian's ROS 1 every test that needs it is skipped, saying which
packages to install."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from amr_twin.ros1.installation import missing, ros_folder

MISSING = missing()
needs_ros1 = pytest.mark.skipif(MISSING is not None, reason=MISSING or "")
ROOT = Path(__file__).resolve().parents[2]
TWIN = [sys.executable, "-m", "amr_twin.cli.main"]


@pytest.fixture(scope="session")
def master():
    """A private roscore on a free port: its URI; stopped after the folder's tests."""
    if MISSING:
        pytest.skip(MISSING)
    from amr_twin.ros1.master import start_roscore

    m = start_roscore()
    yield m.uri
    m.stop()


@pytest.fixture(scope="session")
def ros_env(master):
    """The environment of a process on the test graph (ROS_MASTER_URI, ROS_IP)."""
    env = dict(os.environ, ROS_MASTER_URI=master, ROS_IP="127.0.0.1", PYTHONUNBUFFERED="1")
    env.pop("ROS_HOSTNAME", None)
    return env


@pytest.fixture(scope="session")
def catkin_setup(ros_env):
    """The devel space's setup.bash of the thesis' workspace (controllers/ros/build.sh)."""
    out = subprocess.run(
        ["bash", str(ros_folder() / "build.sh")],
        capture_output=True,
        text=True,
        env=ros_env,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def in_workspace(setup: str, command: str) -> list[str]:
    """``bash -c`` running ``command`` with the workspace sourced."""
    return ["bash", "-c", f"source {setup} && exec {command}"]


def stop(proc: subprocess.Popen, timeout_s: float = 10.0) -> None:
    """Ctrl-C a process (a ROS node, roslaunch) and wait for it."""
    if proc.poll() is None:
        proc.send_signal(2)
        try:
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


# -- waiting for the graph, not for the clock
# ------------------------------------------------------------ A test that sleeps a fixed time for a
# process to start or to connect fails on a loaded machine; these wait for the condition itself,
# with a bound, and say which one did not come.


def wait_for(condition, what: str, timeout_s: float = 60.0):
    """``condition()``'s first true value, polled every 50 ms; fails naming ``what`` after
    ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"not within {timeout_s:g} s: {what}")
        time.sleep(0.05)


def _master(env):
    import xmlrpc.client

    return xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])


def subscribers(env, topic: str) -> set[str]:
    """The nodes the master lists as subscribers of ``topic``."""
    _code, _msg, (_pubs, subs, _srvs) = _master(env).getSystemState("/test")
    return next((set(nodes) for t, nodes in subs if t == topic), set())


def services(env) -> set[str]:
    """The services the master lists."""
    _code, _msg, (_pubs, _subs, srvs) = _master(env).getSystemState("/test")
    return {name for name, _nodes in srvs}


def connected_subscribers(env, node: str, topic: str) -> set[str]:
    """The subscribers ``node`` (a publisher of ``topic``) has a live connection to: its bus
    information (the slave API's getBusInfo, which rospy and roscpp answer); empty while it is not
    on the graph."""
    import xmlrpc.client

    code, _msg, uri = _master(env).lookupNode("/test", node)
    if code != 1:
        return set()
    try:
        _code, _msg, links = xmlrpc.client.ServerProxy(uri).getBusInfo("/test")
    except OSError:
        return set()
    return {
        peer
        for _id, peer, direction, _transport, t, up, *_ in links
        if t == topic and direction == "o" and up
    }


def _child(pid: int) -> int:
    """The one child of ``pid`` (``rosbag record`` runs its recorder as a child)."""
    children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    assert len(children) == 1, children
    return int(children[0])


def _socket_states(pid: int) -> list[tuple[int, int]]:
    """(TCP state, bytes not read yet) of each TCP socket of ``pid``."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    out = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            f = line.split()
            if f[9] in inodes:
                out.append((int(f[3], 16), int(f[4].split(":")[1], 16)))
    return out


def _asleep(pid: int) -> bool:
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            state = (task / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state not in ("S", "D", "I"):
            return False
    return True


def wait_until_recorded(rosbag_pid: int, timeout_s: float = 60.0) -> None:
    """After the twin has exited: wait until ``rosbag record`` has taken every byte the twin wrote.
    Its recorder has read all of its sockets (none holds unread bytes or waits to be closed:
    CLOSE_WAIT, the twin's end gone) and all its threads sleep, three times in a row 50 ms apart
    (its callbacks done)."""
    recorder = _child(rosbag_pid)
    quiet = [0]

    def done():
        drained = all(
            state != 8 and unread == 0 for state, unread in _socket_states(recorder)
        )  # 8: CLOSE_WAIT
        quiet[0] = quiet[0] + 1 if drained and _asleep(recorder) else 0
        return quiet[0] >= 3

    wait_for(done, "rosbag record has read and handled every message", timeout_s)
