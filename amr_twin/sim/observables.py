"""What a running twin shows the code downstream of its loop: :class:`Observables`
(``twin.observables``).

After dm_control's observables: the recorder, the live views, the bridges and the experiments read
the twin's state here (and subscribe to its hooks, :mod:`amr_twin.sim.hooks`) rather than reaching
into its physics, plant, hall sensors or firmware. Every reading is of the instant the twin is at
when it is called: in a grid sampler (``on_grid``), the physics at that grid instant.
"""

from __future__ import annotations

from amr_twin.sim.grid_rows import GridRows, gather


class Observables:
    """Read-only views of one robot's state in its world (module notes); built by
    :class:`~amr_twin.assembly.robot.Robot`."""

    def __init__(self, physics, grid, actuation, battery, collisions, columns=None):
        self._physics, self._grid, self._actuation = physics, grid, actuation
        self._columns = columns  # the robot's columns of the grid's row; None: all of it
        self._battery, self._collisions = battery, collisions

    @property
    def model(self):
        """The compiled MjModel (names, geometry, meshes: what does not change while the twin
        runs)."""
        return self._physics.model

    @property
    def named(self):
        """The physics' named views (:class:`~amr_twin.sim.named_index.NamedIndex`):
        ``named.data.xpos["amr/base_link"]``. Read them; writing MuJoCo's state is the physics
        layer's."""
        return self._physics.named

    def loop_sensors(self) -> list[float]:
        """The loop sensors' row now (:data:`~amr_twin.model.robot_spec.LOOP_SENSOR_DIM` values:
        wheel angles L, R rad; wheel speeds L, R rad/s; base position x, y, z m; base quaternion w,
        x, y, z)."""
        row = self._grid.row()
        return row if self._columns is None else row[self._columns]

    def drive(self) -> list[float]:
        """The drive in force (:attr:`amr_twin.sim.actuation.Actuation.row`): PWM counts L, R; DIR
        L, R (+1/-1); mode codes L, R; phase voltages L, R, V."""
        return self._actuation.row

    def battery(self) -> list[float]:
        """``[terminal_v, current_a, soc]`` as the battery's last accounting (on the grid) left them
        (V, A, 1)."""
        return self._battery.grid_state()

    def battery_rows(self) -> GridRows:
        """A grid sampler keeping ``t_us, terminal_v, current_a, soc`` at each grid instant it runs
        (hook it after the battery's accounting, which the twin runs first); with its C form."""
        b = self._battery
        return GridRows(3, 1, b.grid_state, gather(b.grid_state_addresses()))

    @property
    def collisions(self) -> list:
        """The collisions so far (:class:`~amr_twin.sim.collisions.Collision`, in order; a live
        list)."""
        return self._collisions.collisions
