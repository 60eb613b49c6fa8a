"""The robot's state as ROS messages: static frames, joint states, link transforms, ground truth,
clock.

What ``robot_state_publisher``, a ``joint_state_broadcaster``, Gazebo's ``p3d``
plugin and ``/clock`` would give a ROS user of the twin, built from MuJoCo's state
into the message types of :mod:`amr_twin.ros.messages` (one source for the bus and the
recordings; :mod:`amr_twin.ros.ros2_cdr` encodes them).

Frames (REP-105). One tree per root, every frame with one parent::

    odom -> base_link                       wheel odometry (controllers/odometry.py), /tf
    base_link -> laser, imu_link, uwb_tag   fixed joints of the URDF, /tf_static
    base_link -> wheel_*_link, caster_*_link   moving joints of the URDF, /tf (joint states)
    map -> uwb_anchor_<i>                   the UWB anchors, surveyed in the map, /tf_static

``odom`` has no parent in the twin's own messages: ``map -> odom`` is a localiser's
(slam_toolbox, AMCL, robot_localization with UWB). The twin's ``map`` is its world
frame, in which the anchors and the warehouse map are given. The true pose is not
a tf frame: it goes on ``twin/ground_truth`` (``nav_msgs/Odometry`` in ``world``,
which no transform names).

:class:`StateSampler` keeps the raw state on the loop's grid (a grid sampler: no
clock event, the run is unchanged); the functions turn one sample into messages.
"""

from __future__ import annotations

import copy

import numpy as np

from amr_twin.ros.tf_buffer import BASE_FRAME
from amr_twin.ros.geometry_messages import (
    Odometry,
    Point,
    Pose,
    PoseWithCovariance,
    Quaternion,
    TFMessage,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from amr_twin.ros.messages import Clock, Header, Time
from amr_twin.ros.sensor_messages import JointState

ROBOT = "amr/"
"""Prefix of the robot's MuJoCo names (build.py)."""
WORLD_FRAME = "world"
MAP_FRAME = "map"
FIXED_LINKS = ("laser", "imu_link", "uwb_tag")
"""Links on fixed joints of base_link (static transforms)."""
MOVING_JOINTS = (
    "wheel_left_joint",
    "wheel_right_joint",
    "caster_front_left_joint",
    "caster_front_right_joint",
    "caster_rear_left_joint",
    "caster_rear_right_joint",
)
"""The URDF's non-fixed joints, in ``sensor_msgs/JointState`` order."""
_ZERO36 = np.zeros(36)
_ZERO36.flags.writeable = False


def _quat(wxyz) -> Quaternion:
    w, x, y, z = wxyz
    return Quaternion(float(x), float(y), float(z), float(w))


def frame_transform(parent: str, child: str, xyz, wxyz, stamp: Time = Time()) -> TransformStamped:
    """``parent -> child`` at ``xyz`` (m) turned by the quaternion ``wxyz``."""
    x, y, z = xyz
    return TransformStamped(
        Header(0, stamp, parent),
        child,
        Transform(Vector3(float(x), float(y), float(z)), _quat(wxyz)),
    )


def robot_static_transforms(model, prefix: str = ROBOT) -> list[TransformStamped]:
    """``base_link -> laser, imu_link, uwb_tag`` from the compiled model (the URDF's fixed
    joints) of the robot named ``prefix...`` (``amr-2/`` in a fleet)."""
    import mujoco

    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, prefix + BASE_FRAME)
    out = []
    for link in FIXED_LINKS:
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, prefix + link)
        if b >= 0 and model.body_parentid[b] == base:
            out.append(frame_transform(BASE_FRAME, link, model.body_pos[b], model.body_quat[b]))
    return out


def anchor_transforms(
    anchors_xyz_m: np.ndarray, frame: str = "uwb_anchor_{}"
) -> list[TransformStamped]:
    """``map -> uwb_anchor_<i>`` at the anchors' positions (K, 3), m, axes as the map's."""
    return [
        frame_transform(MAP_FRAME, frame.format(i), xyz, (1.0, 0.0, 0.0, 0.0))
        for i, xyz in enumerate(np.asarray(anchors_xyz_m, float).reshape(-1, 3))
    ]


_QMUL_A = [np.array(i) for i in ([0, 0, 0, 0], [1, 1, 1, 1], [2, 2, 2, 2], [3, 3, 3, 3])]
_QMUL_B = [np.array(i) for i in ([0, 1, 2, 3], [1, 0, 3, 2], [2, 3, 0, 1], [3, 2, 1, 0])]
_QMUL_SIGN = [np.array(s, float) for s in ([-1, 1, -1, 1], [-1, 1, 1, -1], [-1, -1, 1, 1])]


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion products (..., 4) w, x, y, z: each component the sum, left to right, of four
    signed products (``aw bw - ax bx - ay by - az bz``, ...), the four components at once."""
    out = a[..., _QMUL_A[0]] * b[..., _QMUL_B[0]]
    for ia, ib, sign in zip(_QMUL_A[1:], _QMUL_B[1:], _QMUL_SIGN):
        out += sign * (a[..., ia] * b[..., ib])
    return out


_C1, _C2 = np.array([1, 2, 0]), np.array([2, 0, 1])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of (..., 3) vectors, the same operations (bit for bit) without its axis
    handling."""
    return a[..., _C1] * b[..., _C2] - a[..., _C2] * b[..., _C1]


def _rotate_inv(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``R(q)^T v`` for unit quaternions q (..., 4) w, x, y, z and vectors v (..., 3)."""
    w, u = q[..., :1], -q[..., 1:]
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


class StateSampler:
    """The robot's joint, link and base state on the loop's record grid.

    :attr:`sample` is the grid sampler (``sample(t_us)``, the physics at ``t_us``): a
    :class:`~amr_twin.sim.grid_rows.GridRows` of the 67 values of a row (joint positions and
    speeds, the base's twist, the positions and orientations of base_link and the six moving links)
    read through the physics' named views (their ``value_rows``): its C form
    gathers them where they lie, so that a twin keeping this state (a ROS 1 or Foxglove bridge)
    still runs its grid loop in C.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled twin (robot names prefixed ``amr/``): ``twin.observables.model``.
    named : NamedIndex of the physics (``amr_twin.sim.named_index``)
        Its named views: ``twin.observables.named``.
    native : bool
        Give the sampler its C form (False: Python only, the same values).
    prefix : str
        The robot's name prefix in the model (``amr-2/`` in a fleet).
    """

    def __init__(self, model, named, native: bool = True, prefix: str = ROBOT):
        import mujoco

        self.joint_names = MOVING_JOINTS
        joints = [
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, prefix + j) for j in MOVING_JOINTS
        ]
        self.child_frames = tuple(
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])[len(prefix) :]
            for j in joints
        )
        joint_names = [prefix + j for j in MOVING_JOINTS]
        bodies = [prefix + BASE_FRAME, *(prefix + f for f in self.child_frames)]
        root = named.data.qvel.index(prefix + "root")  # the free joint's six dofs
        d = named.data
        self.sample = named.value_rows(
            [
                (d.qpos, joint_names),
                (d.qvel, joint_names),
                (d.qvel, root),
                (d.xpos, bodies),
                (d.xquat, bodies),
            ],
            native=native,
        )
        """The grid sampler: ``sample(t_us)`` keeps the state now (the physics at ``t_us``). Where
        the loop's grid runs in Python (a collision open) its row is the C form's too: one ctypes
        call (2 us against 8 us)."""
        self._taken: np.ndarray | None = None  # a split-off batch's rows (split)

    def _table(self) -> np.ndarray:
        return self._taken if self._taken is not None else self.sample.rows

    @property
    def table(self) -> np.ndarray:
        """The samples kept, a row each: the instant (us), then :attr:`sample`'s 67 values."""
        return self._table()

    @property
    def t_us(self) -> list[int]:
        """The instants kept, us."""
        return self._table()[:, 0].astype(np.int64).tolist()

    def __len__(self) -> int:
        return len(self._table())

    def split(self, t_us: int) -> "StateSampler":
        """The samples at or before ``t_us``, removed from this sampler, as a sampler of their own
        (a live viewer takes them as the clock passes them; :mod:`amr_twin.live.foxglove`)."""
        out = copy.copy(self)
        out._taken = self.sample.take_until(t_us)
        return out

    def arrays(self, period_us: int = 0, base: bool = True) -> dict[str, np.ndarray]:
        """``t_us`` (n,); joint ``q``, ``qd`` (n, 6); base ``v_world``, ``v_body``, ``w_body`` (n,
        3), ``pos`` (n, 3), ``quat`` (n, 4) w, x, y, z in the world; links' ``link_pos`` (n, 6, 3)
        and ``link_quat`` (n, 6, 4) relative to ``base_link``. Only the instants that are multiples
        of ``period_us`` (0: all), and without the base's keys unless ``base`` (numpy's work is per
        call: a bridge taking 50 Hz joint states from 100 Hz samples saves most of it)."""
        table = self._table()
        if period_us:
            table = table[table[:, 0] % period_us == 0]
        rows = table[:, 1:]
        nj, nb = len(self.joint_names), 1 + len(self.child_frames)
        k = 2 * nj + 6
        pos = rows[:, k : k + 3 * nb].reshape(-1, nb, 3)
        quat = rows[:, k + 3 * nb :].reshape(-1, nb, 4)
        base_q = quat[:, :1]
        inv = base_q * np.array([1.0, -1.0, -1.0, -1.0])
        out = {
            "t_us": table[:, 0].astype(np.int64),
            "q": rows[:, :nj],
            "qd": rows[:, nj : 2 * nj],
            "link_pos": _rotate_inv(base_q, pos[:, 1:] - pos[:, :1]),
            "link_quat": _qmul(inv, quat[:, 1:]),
        }
        if base:
            vel = rows[:, 2 * nj : 2 * nj + 6]
            out.update(
                v_world=vel[:, :3],
                v_body=_rotate_inv(quat[:, 0], vel[:, :3]),
                w_body=vel[:, 3:],
                pos=pos[:, 0],
                quat=quat[:, 0],
            )
        return out


def joint_state(t_us: int, names, q, qd) -> JointState:
    """``sensor_msgs/JointState`` of the moving joints: positions (rad, m) and velocities (rad/s,
    m/s)."""
    return JointState(
        Header(0, Time.from_us(t_us), ""),
        list(names),
        np.asarray(q, float),
        np.asarray(qd, float),
        np.zeros(0),
    )


def link_transforms(t_us: int, children, link_pos, link_quat) -> TFMessage:
    """``base_link -> <child>`` of the moving joints' links (what robot_state_publisher sends on
    /tf)."""
    stamp = Time.from_us(t_us)
    return TFMessage(
        [
            frame_transform(BASE_FRAME, c, p, q, stamp)
            for c, p, q in zip(children, link_pos, link_quat)
        ]
    )


def ground_truth(t_us: int, pos, quat, v_body, w_body) -> Odometry:
    """The true pose of ``base_link`` in ``world`` and its twist in ``base_link``
    (``nav_msgs/Odometry``)."""
    return Odometry(
        Header(0, Time.from_us(t_us), WORLD_FRAME),
        BASE_FRAME,
        PoseWithCovariance(Pose(Point(*pos), _quat(quat)), _ZERO36),
        TwistWithCovariance(Twist(Vector3(*v_body), Vector3(*w_body)), _ZERO36),
    )


def clock(t_us: int) -> Clock:
    """``rosgraph_msgs/Clock`` at ``t_us``."""
    return Clock(Time.from_us(t_us))
