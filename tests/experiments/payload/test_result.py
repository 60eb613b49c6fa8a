"""A sweep point's typed result (experiments/payload/result.py) and the flat row written from it."""

import json
import math

from amr_twin.experiments.payload.result import (
    Dynamics,
    Electrics,
    MinWheel,
    PointResult,
    Statics,
    WheelRun,
)

LOADS = {
    "wheel_left": 65.6,
    "wheel_right": 65.6,
    "caster_front_left": 40.0,
    "caster_front_right": 40.0,
    "caster_rear_left": 43.3,
    "caster_rear_right": 43.3,
}


def _point(**kw) -> PointResult:
    return PointResult("m0kg_center_motor", "f" * 16, 0.0, "center", "motor:left:0.5", **kw)


def test_an_invalid_point_writes_only_what_it_reached():
    bad = _point(valid=False, error="payload.xy_m: outside the deck")
    assert list(bad.as_json()) == [
        "key",
        "fingerprint",
        "mass_kg",
        "position",
        "command",
        "valid",
        "error",
        "safe",
    ]
    placed = _point(valid=False, error="x", xy_m=(0.5, 0.0), sample=3, sample_id="abc").as_json()
    assert (
        list(placed)[7:] == ["sample", "sample_id", "x_m", "y_m", "safe"] and placed["x_m"] == 0.5
    )
    assert placed["safe"] is False


def test_a_run_flattens_in_the_rows_order_with_non_finite_numbers_as_null():
    step = {
        "delay_s": 1.0,
        "rise_s": 2.0,
        "peak_s": math.nan,
        "settling_s": 3.0,
        "overshoot_rpm": 0.0,
        "steady_error_rpm": 1.5,
        "oscillation_rpm": 0.2,
    }
    steady = {
        "true_steady_error_rpm": 0.5,
        "steady_duty": 0.2,
        "open_loop_duty": 0.04,
        "steady_slip_ratio": 0.01,
    }
    dyn = Dynamics(
        0.1,
        60.0,
        35.0,
        "",
        59.0,
        MinWheel("right", 0.9, [0.7, -0.3], 61.0, "static load split"),
        Electrics((0.9, 0.1), 0.5, 100.0, 2.0, 50.0),
        False,
        (WheelRun("left", 38.2, 0.01, step, steady), WheelRun("right", 0.0, 0.0)),
        True,
    )
    row = _point(
        xy_m=(0.0, 0.0),
        statics=Statics(30.4, 0.23, 40.0, "", LOADS),
        dynamics=dyn,
        current_limit_a=11.1,
        motor_overload=False,
        safe=True,
        wall_s=0.2,
    ).as_json()
    keys = list(row)
    assert keys[keys.index("static_lifted") + 1 : keys.index("max_tilt_deg")] == [
        f"static_{k}_n" for k in LOADS
    ]
    assert keys[
        keys.index("dyn_min_wheel_contact_n") + 1 : keys.index("left_steady_current_a")
    ] == [
        "dyn_min_wheel",
        "dyn_min_wheel_t_s",
        "dyn_min_wheel_accel_m_s2",
        "dyn_min_wheel_quasi_static_n",
        "dyn_min_wheel_mechanism",
    ]
    assert (
        keys.index("wheel_lift_off")
        < keys.index("left_reference_rpm")
        < keys.index("left_delay_s")
        < keys.index("left_steady_slip_ratio")
        < keys.index("right_reference_rpm")
        < keys.index("tracks")
    )
    assert "right_delay_s" not in row and row["right_max_slip_m_s"] == 0.0  # no reference: no step
    assert keys[-4:] == ["current_limit_a", "motor_overload", "safe", "wall_s"]
    assert row["left_peak_s"] is None and row["dyn_min_wheel"] == "right"
    json.dumps(row, allow_nan=False)
