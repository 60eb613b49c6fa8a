"""The LiDAR's per-beam work in C: directions and origins at the beams' instants, the rays, noise.

Reasons and measurements: docs/explanation/lidar.md#amr_twinsensorslidar_kernels.

Part of the physics layer (``PHYSICS_LAYER``): the LiDAR's ray casts (``mj_multiRay`` on MjData) and
their C arithmetic."""

from __future__ import annotations

import ctypes
from pathlib import Path

import mujoco
import numpy as np

from amr_twin.model.config_sensors import LidarCfg
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import address, c_array, mujoco_address, open_helper
from amr_twin.sensors.lidar_beams import interpolate_poses, quantised_ranges, world_directions

PHYSICS_LAYER = True

C_SOURCE = Path(__file__).with_name("lidar_beams.c")
CUTOFF_M = 1e6
"""Culling distance passed to ``mj_multiRay``: effectively none (ranges are clamped by the noise
model)."""

_P = ctypes.c_void_p


class PythonBeamKernels:
    """The numpy twin of :class:`BeamKernels` (no compiler, ``AMR_TWIN_NATIVE=0``,
    ``native=False``)."""

    def __init__(self, n_beams: int, cfg: LidarCfg, why: str = "native=False"):
        self.cfg = cfg
        self.engine = f"Python ({why})"
        self._normal = np.zeros(3 * n_beams)

    def bind(self, model, data, site: int, groups: np.ndarray) -> None:
        self._bound = (model, data, int(site), groups)

    def cast(
        self,
        t_us: np.ndarray,
        lx: np.ndarray,
        ly: np.ndarray,
        rows: np.ndarray,
        npose: int,
        dist: np.ndarray,
        geomid: np.ndarray,
    ) -> None:
        m, d, _site, groups = self._bound
        u, origin = self.geometry(t_us, lx, ly, rows, npose)
        # one mj_multiRay per run of beams with the same origin (bit for bit: the laser stood
        # still), mj_ray for a beam alone (~5 us in the aisles world against ~100 us for mj_multiRay
        # of one ray)
        change = np.flatnonzero(np.any(origin[1:] != origin[:-1], axis=1)) + 1
        normal = self._normal
        for a, b in zip([0, *change.tolist()], [*change.tolist(), len(u)]):
            if b - a == 1:
                dist[a] = mujoco.mj_ray(
                    m, d, origin[a], u[a], groups, 1, -1, geomid[a:b], normal[:3]
                )
            else:
                mujoco.mj_multiRay(
                    m,
                    d,
                    origin[a],
                    u[a:b].ravel(),
                    groups,
                    1,
                    -1,
                    geomid[a:b],
                    dist[a:b],
                    normal[: 3 * (b - a)],
                    b - a,
                    CUTOFF_M,
                )

    def geometry(
        self, t_us: np.ndarray, lx: np.ndarray, ly: np.ndarray, rows: np.ndarray, npose: int
    ) -> tuple[np.ndarray, np.ndarray]:
        pose = interpolate_poses(rows, npose, t_us)
        return world_directions(pose, lx, ly), np.ascontiguousarray(pose[:, 0:3])

    def noise(self, dist: np.ndarray, geomid: np.ndarray, z: np.ndarray) -> np.ndarray:
        return quantised_ranges(dist, geomid, z, self.cfg)


class BeamKernels:
    """The C helper, with its output buffers for up to ``n_beams`` beams (reused: copy what you
    keep).

    Use :func:`beam_kernels` to get this or, without the helper, its Python twin.
    """

    cull = True
    """Cast through ``lb_rays`` (MuJoCo's ``mju_rayGeom`` behind the helper's cull); False:
    ``mj_multiRay`` (for comparisons: the same bits, slower)."""

    def __init__(self, lib: ctypes.PyDLL, n_beams: int, cfg: LidarCfg):
        self.engine = "C"
        self.cfg = cfg
        self._geometry, self._noise = lib.lb_geometry, lib.lb_noise
        self._cast, self._rays = lib.lb_cast, lib.lb_cast_rays
        lib.lb_geom_bytes.restype = ctypes.c_int
        self._geom_bytes = int(lib.lb_geom_bytes())
        self._geometry.argtypes = [ctypes.c_int, _P, _P, _P, _P, ctypes.c_int, _P, _P]
        self._noise.argtypes = [ctypes.c_int, _P, _P, _P] + [ctypes.c_double] * 5 + [_P]
        self._cast.argtypes = [_P, _P, _P, ctypes.c_int, _P, _P, _P, _P, ctypes.c_int, _P, _P]
        self._rays.argtypes = [_P, _P, _P, _P, ctypes.c_int, _P, _P, _P]
        for fn in (self._geometry, self._noise, self._cast, self._rays):
            fn.restype = None
        self._u = np.zeros((n_beams, 3))
        self._origin = np.zeros((n_beams, 3))
        self._normal = np.zeros((n_beams, 3))
        self._u_at, self._origin_at = address(self._u), address(self._origin)
        self._noise_args = (
            float(cfg.range_noise_floor_m),
            float(cfg.range_noise_frac),
            float(cfg.range_resolution_m),
            float(cfg.range_min_m),
            float(cfg.range_max_m),
        )

    def bind(self, model, data, site: int, groups: np.ndarray) -> None:
        """Cast in ``model`` and ``data`` from the laser ``site``, seeing the geom ``groups`` (6,)
        uint8."""
        self._groups = np.ascontiguousarray(groups, np.uint8)
        caster = self._caster = _Caster()
        caster.multiray = mujoco_address("mj_multiRay")
        caster.groups, caster.site, caster.cutoff = address(self._groups), int(site), CUTOFF_M
        caster.u, caster.org, caster.normal = self._u_at, self._origin_at, address(self._normal)
        caster.raygeom = mujoco_address("mju_rayGeom") if self.cull else None
        self._seen = np.zeros(max(model.ngeom, 1) * self._geom_bytes, np.uint8)  # lb_geom work rows
        caster.seen = address(self._seen)
        caster.ray = mujoco_address("mj_ray")
        self._keep = (model, data)  # the model and data outlive every call
        self._cast_head = (ctypes.addressof(caster), model._address, data._address)
        self._bound = (model, data, int(site), self._groups)

    def cast(
        self,
        t_us: np.ndarray,
        lx: np.ndarray,
        ly: np.ndarray,
        rows: np.ndarray,
        npose: int,
        dist: np.ndarray,
        geomid: np.ndarray,
    ) -> None:
        _check_outputs(dist, geomid, len(t_us))
        t_us, lx, ly = c_array(t_us, np.int64), c_array(lx, np.float64), c_array(ly, np.float64)
        rows = c_array(rows, np.float64)
        self._cast(
            *self._cast_head,
            len(t_us),
            address(t_us),
            address(lx),
            address(ly),
            address(rows),
            int(npose),
            address(dist),
            address(geomid),
        )

    def rays(
        self, origin: np.ndarray, u: np.ndarray, dist: np.ndarray, geomid: np.ndarray
    ) -> np.ndarray:
        """Cast unit directions ``u`` (k, 3) from ``origin`` (3,), m, as :meth:`cast` does (no
        instants, no correction): ``dist`` (k,) m, -1 for none, and ``geomid`` (k,) written in
        place; returns the hit normals (k, 3), a view of a reused buffer."""
        k = len(u)
        if k > len(self._normal):
            raise ValueError(f"{k} directions: at most n_beams = {len(self._normal)}")
        _check_outputs(dist, geomid, k)
        origin, u = c_array(origin, np.float64), c_array(u, np.float64)
        self._rays(*self._cast_head, address(origin), k, address(u), address(dist), address(geomid))
        return self._normal[:k]

    def geometry(
        self, t_us: np.ndarray, lx: np.ndarray, ly: np.ndarray, rows: np.ndarray, npose: int
    ) -> tuple[np.ndarray, np.ndarray]:
        k = len(t_us)
        u, origin = self._u[:k], self._origin[:k]
        t_us, lx, ly = c_array(t_us, np.int64), c_array(lx, np.float64), c_array(ly, np.float64)
        rows = c_array(rows, np.float64)
        self._geometry(
            k,
            address(t_us),
            address(lx),
            address(ly),
            address(rows),
            int(npose),
            self._u_at,
            self._origin_at,
        )
        return u, origin

    def noise(self, dist: np.ndarray, geomid: np.ndarray, z: np.ndarray) -> np.ndarray:
        n = len(dist)
        out = np.empty(n, np.float32)
        dist, geomid, z = (
            c_array(dist, np.float64),
            c_array(geomid, np.int32),
            c_array(z, np.float64),
        )
        self._noise(n, address(dist), address(geomid), address(z), *self._noise_args, address(out))
        return out


def _check_outputs(dist: np.ndarray, geomid: np.ndarray, k: int) -> None:
    """``dist`` and ``geomid``, written in place by the helper: C-contiguous float64 and int32 of
    length ``k``."""
    if not (
        len(dist) == len(geomid) == k
        and dist.flags.c_contiguous
        and dist.dtype == np.float64
        and geomid.flags.c_contiguous
        and geomid.dtype == np.int32
    ):
        raise ValueError(
            f"dist, geomid: C-contiguous float64 and int32 arrays of length {k} are written in "
            f"place"
        )


class _Caster(ctypes.Structure):
    """``lb_caster`` of lidar_beams.c."""

    _fields_ = [
        ("multiray", _P),
        ("groups", _P),
        ("site", ctypes.c_int),
        ("cutoff", ctypes.c_double),
        ("u", _P),
        ("org", _P),
        ("normal", _P),
        ("raygeom", _P),
        ("seen", _P),
        ("ray", _P),
    ]


register(C_SOURCE, lb_caster=_Caster)


def beam_kernels(
    n_beams: int, cfg: LidarCfg, native: bool = True
) -> BeamKernels | PythonBeamKernels:
    """The C helper when it builds and loads (and ``native``), else its Python twin; ``.engine``
    says which."""
    lib, engine = open_helper(C_SOURCE, native)
    if lib is None:
        return PythonBeamKernels(n_beams, cfg, engine[len("Python (") : -1])
    return BeamKernels(lib, n_beams, cfg)
