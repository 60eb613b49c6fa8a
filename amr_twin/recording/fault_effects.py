"""What each injected fault did to a run (:class:`~amr_twin.sim.fault_injector.FaultInjector`), from
the run's series: the ``faults`` of a run's result and of ``amr-twin run --json``."""

from __future__ import annotations

import numpy as np

from amr_twin.recording.recorder import RunSeries, signed_published
from amr_twin.sim.fault_injector import FaultInjector
from amr_twin.sim.faults import WHEEL_NAMES

WINDOW_S = 0.5
"""Averaging window of the speeds before a fault and at the end of the run, s."""


def fault_effects(injector: FaultInjector, series: RunSeries) -> list[dict]:
    """Each fault (:meth:`Fault.describe`) with ``effect``: what the wheels and sensors did.

    Per wheel: mean true speed in the :data:`WINDOW_S` before the fault and at the
    end of the run, the largest true speed after the fault (RPM, signed +
    forward), the wheel speeds the firmware published after the fault (count and
    last value) and the PWM counts at the end. For the robot: the distance it
    travelled after the fault, m. For sensor faults: the messages published after it
    (and, for the IMU, how many distinct gyro/accelerometer readings they carried).
    """
    t = series.t_s
    out = []
    for fault in injector.faults:
        after = t >= fault.t_s
        before = (t < fault.t_s) & (t >= fault.t_s - WINDOW_S)
        end = t >= t[-1] - WINDOW_S
        wheels = {}
        for w, name in enumerate(WHEEL_NAMES):
            rpm = series.true_rpm[:, w]
            pub = signed_published(series, w)
            pub_after = pub[pub[:, 0] >= fault.t_s] if len(pub) else pub
            peak = rpm[after][np.argmax(np.abs(rpm[after]))] if after.any() else float("nan")
            wheels[name] = {
                "true_rpm_before": _mean(rpm[before]),
                "true_rpm_end": _mean(rpm[end]),
                "true_rpm_peak_after": round(float(peak), 3),
                "published_after": int(len(pub_after)),
                "last_published_rpm": round(float(pub[-1, 1]), 3) if len(pub) else None,
                "last_published_t_s": round(float(pub[-1, 0]), 4) if len(pub) else None,
                "pwm_counts_end": int(series.pwm_counts[-1, w]),
            }
        xy = series.pose[after, :2]
        effect = {
            "wheels": wheels,
            "moved_after_m": round(float(np.sum(np.hypot(*np.diff(xy, axis=0).T))), 4)
            if len(xy) > 1
            else 0.0,
        }
        for topic in ("scan", "imu/data_raw"):
            if topic in injector.sensor_times:
                times = np.array(injector.sensor_times[topic]) * 1e-6
                effect[f"{topic}_published_after"] = int(np.sum(times >= fault.t_s))
        if "imu/data_raw" in injector.sensor_times:
            times = np.array(injector.sensor_times["imu/data_raw"]) * 1e-6
            after_values = [v for v, t_m in zip(injector.imu_values, times) if t_m >= fault.t_s]
            effect["imu/data_raw_distinct_values_after"] = len(set(after_values))
        out.append(dict(fault.describe(), effect=effect))
    return out


def _mean(values: np.ndarray):
    return round(float(np.mean(values)), 3) if len(values) else None
