"""``--ros1``, ``--roscore`` and ``--serial-pty``: their typer options and their check
(amr_twin.ros1.session, controllers/avr_serial_port.py).
"""

from __future__ import annotations

from typing import Callable, Optional

import typer


def ros1_options() -> dict[str, tuple[object, typer.models.OptionInfo]]:
    """``--ros1``, ``--roscore``, ``--serial-pty PATH`` (amr_twin.ros1.session,
    controllers/avr_serial_port.py)."""
    return {
        "ros1": (
            bool,
            typer.Option(
                False,
                "--ros1",
                help="Join the ROS 1 graph at ROS_MASTER_URI (Debian's ROS 1) "
                "and bridge the twin both ways: /clock (use_sim_time), /tf, /odom, /scan, "
                "/imu/*, /joint_states, "
                "... out; /wheel_Command and /cmd_vel in (docs/how-to/ros1.md). As fast as "
                "possible unless --rate.",
            ),
        ),
        "roscore": (
            bool,
            typer.Option(
                False,
                "--roscore",
                help="With --ros1: start a private roscore on a free "
                "port (its URI is printed) instead of joining ROS_MASTER_URI.",
            ),
        ),
        "serial_pty": (
            Optional[str],
            typer.Option(
                None,
                "--serial-pty",
                metavar="PATH",
                help="With --firmware avr: "
                "serve the emulated Mega's serial port on a pseudo-terminal linked at PATH (as "
                "/dev/ttyACM0 "
                "on the robot) for a rosserial host, paced to real time; the board is driven "
                "from ROS, not "
                "by the run's command (give `run stop`).",
            ),
        ),
    }


def checked_ros1(
    ros1: bool,
    roscore: bool,
    serial_pty: Optional[str],
    firmware: str,
    live_given: bool,
    rate: Optional[float],
    fail: Callable[[str], None],
):
    """``(Ros1Options or None, AvrParams or None, rate)`` of the ROS 1 options, checked before the
    work: ROS 1 installed, the master answering, the pseudo-terminal's path free. ``rate`` is the
    pacing of a run that is not served live: ``--rate``, else as fast as possible (0), or real time
    (1) with ``--serial-pty``."""
    import math

    if roscore and not ros1:
        fail("--roscore is an option of --ros1: give --ros1 (or drop --roscore)")
    from amr_twin.ros1.remapping import kept

    if kept() and not ros1:
        fail(
            f"ROS argument {kept()[0]!r} is for the twin's ROS 1 node: give --ros1 (or drop the "
            f"NAME:=VALUE arguments)"
        )
    params = None
    if serial_pty is not None:
        if not firmware.startswith("avr"):
            fail(
                f"--serial-pty serves the emulated board's serial port: give --firmware avr (got "
                f"{firmware})"
            )
        from amr_twin.controllers.avr_serial_port import pty_problem
        from amr_twin.controllers.firmware import AvrParams

        problem = pty_problem(serial_pty)  # a link left dangling by a killed twin is replaced
        if problem:
            fail(f"--serial-pty {serial_pty}: {problem}")
        params = AvrParams(serial_pty=serial_pty)
        if rate is not None and not (math.isfinite(rate) and 0 < rate <= 1000):
            fail(
                f"--rate {rate}: with --serial-pty the board's serial port runs paced: give a "
                f"rate in (0, 1000]"
            )
    if not live_given and rate is not None and not (math.isfinite(rate) and 0 <= rate <= 1000):
        fail(f"--rate {rate}: must be a finite number in [0, 1000] (0: as fast as possible)")
    options = None
    if ros1:
        from amr_twin.ros1.session import Ros1Options

        options = Ros1Options(roscore=roscore, firmware_topics=serial_pty is None)
        try:
            options.check()
        except ValueError as exc:
            fail(str(exc))
    default = 1.0 if serial_pty is not None else 0.0
    return options, params, default if rate is None else rate
