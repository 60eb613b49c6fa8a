"""``--ros1``, ``--roscore``, ``--serial-pty``: refusals before anything is simulated, and no orphan
process."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from typer.testing import CliRunner

from conftest import needs_ros1
from amr_twin.cli.main import app
from amr_twin.ros1.master import free_port

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
runner = CliRunner()


def _refused(args, env=None):
    result = runner.invoke(app, args, env=env)
    assert result.exit_code == 2, result.output
    assert result.output.count("\n") == 1, result.output
    return result.output


@needs_ros1
def test_no_master_at_ros_master_uri_is_one_line_naming_it_before_any_simulation(tmp_path):
    uri = f"http://127.0.0.1:{free_port()}"
    csv = tmp_path / "run.csv"
    start = time.monotonic()
    out = _refused(
        ["run", "stop", "--duration-s", "1", "--ros1", "--csv", str(csv)],
        env={"ROS_MASTER_URI": uri},
    )
    assert time.monotonic() - start < 5.0  # 3 s to answer, and the command's own start-up
    assert uri in out and "--roscore" in out and not csv.exists()


def test_ros1_not_installed_is_one_line_naming_the_debian_packages(monkeypatch):
    from amr_twin.ros1 import installation

    monkeypatch.setattr(installation, "DIST_PACKAGES", "/nonexistent")
    out = _refused(["run", "stop", "--duration-s", "1", "--ros1", "--roscore"])
    assert "ROS 1 is not installed" in out and "python3-rospy" in out and "ros-core" in out
    assert "controllers/ros/install.sh" in out


def test_the_ros1_options_refuse_what_does_not_fit(tmp_path):
    assert "--roscore is an option of --ros1" in _refused(["run", "stop", "--roscore"])
    assert "give --firmware avr" in _refused(["run", "stop", "--serial-pty", str(tmp_path / "tty")])
    taken = tmp_path / "taken"
    taken.write_text("")
    assert f"--serial-pty {taken}: {taken} exists" in _refused(
        ["run", "stop", "--firmware", "avr", "--serial-pty", str(taken)]
    )
    assert "does not exist" in _refused(
        ["run", "stop", "--firmware", "avr", "--serial-pty", str(tmp_path / "no" / "tty")]
    )
    out = _refused(
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--firmware",
            "avr",
            "--serial-pty",
            str(tmp_path / "t"),
        ]
    )
    assert "drive it from ROS" in out and not (tmp_path / "t").exists()
    assert "--rate is an option of --live" in _refused(["run", "stop", "--rate", "2"])


def test_a_dangling_link_of_a_killed_twin_is_replaced_and_the_pty_carries_bytes_raw(tmp_path):
    from amr_twin.controllers.avr_serial_port import PtySerialPort

    path = tmp_path / "ttyACM0"
    os.symlink("/dev/pts/999999", path)
    port = PtySerialPort(str(path))
    try:
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        data = bytes(range(256))
        os.write(fd, data)
        time.sleep(0.05)
        assert (
            port.read() == data
        )  # no echo, no line discipline: 0x0a, 0x0d, 0x03 ... pass as they are
        port.write(data)
        time.sleep(0.05)
        assert os.read(fd, 1024) == data
        os.close(fd)
    finally:
        port.close()
    assert not path.is_symlink()


@needs_ros1
def test_the_twin_killed_leaves_no_roscore_behind():
    twin = subprocess.Popen(
        [
            AMR_TWIN,
            "run",
            "stop",
            "--duration-s",
            "600",
            "--world",
            "empty",
            "--ros1",
            "--roscore",
            "--rate",
            "1",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = twin.stderr.readline()
    assert line.startswith(
        "ros1: the twin is /amr_twin on a private roscore at http://127.0.0.1:"
    ), line
    port = line.split("http://127.0.0.1:")[1].split()[0]
    children = subprocess.run(
        ["pgrep", "-f", "--", f"-p {port}"], capture_output=True, text=True
    ).stdout.split()
    assert len(children) >= 2  # roscore and its rosmaster
    twin.send_signal(signal.SIGKILL)
    twin.wait()
    for _ in range(100):
        left = subprocess.run(
            ["pgrep", "-f", "--", f"-p {port}"], capture_output=True, text=True
        ).stdout.split()
        if not left:
            break
        time.sleep(0.1)
    assert not left, f"orphans: {left}"
