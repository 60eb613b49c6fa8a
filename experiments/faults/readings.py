"""The fault study's readings: what the measurements say, case by case, each number from the run
(:func:`reading`), and a number as ``faults.md`` prints it (:func:`number`)."""

from __future__ import annotations

import math

from amr_twin.experiments.faults.experiment import FIRMWARES, REFERENCE_RPM, STOP_T_S
from amr_twin.sim.faults import parse_fault


def number(value, fmt: str = ".1f") -> str:
    """``value`` formatted with ``fmt``; ``-`` for none or not finite, never ``-0.0``."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    text = format(value, fmt)
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text  # no "-0.0"


def _pair(rows: dict, key) -> tuple:
    return tuple(key(rows[fw]) for fw in FIRMWARES)


def reading(case: str, rows: dict) -> str:
    """What the measurements say, case by case (each number from this run)."""
    fa, im = rows["faithful"], rows["improved"]
    L = lambda r, k: r["wheels"]["left"][k]  # noqa: E731
    kind = parse_fault(case).kind
    if kind == "hall-dead" and case.endswith(":a"):
        return (
            f"With one of three hall sensors stuck the SC line changes 60 times per revolution, "
            f"not 90. "
            f"The faithful firmware, timing 90 changes per sample, publishes "
            f"{number(L(fa, 'published_last_rpm'))} RPM "
            f"for a wheel turning at {number(L(fa, 'true_during_rpm'))} RPM (2/3); its PI corrects "
            f"once per sample by "
            f"Ki*T = 0.03 of the error and the wheel stays at {number(L(fa, 'true_during_rpm'))} "
            f"RPM. The improved "
            f"firmware also reads 2/3 of the speed, every 20 ms, and speeds the wheel up to "
            f"{number(L(im, 'true_during_rpm'))} RPM: the robot ends "
            f"{number(im['end_offset_m'], '.2f')} "
            f"m and "
            f"{number(im['end_heading_offset_deg'], '.0f')} deg from its fault-free run."
        )
    if kind == "hall-dead":
        return (
            f"The left SC line goes silent. The faithful firmware publishes "
            f"{L(fa, 'published_during')} left "
            f"speeds after the fault: its PI for that wheel only runs after a completed sample, "
            f"so the left "
            f"duty stays at {L(fa, 'pwm_before_stop')} counts and the wheel keeps turning open "
            f"loop at "
            f"{number(L(fa, 'true_during_rpm'))} RPM; the motion looks normal "
            f"({number(fa['end_offset_m'], '.2f')} m from the fault-free run) while the PC sees no "
            f"speed. The "
            f"improved firmware reads the silent wheel as stopped 150 ms later, publishes 0 and "
            f"raises its "
            f"command: the left wheel runs away to {number(L(im, 'true_during_rpm'))} RPM "
            "(reference "
            f"{REFERENCE_RPM:.1f}) and the robot turns "
            f"{number(abs(im['end_heading_offset_deg']), '.0f')} deg off its "
            f"course before the stop. Neither firmware checks that a driven wheel produces edges."
        )
    if kind == "hall-chatter":
        return (
            f"Spurious pulses add changes the firmwares count as rotation. The faithful firmware "
            f"completes its "
            f"90-change samples sooner ({L(fa, 'published_during')} left samples during the "
            f"fault instead of about "
            f"2), the last at {number(L(fa, 'published_last_rpm'))} RPM; its PI, clamped at zero "
            f"integral and with Kp = 0.001, barely moves the duty "
            f"({number(L(fa, 'true_during_rpm'))} RPM). The "
            f"improved firmware believes the wheel too fast and slows it to "
            f"{number(L(im, 'true_during_rpm'))} RPM: "
            f"the robot ends {number(abs(im['end_heading_offset_deg']), '.0f')} deg off its course."
        )
    if kind == "motor-stall":
        return (
            f"The jammed left wheel stops ({number(L(fa, 'true_during_rpm'))} and "
            f"{number(L(im, 'true_during_rpm'))} "
            f"RPM at the end of the jam) while the right one drives on: the robot pivots and ends "
            f"{number(abs(fa['end_heading_offset_deg']), '.0f')} deg (faithful) and "
            f"{number(abs(im['end_heading_offset_deg']), '.0f')} deg (improved) off its course. "
            f"Neither firmware "
            f"notices the stall or stops the other wheel; both resume the left wheel when the "
            f"jam clears "
            f"({number(L(fa, 'true_before_stop_rpm'))} and "
            f"{number(L(im, 'true_before_stop_rpm'))} RPM "
            f"before the stop)."
        )
    if kind == "wheel-lifted":
        lifted = (
            f"The lifted wheel spins freely at {number(L(fa, 'true_during_rpm'))} RPM (faithful) "
            "and "
            f"{number(L(im, 'true_during_rpm'))} RPM (improved). "
        )
        if max(fa["end_offset_m"], im["end_offset_m"]) < 0.05:
            return lifted + (
                "The robot keeps its course: nothing resists its rolling, so at constant speed the "
                "one wheel still on the ground needs no force and makes no turning moment."
            )
        return lifted + (
            f"Only the right wheel drives, against the rolling resistance of the casters and of "
            f"itself: the robot turns {number(abs(fa['end_heading_offset_deg']), '.0f')} deg "
            f"(faithful) "
            f"and {number(abs(im['end_heading_offset_deg']), '.0f')} deg (improved) towards the "
            "lifted "
            "side during the 2 s, and neither firmware can tell: the lifted wheel's speed is "
            "what it commanded."
        )
    if kind == "rosserial-loss" and "0.3" not in case:
        return (
            f"With the link cut the stop sent at {STOP_T_S:g} s never arrives. Neither firmware "
            f"has a "
            f"watchdog on the link: the faithful one drives on at "
            f"{number(L(fa, 'true_before_stop_rpm'))} RPM and "
            f"the robot covers {number(fa['moved_after_stop_m'], '.2f')} m after the stop "
            "(improved: "
            f"{number(im['moved_after_stop_m'], '.2f')} m; fault-free: "
            f"{number(fa['baseline_moved_after_stop_m'], '.2f')} m), "
            f"still moving at the end of the run. The PC receives no wheel speed either "
            f"({L(fa, 'published_during')} and {L(im, 'published_during')} left samples)."
        )
    if kind == "rosserial-loss":
        return (
            f"30 % of the frames are lost (seeded). The wheel speeds reaching the PC thin out "
            f"({L(fa, 'published_during')} faithful and {L(im, 'published_during')} improved "
            f"left samples "
            f"during the fault); with this seed the stop frame arrived "
            f"({'stopped' if fa['stopped_at_end'] and im['stopped_at_end'] else 'NOT stopped'} "
            f"at the end). A "
            f"lost stop is the previous case: nothing on the Arduino repeats or times out a "
            f"command."
        )
    if kind == "rosserial-latency":
        return (
            f"Every frame arrives 250 ms late: the stop takes effect 250 ms later and the robot "
            f"ends "
            f"{number(fa['end_offset_m'], '.2f')} m (faithful) and "
            f"{number(im['end_offset_m'], '.2f')} m "
            f"(improved) "
            f"further than without the delay; the published speeds reach the PC 250 ms older."
        )
    if kind == "lidar-dead":
        return (
            f"The firmware does not read the LiDAR: the motion is unchanged "
            f"({number(fa['end_offset_m'], '.2f')} m). "
            f"No scan is published after the fault ({fa['scan_published_after']} scans): a "
            f"consumer (SLAM, "
            f"LiDAR odometry) has to detect the silence itself."
        )
    if kind == "imu-stuck":
        return (
            f"The firmware does not read the IMU: the motion is unchanged. imu/data_raw keeps "
            f"its 100 Hz "
            f"rate ({fa['imu_published_after']} messages after the fault) with fresh stamps but "
            f"{fa['imu_distinct_after']} distinct reading(s): only a plausibility check (a gyro "
            f"that never "
            f"changes while the wheels turn) reveals it."
        )
    if kind == "battery-sag":
        return (
            f"The terminal voltage falls to {number(fa['min_battery_v'])} V. The drivers' output "
            f"falls with it: the "
            f"faithful firmware's PI, acting once per revolution with Ki*T = 0.03, leaves the "
            f"wheels at "
            f"{number(L(fa, 'true_during_rpm'))} RPM until the stop; the improved firmware's 50 Hz "
            f"PI holds "
            f"{number(L(im, 'true_during_rpm'))} RPM (duty {L(im, 'pwm_before_stop')} counts "
            "before "
            f"the stop)."
        )
    if kind in ("battery-cut", "estop"):
        what, back = (
            ("the drivers lose their supply", "power returns")
            if kind == "battery-cut"
            else ("the e-stop relays open the phases", "the button is released")
        )
        return (
            f"For 2 s {what}: the wheels coast down to {number(L(fa, 'true_during_rpm'))} RPM. "
            f"Neither firmware "
            f"knows (no feedback of the relay or supply state); their commands stay on and the "
            f"wheels come "
            f"back when {back}, the improved firmware overshooting to "
            f"{number(L(im, 'true_peak_rpm'))} RPM "
            f"(its integral grew while the slowing wheels were still inside its 8 RPM band). The "
            f"robot ends {number(fa['end_offset_m'], '.2f')} m and "
            f"{number(im['end_offset_m'], '.2f')} m from its fault-free runs."
        )
    return ""
