"""The wheel odometry's calibration file (controllers/odometry_calibration.py): read, refused in one
line when bad, and applied by the odometry node (TwinOptions.odometry_calibration, amr-twin run
--odometry)."""

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.controllers.odometry_calibration import OdometryCalibration, load, text
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions

GOOD = OdometryCalibration(0.1262, 0.1250, 0.4900, "a test")


def test_text_and_load_give_the_calibration_back(tmp_path):
    path = tmp_path / "odom.yaml"
    path.write_text(text(GOOD, "from a test\nsecond line"))
    assert load(path) == GOOD


@pytest.mark.parametrize(
    "body, names",
    [
        ("wheel_odometry: [1, 2]", "expected a 'wheel_odometry:' mapping"),
        (
            "wheel_odometry:\n  left_wheel_radius_m: 0.125\n  right_wheel_radius_m: 0.125\n",
            "wheel_separation_m",
        ),
        (
            "wheel_odometry:\n  left_wheel_radius_m: 0.5\n  right_wheel_radius_m: 0.125\n  "
            "wheel_separation_m: 0.48\n",
            "left_wheel_radius_m: 0.5, expected a number in [0.05, 0.3]",
        ),
        (
            "wheel_odometry:\n  left_wheel_radius_m: .nan\n  right_wheel_radius_m: 0.125\n  "
            "wheel_separation_m: 0.48\n",
            "left_wheel_radius_m",
        ),
        (
            "wheel_odometry:\n  left_wheel_radius_m: true\n  right_wheel_radius_m: 0.125\n  "
            "wheel_separation_m: 0.48\n",
            "left_wheel_radius_m",
        ),
        (
            "wheel_odometry:\n  left_wheel_radius_m: 0.125\n  right_wheel_radius_m: 0.125\n  "
            "wheel_separation_m: 0.48\n"
            "  wheel_base: 1\n",
            "wheel_base: unknown key",
        ),
        ("{{{", "not valid YAML"),
    ],
)
def test_a_bad_file_is_refused_naming_the_file_and_field(tmp_path, body, names):
    path = tmp_path / "odom.yaml"
    path.write_text(body)
    with pytest.raises(ValueError) as err:
        load(path)
    message = str(err.value)
    assert names in message and str(path) in message and "\n" not in message


def _drive(calibration, left_m_s: float, right_m_s: float):
    """The same drive each time (the odometry only watches it): its smoothed (hindsight) pose."""
    twin = Twin(
        load_config(sets=["wheel.tyre_slip=false"]),
        TwinOptions(world="empty", firmware="improved", odometry_calibration=calibration),
    )
    twin.client.wheels(left_m_s, right_m_s)
    twin.advance(4.0)
    twin.client.stop()
    twin.advance(1.0)
    return twin.nodes["odometry"].smoothed_pose()


def test_the_node_turns_with_the_calibrated_wheelbase():
    """On an arc the heading is (r_R theta_R - r_L theta_L) / b: a wheelbase 0.49 m instead of
    0.48 m turns the same wheel angles 0.48 / 0.49 as far."""
    nominal = _drive(None, 0.3, 0.5)
    wider = _drive(OdometryCalibration(0.125, 0.125, 0.49), 0.3, 0.5)
    assert nominal[2] > 0.5 and wider[2] == pytest.approx(nominal[2] * 0.48 / 0.49, rel=1e-9)


def test_the_node_rolls_each_wheel_on_its_calibrated_radius():
    """Straight ahead with the left radius 1.2 mm larger: the node sees the left wheel travel
    0.96 % further, so it turns right by 0.0012 theta_L / b (theta_L = x / r)."""
    nominal = _drive(None, 0.4, 0.4)
    left = _drive(OdometryCalibration(0.1262, 0.125, 0.48), 0.4, 0.4)
    turn = -0.0012 * (nominal[0] / 0.125) / 0.48
    assert nominal[0] > 1.0 and left[2] - nominal[2] == pytest.approx(turn, rel=0.02)
    assert left[0] == pytest.approx(nominal[0] * (1 + 0.0012 / 0.25), rel=1e-3)


def test_amr_twin_run_takes_the_file_and_refuses_a_bad_one_in_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("wheel_odometry:\n  left_wheel_radius_m: 0.125\n")
    res = CliRunner().invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--duration-s",
            "1",
            "--world",
            "empty",
            "--odometry",
            str(bad),
        ],
    )
    assert (
        res.exit_code == 2
        and len(res.output.strip().splitlines()) == 1
        and "bad.yaml" in res.output
    )
    assert "right_wheel_radius_m" in res.output
    good = tmp_path / "good.yaml"
    good.write_text(text(OdometryCalibration(0.1300, 0.1300, 0.48)))
    outs = []
    for extra in ([], ["--odometry", str(good)]):
        res = CliRunner().invoke(
            app,
            [
                "run",
                "linear",
                "--speed-m-s",
                "0.5",
                "--duration-s",
                "3",
                "--world",
                "empty",
                "--firmware",
                "improved",
                "--json",
                *extra,
            ],
        )
        assert res.exit_code == 0, res.output
        outs.append(json.loads(res.output[res.output.index("{") :]))
    assert _odom_x(outs[1]) == pytest.approx(_odom_x(outs[0]) * 0.1300 / 0.125, rel=2e-3)


def _odom_x(result: dict) -> float:
    return result["final_odom_pose"]["x_m"]
