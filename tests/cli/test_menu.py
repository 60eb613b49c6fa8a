"""amr-twin client: the fig. 3.2 menu under a pseudo-terminal, the twin at 20x real time."""

import sys
from pathlib import Path

import pytest

pexpect = pytest.importorskip("pexpect")

AMR_TWIN = Path(sys.executable).with_name("amr-twin")


def _client(*args: str, columns: int = 120):
    """``amr-twin client ARGS`` under a pseudo-terminal, plain text."""
    return pexpect.spawn(
        str(AMR_TWIN),
        ["client", *args],
        encoding="utf-8",
        timeout=30,
        env={"TERM": "dumb", "NO_COLOR": "1", "COLUMNS": str(columns), "PATH": "/usr/bin:/bin"},
    )


def _quit(child) -> None:
    """Menu choice 0: the client says when it exits, then ends."""
    child.sendline("0")
    child.expect("exit at t=")
    child.expect(pexpect.EOF)


def test_menu_linear_then_stop_then_exit():
    child = _client("--rate", "20", "--firmware", "faithful")
    try:
        child.expect("Linear motion")
        child.expect("choice: ")
        child.sendline("1")
        child.expect(r"linear speed \[m/s\]: ")
        child.sendline("0.5")
        child.expect(r"sent wheel_Command \[1, 38\.19719, 1, 38\.19719\]")
        child.expect(r"wheel0_Vel \(left \)\s+(\d+\.\d+) RPM")  # first sample after ~1.7 s
        assert 25.0 < float(child.match.group(1)) < 55.0
        child.sendline("9")  # the prompt may be buried under speed lines: an unknown choice
        child.expect("unknown choice")
        child.sendline("1")
        child.expect(r"linear speed \[m/s\]: ")
        child.sendline("30")
        child.expect("ERROR: linear velocity not valid")
        child.sendline("3")
        child.expect(r"sent wheel_Command \[0, 0\.00000, 0, 0\.00000\]")
        _quit(child)
    finally:
        child.close()
    assert child.exitstatus == 0


def test_menu_live_foxglove_client_drives_and_menu_stops():
    """``client --live``: a Foxglove client's Twist and the menu drive the same twin."""
    pytest.importorskip("websockets")
    from rosbags.typesys import Stores, get_typestore

    from foxglove_client import FoxgloveClient

    ts = get_typestore(Stores.ROS2_HUMBLE)
    twist = ts.serialize_cdr(
        ts.types["geometry_msgs/msg/Twist"](
            linear=ts.types["geometry_msgs/msg/Vector3"](0.5, 0.0, 0.0),
            angular=ts.types["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0),
        ),
        "geometry_msgs/msg/Twist",
    )
    child = pexpect.spawn(
        str(AMR_TWIN),
        ["client", "--live", "--port", "0"],
        encoding="utf-8",
        timeout=30,
        env={"TERM": "dumb", "NO_COLOR": "1", "COLUMNS": "200", "PATH": "/usr/bin:/bin"},
    )
    try:
        child.expect(r"(ws://127\.0\.0\.1:\d+)")
        url = child.match.group(1)
        child.expect("choice: ")
        with FoxgloveClient(url) as client:
            client.wait_for_channels(["/wheel_Command"])
            client.subscribe(["/wheel_Command"])
            channel = client.advertise("/cmd_vel", "geometry_msgs/msg/Twist")
            client.pump(0.2)
            client.publish(channel, twist)
            got = client.pump(3.0, until=lambda: False)
            child.sendline("3")  # the menu's stop, on the same twin
            child.expect(r"sent wheel_Command \[0, 0\.00000, 0, 0\.00000\]")
            client.pump(1.0, got)
        commands = [
            list(ts.deserialize_cdr(d, "std_msgs/msg/Float64MultiArray").data)
            for _w, _n, _t, d in got
        ]
        assert commands[0] == pytest.approx(
            [1, 38.19719, 1, 38.19719], abs=1e-4
        )  # the Twist, via the diff drive
        assert [0, 0, 0, 0] in commands[1:]  # the watchdog's stop (0.5 s later), then the menu's
        child.sendline("0")
        child.expect(r"exit at t=(\d+\.\d+) s")
        assert float(child.match.group(1)) > 3.0
        child.expect(pexpect.EOF)
    finally:
        child.close()
    assert child.exitstatus == 0


def test_the_menu_reads_bounded_lines_from_a_pipe_or_a_file(tmp_path):
    """``amr-twin client < /dev/zero``: input() read the endless line whole (9 GB in 48 s). From a
    pipe or a file a line is at most MAX_LINE characters: a longer one is refused in one line (exit
    2); short answers are read as from a terminal."""
    import subprocess

    from amr_twin.cli.menu import MAX_LINE

    zeros = tmp_path / "zeros"
    zeros.write_bytes(bytes(20 * MAX_LINE))  # /dev/zero, bounded so that the unfixed menu ends too
    with open(zeros, "rb") as stdin:
        res = subprocess.run(
            [str(AMR_TWIN), "client", "--rate", "20"],
            stdin=stdin,
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert res.returncode == 2 and res.stderr.strip().splitlines() == [
        f"error: standard input: a line of the menu is at most {MAX_LINE} characters of text (a "
        f"choice, a number)"
    ]
    res = subprocess.run(
        [str(AMR_TWIN), "client", "--rate", "20"],
        input="1\n0.5\n3\n0\n",
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 0 and "sent wheel_Command [1, 38.19719, 1, 38.19719]" in res.stdout, (
        res.stderr
    )


def test_the_client_takes_a_world_as_the_run_commands_do():
    """``client`` had no ``--world``: the thesis' 0.7 m/s drove into the warehouse's south rack (at
    7.3 s) with no hint. In the empty world it drives on; the start line names the world."""
    child = _client("--rate", "20", "--world", "empty", columns=200)
    try:
        child.expect(r"world empty \(start x 0 m")
        child.expect("choice: ")
        child.sendline("1")
        child.expect(r"linear speed \[m/s\]: ")
        child.sendline("0.7")
        index = child.expect([r"\[collision\]", r"t=\s*1[01]\.\d+ s"])
        assert index == 1, child.before
        _quit(child)
    finally:
        child.close()
    assert child.exitstatus == 0
