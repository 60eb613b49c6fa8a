"""The time-series streams of a ``.rrd`` recording, one ``_log_<stream>`` function per stream.

All on the ``sim_time`` timeline (:data:`TIMELINE`, durations in s), a robot of a fleet's
under its name (``amr-2/wheels/...``; the functions' ``root``)::

    wheels/{left,right}/{reference,published,true}_rpm   Scalars, RPM
    duty/{left,right}                   analogWrite counts
    electrics/{left,right}/current_a    Scalars, motor (phase) current, A, + driving forward
    electrics/battery/{current_a,voltage_v}  Scalars, the pack
    imu/{accel,gyro,mag}                Scalars (x, y, z), m/s^2, rad/s, T
    commands                            TextLog of wheel_Command and the client calls

The entities of the 3D view are in :mod:`amr_twin.recording.rerun_world`; the file is written by
:func:`amr_twin.recording.rerun_log.write_rrd`.
"""

from __future__ import annotations

import numpy as np

from amr_twin.recording.recorder import signed_published
from amr_twin.recording.rerun_capture import Capture

TIMELINE = "sim_time"
WHEELS = ("left", "right")


def _time(t_s) -> list:
    import rerun as rr

    return [rr.TimeColumn(TIMELINE, duration=np.asarray(t_s, float))]


def _scalars(rec, path: str, t_s, values) -> None:
    import rerun as rr

    values = np.asarray(values, float)
    if len(values):
        rec.send_columns(path, indexes=_time(t_s), columns=rr.Scalars.columns(scalars=values))


def reference_rpm(series) -> np.ndarray:
    """Signed reference (motion x speed) of each wheel at ``series.t_s``, held; (n, 2), 0 before."""
    cmd_t = np.array([c[0] for c in series.commands], float)
    cmd = np.array([c[1] for c in series.commands], float).reshape(-1, 4)
    idx = np.searchsorted(cmd_t, series.t_s, side="right") - 1
    ref = (
        np.column_stack([cmd[:, 0] * cmd[:, 1], cmd[:, 2] * cmd[:, 3]])
        if len(cmd)
        else np.zeros((1, 2))
    )
    return np.where((idx >= 0)[:, None], ref[np.clip(idx, 0, None)], 0.0)


def _log_wheel_speeds(rec, series, root: str = "") -> None:
    ref = reference_rpm(series)
    for w, name in enumerate(WHEELS):
        _scalars(rec, f"{root}wheels/{name}/reference_rpm", series.t_s, ref[:, w])
        pub = signed_published(series, w)  # signed like the reference and the true speed
        _scalars(rec, f"{root}wheels/{name}/published_rpm", pub[:, 0], pub[:, 1])
        _scalars(rec, f"{root}wheels/{name}/true_rpm", series.t_s, series.true_rpm[:, w])


def _log_duty(rec, series, root: str = "") -> None:
    for w, name in enumerate(WHEELS):
        _scalars(rec, f"{root}duty/{name}", series.t_s, series.pwm_counts[:, w])


def _log_electrics(rec, series, root: str = "") -> None:
    for w, name in enumerate(WHEELS):
        _scalars(rec, f"{root}electrics/{name}/current_a", series.t_s, series.current_a[:, w])
    _scalars(rec, f"{root}electrics/battery/current_a", series.t_s, series.battery_a)
    _scalars(rec, f"{root}electrics/battery/voltage_v", series.t_s, series.battery_v)


def _log_commands(rec, series, result=None, root: str = "") -> None:
    import rerun as rr

    for t_s, command in result.commands if result is not None else []:
        rec.set_time(TIMELINE, duration=float(t_s))
        rec.log(f"{root}commands", rr.TextLog(f"client {command.describe()}", level="INFO"))
    for t_s, data in series.commands:
        rec.set_time(TIMELINE, duration=float(t_s))
        rec.log(
            f"{root}commands",
            rr.TextLog("wheel_Command [" + ", ".join(f"{v:g}" for v in data) + "]", level="INFO"),
        )


def _log_imu(rec, capture: Capture, root: str = "") -> None:
    imu = capture.messages.get("imu/data_raw", [])
    if imu:
        t = [msg.header.stamp.to_sec() for _, msg in imu]
        _scalars(
            rec,
            f"{root}imu/accel",
            t,
            [
                (m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z)
                for _, m in imu
            ],
        )
        _scalars(
            rec,
            f"{root}imu/gyro",
            t,
            [(m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z) for _, m in imu],
        )
    mag = capture.messages.get("imu/mag", [])
    if mag:
        t = [msg.header.stamp.to_sec() for _, msg in mag]
        _scalars(
            rec,
            f"{root}imu/mag",
            t,
            [(m.magnetic_field.x, m.magnetic_field.y, m.magnetic_field.z) for _, m in mag],
        )
