"""The RPLIDAR A1's beams cast in MuJoCo: the world and the other robots, never its own robot, and
a payload it carries apart (in the present laser frame).

Reasons and measurements: docs/explanation/lidar.md#amr_twinsensorslidar.

Part of the physics layer (``PHYSICS_LAYER``): casts with ``mj_multiRay`` (or the kernels' cast) on
MjData at each laser pose; the clock-driven sensor is :class:`amr_twin.sensors.lidar.Lidar`."""

from __future__ import annotations

import mujoco
import numpy as np

from amr_twin.sensors.lidar_beams import PoseSamples, group_masks
from amr_twin.sensors.lidar_kernels import CUTOFF_M
from amr_twin.sim.robot_bodies import OwnGeoms

PHYSICS_LAYER = True


class BeamCaster:
    """Casts beams from the laser site ``site_id`` along ``local_dirs`` (n, 3) of the laser frame.

    ``kernels`` (:func:`amr_twin.sensors.lidar_kernels.beam_kernels`) casts each beam at its own
    instant; it is bound here to the site and the geom groups a beam sees.
    """

    def __init__(self, model, data, site_id: int, local_dirs: np.ndarray, kernels):
        self.model, self.data, self.site_id, self.local_dirs = model, data, site_id, local_dirs
        self._kernels = kernels
        moving = model.body_rootid[model.geom_bodyid] != 0  # cast what moves with the robot apart
        self.geomgroup, self._world_groups, self._payload_groups = group_masks(
            model.geom_group, moving
        )
        self._own = OwnGeoms(model, int(model.site_bodyid[site_id]))
        """Its robot's geoms, hidden while it casts: it sees the other robots, never its own."""
        self.geomgroup = self._own.seeing_others(self.geomgroup)
        if self._world_groups is not None:
            self._world_groups = self._own.seeing_others(self._world_groups)
        kernels.bind(
            model,
            data,
            site_id,
            self.geomgroup if self._world_groups is None else self._world_groups,
        )
        n = len(local_dirs)
        self._normal = np.zeros(3 * n)
        self._pdist = np.zeros(n)
        self._pgeom = np.zeros(n, np.int32)
        self._lx, self._ly = local_dirs[:, 0:1].copy(), local_dirs[:, 1:2].copy()  # (n, 1) each

    def cast(
        self,
        start: int,
        stop: int,
        beam_t_us: np.ndarray,
        poses: PoseSamples,
        at_own_instants: bool,
        geomid: np.ndarray,
        dist: np.ndarray,
    ) -> None:
        """Cast beams ``start:stop`` into ``geomid`` and ``dist`` (m, -1 for no hit), shape
        (stop - start,): each from the laser pose at its instant ``beam_t_us[i]``, us (from
        ``poses``), with ``at_own_instants`` and samples kept; otherwise all from the pose now."""
        with self._own:
            self._cast(start, stop, beam_t_us, poses, at_own_instants, geomid, dist)

    def _cast(self, start, stop, beam_t_us, poses, at_own_instants, geomid, dist) -> None:
        m, d, s, k = self.model, self.data, self.site_id, stop - start
        if at_own_instants and poses.n > 0:  # origins and directions at the beams' instants
            self._kernels.cast(
                beam_t_us[start:stop],
                self._lx[start:stop],
                self._ly[start:stop],
                poses.rows,
                poses.n,
                dist,
                geomid,
            )
        else:
            u = self.local_dirs[start:stop] @ d.site_xmat[s].reshape(3, 3).T
            groups = self.geomgroup if self._world_groups is None else self._world_groups
            mujoco.mj_multiRay(
                m,
                d,
                d.site_xpos[s],
                u.ravel(),
                groups,
                1,
                -1,
                geomid,
                dist,
                self._normal[: 3 * k],
                k,
                CUTOFF_M,
            )
        if self._payload_groups is not None:
            origin = d.site_xpos[s]  # what moves with the robot: the present frame
            u_now = self.local_dirs[start:stop] @ d.site_xmat[s].reshape(3, 3).T
            pgeom, pdist = self._pgeom[:k], self._pdist[:k]
            mujoco.mj_multiRay(
                m,
                d,
                origin,
                u_now.ravel(),
                self._payload_groups,
                1,
                -1,
                pgeom,
                pdist,
                None,
                k,
                CUTOFF_M,
            )
            near = (pgeom >= 0) & ((geomid < 0) | (pdist < dist))
            geomid[near], dist[near] = pgeom[near], pdist[near]
