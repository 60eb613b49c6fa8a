"""A third party's sensor: defined here, registered by name through the public API (amr_twin),
listed in the options, built by the loop."""

from __future__ import annotations

import numpy as np
import pytest

from amr_twin import SENSORS, Twin, TwinOptions, attach_recorder, load_config
from amr_twin.sim.component import Mount  # the type of what a factory is handed
from amr_twin.ros.messages import Float64MultiArray

TOPIC = "wheel_angles"
PERIOD_US = 20_000


class WheelAngleSensor:
    """Publishes both wheels' angles (rad) on :data:`TOPIC` every ``period_us``: MuJoCo's
    ``amr/wheel_*_angle`` sensors read by name at its instant (the values the loop's rows hold)."""

    def __init__(self, physics, clock, bus, period_us: int):
        self.sensordata = physics.named.data.sensordata
        self.pub = bus.advertise(TOPIC, Float64MultiArray)
        self.readings = 0
        clock.schedule_every(period_us, period_us, self._tick)  # synced: the physics at its instant

    def _tick(self) -> None:
        self.readings += 1
        angles = [float(self.sensordata[f"amr/wheel_{side}_angle"]) for side in ("left", "right")]
        self.pub.publish(Float64MultiArray(data=angles))


def wheel_angle(mount: Mount, cfg) -> WheelAngleSensor:
    """The factory: the plain values the sensor needs from the mount; nothing of ``cfg``."""
    return WheelAngleSensor(mount.physics, mount.clock, mount.bus, PERIOD_US)


@pytest.fixture
def registered():
    SENSORS.register("wheel_angle", wheel_angle)
    yield
    SENSORS.unregister("wheel_angle")


def test_a_registered_sensor_listed_in_the_options_publishes_what_it_measured(registered):
    options = TwinOptions(world="empty", sensors=("wheel_angle",), nodes=(), visuals=False)
    twin = Twin(load_config(), options)
    recorder = attach_recorder(twin)
    got = []
    twin.on_message(lambda _topic, msg, t_us: got.append((t_us, msg.data)), topics=(TOPIC,))
    twin.client.linear(0.5)
    twin.advance(1.0)
    sensor = twin.sensors["wheel_angle"]
    assert isinstance(sensor, WheelAngleSensor) and sensor.readings == len(got) == 50
    assert [t for t, _ in got] == list(range(PERIOD_US, 1_000_001, PERIOD_US))
    series = recorder.series()  # the loop's own rows on its 10 ms grid
    at = {int(round(t * 1e6)): row for t, row in zip(series.t_s, series.wheel_angle_rad)}
    for t_us, angles in got:
        np.testing.assert_array_equal(angles, at[t_us], err_msg=f"t = {t_us} us")
    assert min(got[-1][1]) > 1.0  # the wheels turned: the readings are not all the resting angles


def test_an_unknown_sensor_is_refused_in_one_line_naming_the_choices():
    with pytest.raises(ValueError, match=r"^--sensors 'sonar': must be one of imu, lidar.* uwb"):
        Twin(load_config(), TwinOptions(world="empty", sensors=("sonar",)))


def test_sensors_are_a_tuple_of_names():
    with pytest.raises(ValueError, match=r"^sensors: True must be a tuple of sensor names"):
        TwinOptions(sensors=True)


def test_a_sensor_added_to_a_built_twin_joins_its_sensors(registered):
    twin = Twin(load_config(), TwinOptions(world="empty", nodes=(), visuals=False))
    assert twin.sensors == {}
    sensor = twin.add_sensor("wheel_angle")
    twin.advance(0.1)
    assert twin.sensors == {"wheel_angle": sensor} and sensor.readings == 5
    with pytest.raises(ValueError, match="'wheel_angle': the twin has it already"):
        twin.add_sensor("wheel_angle")
