"""What the ROS 1 tests share: one private roscore for the folder's tests (a free port, stopped at the end),
the environment that points a process at it, and the catkin workspace built once (cached by its sources'
hash in the session's cache folder). Without Debian's ROS 1 every test that needs it is skipped, saying
which packages to install."""

import os
import subprocess
import sys
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
    out = subprocess.run(["bash", str(ros_folder() / "build.sh")], capture_output=True, text=True, env=ros_env,
                         timeout=600)
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
