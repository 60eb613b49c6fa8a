"""UWB two-way ranging: a Decawave DWM1000 tag on the robot and fixed anchors in the warehouse.

The thesis (§6.2.2, figs. 6.6 and 6.7) fuses UWB with odometry and the IMU but says
nothing of the hardware; the model is a DW1000 tag ranging to ``n`` anchors with
double-sided two-way ranging (Decawave APS013). The parameters and their sources
are in the ``uwb:`` section of ``models/amr/amr.yaml``.

Reasons and measurements: docs/explanation/fusion.md#amr_twinsensorsuwb.

Part of the physics layer (``PHYSICS_LAYER``): a sensor: reads the tag's pose from MjData and casts
each tag-anchor line with ``mj_ray``."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config_sensors import UwbCfg
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.sensor_messages import Range
from amr_twin.ros.ros_state import anchor_transforms
from amr_twin.sim.robot_bodies import OwnGeoms
from amr_twin.sensors.uwb_errors import corrupt_range, corrupt_ranges

PHYSICS_LAYER = True

US = 1_000_000
TOPIC = "uwb/range"
FRAME_PREFIX = "uwb_anchor_"
FIELD_OF_VIEW_RAD = 2.0 * math.pi


def anchor_frame(index: int) -> str:
    """``header.frame_id`` of the ranges to anchor ``index``."""
    return f"{FRAME_PREFIX}{int(index)}"


def anchor_index(frame_id: str) -> int:
    """Anchor index from a ``"uwb_anchor_<i>"`` frame id; ValueError otherwise."""
    if not frame_id.startswith(FRAME_PREFIX) or not frame_id[len(FRAME_PREFIX) :].isdigit():
        raise ValueError(f"header.frame_id: {frame_id!r} is not '{FRAME_PREFIX}<i>'")
    return int(frame_id[len(FRAME_PREFIX) :])


def tag_positions_m(pose: np.ndarray, tag_pos_m) -> np.ndarray:
    """World (x, y) of the tag for base poses ``pose``.

    Parameters
    ----------
    pose : ndarray, shape (N, 3)
        Base poses [x_m, y_m, yaw_rad] in the world frame.
    tag_pos_m : sequence of 2 or 3 float
        Tag position in ``base_link``, m (z ignored).

    Returns
    -------
    ndarray, shape (N, 2)
        Tag position in the world frame, m.
    """
    pose = np.atleast_2d(np.asarray(pose, dtype=np.float64))
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    tx, ty = float(tag_pos_m[0]), float(tag_pos_m[1])
    return np.column_stack((pose[:, 0] + c * tx - s * ty, pose[:, 1] + s * tx + c * ty))


def _message(seq: int, stamp: Time, index: int, range_m: float, cfg: UwbCfg) -> Range:
    return Range(
        header=Header(seq, stamp, anchor_frame(index)),
        radiation_type=Range.INFRARED,
        field_of_view=FIELD_OF_VIEW_RAD,
        min_range=0.0,
        max_range=cfg.max_range_m,
        range=float(range_m),
    )


def simulate_ranges(
    t_s: np.ndarray,
    tag_xy_m: np.ndarray,
    anchors_xy_m: np.ndarray,
    cfg: UwbCfg,
    rng: np.random.Generator,
    anchor: np.ndarray | None = None,
) -> list[Range]:
    """UWB range messages for known tag positions, offline.

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Exchange times, s.
    tag_xy_m : ndarray, shape (N, 2)
        Tag position in the world frame at each time, m (height ``cfg.tag_pos_m[2]``;
        see :func:`tag_positions_m` for base poses).
    anchors_xy_m : ndarray, shape (M, 2)
        Anchor positions in the world frame, m (height ``cfg.anchor_z_m``).
    cfg : UwbCfg
        Error parameters.
    rng : numpy.random.Generator
        Source of all draws (:func:`~amr_twin.sensors.uwb_errors.corrupt_ranges`).
    anchor : ndarray of int, shape (N,), optional
        The anchor ranged at each time (round-robin). Default: every anchor at every
        time, in anchor order.

    Returns
    -------
    list of Range
        The received ranges in time order (dropped ones are absent).
    """
    t_s = np.asarray(t_s, dtype=np.float64).ravel()
    tag = np.asarray(tag_xy_m, dtype=np.float64).reshape(-1, 2)
    anchors = np.asarray(anchors_xy_m, dtype=np.float64).reshape(-1, 2)
    if tag.shape[0] != t_s.shape[0]:
        raise ValueError(f"tag_xy_m: {tag.shape[0]} rows, expected one per time ({t_s.shape[0]})")
    if anchor is None:
        rows = np.repeat(np.arange(t_s.shape[0]), anchors.shape[0])
        idx = np.tile(np.arange(anchors.shape[0]), t_s.shape[0])
    else:
        rows, idx = np.arange(t_s.shape[0]), np.asarray(anchor, dtype=np.int64).ravel()
        if idx.shape[0] != t_s.shape[0] or np.any((idx < 0) | (idx >= anchors.shape[0])):
            raise ValueError(f"anchor: one index in [0, {anchors.shape[0] - 1}] per time expected")
    dz = cfg.anchor_z_m - cfg.tag_pos_m[2]
    d = np.sqrt(np.sum((tag[rows] - anchors[idx]) ** 2, axis=1) + dz * dz)
    r, ok = corrupt_ranges(d, cfg, rng)
    return [
        _message(k, Time.from_sec(t_s[rows[k]]), int(idx[k]), r[k], cfg) for k in np.flatnonzero(ok)
    ]


class UwbSensor:
    """The UWB tag on the robot in a compiled twin, ranging round-robin on the clock.

    Parameters
    ----------
    physics : amr_twin.sim.physics.Physics
        The compiled twin, with a body named ``body``.
    clock : VirtualClock
        Shared clock; one event per exchange (``rate_hz * n_anchors`` per second).
    bus : Bus
        Publishes ``uwb/range`` (``sensor_msgs/Range``).
    cfg : UwbCfg
        Anchors, tag position and error model (``uwb:`` section).
    seed : int, sequence of int or None
        Seed of the ``numpy.random.Generator``.
    body : str
        MuJoCo name of ``base_link`` (default: its robot's, ``<prefix>base_link``).
    autostart : bool
        Schedule the first exchange at the next slot of the time grid.
    walls : bool
        Cast each tag-anchor line against the world's geoms (group 0) and apply the
        blocked-path bias and loss (module notes); False: line of sight everywhere.

    ``blocked`` counts the exchanges per anchor whose line a wall blocked.
    """

    def __init__(
        self,
        physics,
        clock: VirtualClock,
        bus: Bus,
        cfg: UwbCfg,
        seed=0,
        body: str | None = None,
        autostart: bool = True,
        walls: bool = True,
    ):
        model, data = physics.model, physics.data
        self.model, self.data, self.clock, self.bus, self.cfg = model, data, clock, bus, cfg
        self.walls = bool(walls)
        self._groups = np.zeros(6, dtype=np.uint8)
        self._groups[0] = 1  # the world's geoms: not the robot (1, 2), not a payload (4)
        self._geomid = np.zeros(1, dtype=np.int32)
        self.body_id = int(model.body(physics.prefix + "base_link" if body is None else body).id)
        self._own = OwnGeoms(model, self.body_id)  # other robots block the line, its own never
        self._groups = self._own.seeing_others(self._groups)
        self.rng = np.random.default_rng(seed)
        self.anchors_xyz_m = np.column_stack(
            (cfg.anchors_xy_m, np.full(len(cfg.anchors_x_m), cfg.anchor_z_m))
        )
        self.tag_pos_m = np.asarray(cfg.tag_pos_m, dtype=np.float64)
        self.n_anchors = self.anchors_xyz_m.shape[0]
        self.slot_us = int(round(US / (cfg.rate_hz * self.n_anchors)))
        self.pub = bus.advertise(TOPIC, Range)
        bus.send_transform(anchor_transforms(self.anchors_xyz_m, FRAME_PREFIX + "{}"), static=True)
        self.seq = 0
        self.exchanges = 0
        self.blocked = np.zeros(self.n_anchors, dtype=np.int64)
        self._handle = None
        if autostart:
            self.start()

    def start(self) -> None:
        """Start ranging at the next multiple of the slot time, then every slot."""
        if self._handle is None:
            self._handle = self.clock.schedule(
                -(-self.clock.now_us // self.slot_us) * self.slot_us, self._tick
            )

    def stop(self) -> None:
        """Stop ranging."""
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def tag_world_m(self) -> np.ndarray:
        """Tag position in the world frame now, shape (3,), m."""
        b = self.body_id
        return self.data.xpos[b] + self.data.xmat[b].reshape(3, 3) @ self.tag_pos_m

    def true_ranges_m(self) -> np.ndarray:
        """True distances from the tag to every anchor now, shape (n_anchors,), m."""
        return np.linalg.norm(self.anchors_xyz_m - self.tag_world_m(), axis=1)

    def _tick(self) -> None:
        self._handle = self.clock.schedule(self.clock.now_us + self.slot_us, self._tick)
        index = self.exchanges % self.n_anchors
        self.exchanges += 1
        tag = self.tag_world_m()
        line = self.anchors_xyz_m[index] - tag
        d = np.linalg.norm(line)
        blocked = None
        if self.walls:
            with self._own:
                hit = mujoco.mj_ray(
                    self.model, self.data, tag, line, self._groups, 1, -1, self._geomid
                )
            blocked = (
                0.0 <= hit < 1.0
            )  # a surface between tag and anchor (hit in units of the line)
            self.blocked[index] += int(blocked)
        r, ok = corrupt_range(d, self.cfg, self.rng, blocked)
        if ok:
            self.pub.publish(
                _message(self.seq, Time.from_us(self.clock.now_us), index, r, self.cfg)
            )
            self.seq += 1
