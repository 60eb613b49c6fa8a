"""Physics wrapper: the door to ``MjData``, always by name.

It holds the compiled model and its data, resolves one robot's joints, actuators,
geoms and sensors by name once (the robot named by its prefix: a world may hold several, each
addressed by a Physics of its own sharing the one MjData, :meth:`Physics.robot`), offers named
views of both (:attr:`Physics.named`, as dm_control's ``physics.named``) and what the rest of
the twin needs:
stepping in C, wheel angles and speeds, the base pose, and its components: the motors
(:mod:`~amr_twin.sim.motors`), the support's contact loads (:mod:`~amr_twin.sim.support`), a load
on the deck (:mod:`~amr_twin.sim.payload`), teleporting (:mod:`~amr_twin.sim.placement`).

The physics layer is this module and those that declare ``PHYSICS_LAYER = True`` with the
reason (C-speed callbacks and grid samplers, ray-casting sensors, the grid loop); no other
module touches MjData (tests/sim/test_physics_door.py).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from amr_twin.analysis.se2 import yaw_of_quaternion
from amr_twin.model.robot_spec import CASTERS, LOOP_SENSOR_DIM, WHEELS
from amr_twin.model.robot_starts import ROBOT_PREFIX
from amr_twin.model.tyre_numeric import numeric_name
from amr_twin.sim.motors import Motors
from amr_twin.sim.named_index import NamedIndex
from amr_twin.sim.payload import Payload
from amr_twin.sim.placement import Placement
from amr_twin.sim.robot_bodies import robot_indices
from amr_twin.sim.support import Support

PHYSICS_LAYER = True


class DivergenceError(RuntimeError):
    """The simulation produced NaN/inf or MuJoCo warned; carries the sim time."""

    def __init__(self, t_s: float, what: str):
        super().__init__(f"simulation diverged at t = {t_s:.4f} s: {what}")
        self.t_s = t_s


@dataclass(frozen=True)
class Pose2D:
    """Planar pose in the world (REP-103): x_m, y_m, yaw_rad."""

    x_m: float
    y_m: float
    yaw_rad: float


class Physics:
    """A compiled model with its data, addressed by the names of the robot ``prefix...``.

    ``data``: the MjData of another robot's Physics in the same world (:meth:`robot`); None: a new
    one, brought to its start (``mj_forward``). Stepping (:meth:`step`, :meth:`settle`,
    :meth:`forward`) acts on the whole world: in a world of several robots one owner (the world)
    steps it once, through any robot's Physics; the rest read and actuate their own robot."""

    def __init__(
        self,
        model: mujoco.MjModel,
        prefix: str = ROBOT_PREFIX,
        data: mujoco.MjData | None = None,
    ):
        m = self.model = model
        self.prefix = prefix
        """What the robot's names begin with (``amr/``, a fleet's ``amr-2/``)."""
        self.data = mujoco.MjData(m) if data is None else data

        def _id(m: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
            i = mujoco.mj_name2id(m, kind, prefix + name)
            if i < 0:
                raise KeyError(f"model has no {kind.name[6:].lower()} named {prefix + name}")
            return i

        J = mujoco.mjtObj.mjOBJ_JOINT
        self.root_qpos = m.jnt_qposadr[_id(m, J, "root")]
        self.root_dof = m.jnt_dofadr[_id(m, J, "root")]
        self.wheel_qpos = np.array([m.jnt_qposadr[_id(m, J, f"wheel_{s}_joint")] for s in WHEELS])
        self.wheel_dof = np.array([m.jnt_dofadr[_id(m, J, f"wheel_{s}_joint")] for s in WHEELS])
        self.wheel_joint = [_id(m, J, f"wheel_{s}_joint") for s in WHEELS]
        self._wheel_limited = [int(m.jnt_limited[j]) for j in self.wheel_joint]
        self._wheel_range = [m.jnt_range[j].copy() for j in self.wheel_joint]
        self._wheel_dof_l, self._wheel_dof_r = (int(v) for v in self.wheel_dof)
        self.caster_qpos = np.array(
            [m.jnt_qposadr[_id(m, J, f"caster_{c}_joint")] for c in CASTERS]
        )
        self.actuator = np.array(
            [_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, f"motor_{s}") for s in WHEELS]
        )
        self.base_body = _id(m, mujoco.mjtObj.mjOBJ_BODY, "base_link")
        b = self.base_body
        self.payload = Payload(m, b)
        """A load on the deck (:meth:`~amr_twin.sim.payload.Payload.set_kg`)."""
        G = mujoco.mjtObj.mjOBJ_GEOM
        geoms = {f"wheel_{s}": _id(m, G, f"wheel_{s}_collision") for s in WHEELS}
        geoms.update({f"caster_{c}": _id(m, G, f"caster_{c}_ball") for c in CASTERS})
        self.support = Support(m, self.data, geoms)
        """The wheels and caster balls on the ground (:class:`~amr_twin.sim.support.Support`)."""
        own_qpos, own_dof = robot_indices(m, self.base_body)
        self.placement = Placement(m, self.data, self.root_qpos, self.wheel_qpos, own_qpos, own_dof)
        """Teleporting the robot (:meth:`~amr_twin.sim.placement.Placement.place`)."""
        adr = int(m.sensor_adr[_id(m, mujoco.mjtObj.mjOBJ_SENSOR, "wheel_left_angle")])
        self.loop_columns = slice(adr, adr + LOOP_SENSOR_DIM)
        """Where the robot's loop sensors lie in ``sensordata`` (and in a grid loop's rows that
        begin at its start: :class:`~amr_twin.sim.grid_loop.GridLoop`)."""
        self.motors = Motors(m, self.data, self.actuator)
        """The wheel motors' modes (:meth:`~amr_twin.sim.motors.Motors.set`)."""
        self.tyres_engine = None
        """What computes the brush tyres' forces (:mod:`amr_twin.sim.tyres`): ``"C"``, ``"Python
        (...)"``, or None for the rigid contact (``wheel.tyre_slip`` off)."""
        if mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, numeric_name(prefix)) >= 0:
            from amr_twin.sim import tyres

            self.tyres_engine = tyres.install()
        if data is None:
            mujoco.mj_forward(m, self.data)

    def robot(self, prefix: str) -> "Physics":
        """The Physics of the robot ``prefix...`` of this world: the same model and data."""
        return Physics(self.model, prefix, self.data)

    def set_floor_friction(self, field) -> None:
        """Give the brush tyres the floor's friction field
        (:class:`~amr_twin.sim.floor_friction.FrictionField`, or None for ``wheel.friction``
        everywhere); ValueError with the rigid contact."""
        from amr_twin.sim.floor_friction import set_friction_field

        set_friction_field(
            self.model,
            self.data,
            *((None, None) if field is None else (field.spacing_m, field.values.tolist())),
        )

    def clone(self) -> "Physics":
        """An independent copy in its present state: the model and the data (contacts and
        constraint forces included) copied in C, the names' addresses shared. Stepping the
        copy gives the same bits as stepping this one."""
        twin = copy.copy(self)
        twin.model = copy.copy(self.model)
        twin.data = copy.copy(self.data)
        for part in ("motors", "payload", "placement", "support"):  # its own, on the copies
            own = copy.copy(getattr(self, part))
            own.model = twin.model
            if hasattr(own, "data"):
                own.data = twin.data
            setattr(twin, part, own)
        return twin

    @property
    def named(self) -> NamedIndex:
        """Named views of the model and data: ``named.data.qpos["amr/wheel_left_joint"]``
        (:mod:`amr_twin.sim.named_index`)."""
        named = self.__dict__.get("_named")
        if named is None or named.data._struct is not self.data:  # a clone has data of its own
            named = self._named = NamedIndex(self.model, self.data)
        return named

    def forward(self) -> None:
        """Recompute the derived quantities (positions, contacts, sensors) of the present state
        (``mj_forward``)."""
        mujoco.mj_forward(self.model, self.data)

    # -- time and stepping ----------------------------------------------------------
    @property
    def timestep_s(self) -> float:
        return float(self.model.opt.timestep)

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    def step(self, nstep: int = 1) -> None:
        """Advance ``nstep`` physics steps in C with the actuation held."""
        mujoco.mj_step(self.model, self.data, nstep)

    def check(self) -> None:
        """Raise :class:`DivergenceError` on NaN/inf state or any MuJoCo warning."""
        d = self.data
        if not (np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all()):
            raise DivergenceError(self.time_s, "non-finite state")
        counts = d.warning.number  # one vectorised read (a loop over the list costs ~150 us)
        if counts.any():
            i = int(counts.nonzero()[0][0])
            raise DivergenceError(self.time_s, f"MuJoCo warning {mujoco.mjtWarning(i).name}")

    # -- readings -------------------------------------------------------------------
    def wheel_angles_rad(self) -> np.ndarray:
        """(2,) wheel angles [left, right], rad, positive rolling forward."""
        return self.data.qpos[self.wheel_qpos]

    def wheel_speeds_rad_s(self) -> np.ndarray:
        """(2,) wheel angular speeds [left, right], rad/s."""
        return self.data.qvel[self.wheel_dof]

    def wheel_speeds_list(self) -> list[float]:
        """[left, right] wheel angular speeds, rad/s, as plain floats (cheap in scalar code)."""
        qvel = self.data.qvel
        return [qvel.item(self._wheel_dof_l), qvel.item(self._wheel_dof_r)]

    def caster_compression_m(self) -> np.ndarray:
        """(4,) caster spring compressions [fl, fr, rl, rr], m."""
        return self.data.qpos[self.caster_qpos]

    def pose(self) -> Pose2D:
        """Base pose in the world plane."""
        q = self.data.qpos[self.root_qpos : self.root_qpos + 7]
        return Pose2D(float(q[0]), float(q[1]), yaw_of_quaternion(*q[3:7]))

    def site_position_m(self, name: str) -> np.ndarray:
        """(3,) world position of the site ``name`` (e.g. ``amr/laser``), m."""
        return self.data.site(name).xpos.copy()

    def base_velocity(self) -> np.ndarray:
        """(6,) free-joint velocity: linear (world, m/s), angular (body, rad/s)."""
        return self.data.qvel[self.root_dof : self.root_dof + 6].copy()

    def base_tilt_rad(self) -> float:
        """Angle between the base z axis and the world vertical."""
        return math.acos(max(-1.0, min(1.0, self.base_up_z())))

    def base_up_z(self) -> float:
        """World z of the base's z axis: the cosine of :meth:`base_tilt_rad` (one float read)."""
        return self.data.xmat.item(9 * self.base_body + 8)

    def base_velocity_list(self) -> list[float]:
        """:meth:`base_velocity` as a plain list (a sampler's 50 Hz read)."""
        return self.data.qvel[self.root_dof : self.root_dof + 6].tolist()

    def robot_mass_kg(self) -> float:
        return float(self.model.body_subtreemass[self.base_body])

    def com_world_m(self) -> np.ndarray:
        """(3,) centre of mass of the robot (with payload), world frame."""
        return self.data.subtree_com[self.base_body].copy()

    def base_heading_xy(self) -> tuple[float, float, float, float]:
        """Base origin x, y (m) and the world x, y of its x axis (unnormalised when tilted), plain
        floats."""
        b, d = self.base_body, self.data
        return (
            d.xpos.item(3 * b),
            d.xpos.item(3 * b + 1),
            d.xmat.item(9 * b),
            d.xmat.item(9 * b + 3),
        )

    # -- things that move in the world (amr_twin/sim/actors.py) ----------------------------
    def mocap_index(self, body: str) -> int:
        """The mocap index of the world's mocap body ``body`` (an actor: ``person_0``)."""
        m = self.model
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
        if b < 0 or m.body_mocapid[b] < 0:
            raise KeyError(f"model has no mocap body named {body}")
        return int(m.body_mocapid[b])

    def set_mocap_pose(self, body: str | int, x_m: float, y_m: float, yaw_rad: float) -> None:
        """Place the mocap body ``body`` (name, or :meth:`mocap_index`) on the floor at ``x_m, y_m``
        heading ``yaw_rad``; it is there from the next step on."""
        i = body if isinstance(body, int) else self.mocap_index(body)
        h = 0.5 * yaw_rad
        self.data.mocap_pos[i] = (x_m, y_m, 0.0)
        self.data.mocap_quat[i] = (math.cos(h), 0.0, 0.0, math.sin(h))

    # -- faults (amr_twin/sim/fault_injector.py) --------------------------------------------
    def jam_wheel(self, wheel: int, jammed: bool) -> None:
        """Block ``wheel`` where it is (a joint limit of +-1 mrad around its angle), or free it.

        A jammed hub or a stone in the wheel: it turns no further whatever the motor
        or the ground do, until it is freed.
        """
        j = self.wheel_joint[wheel]
        if jammed:
            q = float(self.data.qpos[self.wheel_qpos[wheel]])
            self.model.jnt_range[j] = (q - 1e-3, q + 1e-3)
        self.model.jnt_limited[j] = 1 if jammed else self._wheel_limited[wheel]
        if not jammed:
            self.model.jnt_range[j] = self._wheel_range[wheel]

    def settle(self, duration_s: float = 1.0) -> None:
        """Let the robot come to rest on its wheels and casters (motors braked)."""
        for w in range(2):
            self.motors.set(w, "brake")
        self.step(int(round(duration_s / self.timestep_s)))
        self.check()
