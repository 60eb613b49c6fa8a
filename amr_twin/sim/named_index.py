"""Named views of a :class:`~amr_twin.sim.physics.Physics`' MjModel and MjData, after dm_control's
``physics.named``.

``physics.named.data.qpos["amr/wheel_left_joint"]`` is the wheel's angle, rad;
``physics.named.data.xpos["amr/base_link"]`` the base's world position (3,), m;
``physics.named.data.sensordata["amr/imu_gyro"]`` the gyro's three values (a view: writes go
to MjData). A field is indexed by the names of the objects its rows belong to: bodies for
``x*``, ``subtree_*``, ``c*`` and ``*frc_ext``; joints for ``qpos`` (its ``jnt_qposadr``
and width) and for the dof fields (``qvel``, ``qacc``, ``qfrc_*``, ``dof_*``: its
``jnt_dofadr`` and width); sensors for ``sensordata`` (``sensor_adr``, ``sensor_dim``); the
mocap bodies' names for ``mocap_*``; the prefix names the rest (``geom_``, ``site_``,
``actuator_``, ``jnt_``, ``body_``, ...). A list of names gives their values in that order;
anything else (an int, a slice, an index array) indexes the array as it is. A field of
width 1 per name (a hinge's ``qpos``, a one-value sensor) gives a scalar.

:meth:`NamedArray.addresses` gives where the selected values lie (a C row keeper's
pointers, :func:`amr_twin.sim.grid_rows.gather`); :meth:`NamedIndex.value_rows` keeps a selection
of them on the loop's grid.

Part of the physics layer (``PHYSICS_LAYER``): this is the door through which the rest of
the twin reads and writes MuJoCo's state by name.
"""

from __future__ import annotations

import mujoco
import numpy as np

from amr_twin.sim.grid_rows import GridRows, gather
from amr_twin.base.native_build import address

PHYSICS_LAYER = True

_O = mujoco.mjtObj
_BODY_FIELDS = (
    "xpos",
    "xquat",
    "xmat",
    "xipos",
    "ximat",
    "xiquat",
    "subtree_com",
    "subtree_linvel",
    "subtree_angmom",
    "cinert",
    "cvel",
    "cacc",
    "cfrc_int",
    "cfrc_ext",
    "xfrc_applied",
    "crb",
)
_DOF_FIELDS = ("qvel", "qacc", "qacc_smooth", "qacc_warmstart")
_DATA_OBJECTS = {
    "ctrl": _O.mjOBJ_ACTUATOR,
    "act": _O.mjOBJ_ACTUATOR,
    "eq_active": _O.mjOBJ_EQUALITY,
    "xanchor": _O.mjOBJ_JOINT,
    "xaxis": _O.mjOBJ_JOINT,
}
_PREFIXES = (
    ("body_", _O.mjOBJ_BODY),
    ("jnt_", _O.mjOBJ_JOINT),
    ("geom_", _O.mjOBJ_GEOM),
    ("site_", _O.mjOBJ_SITE),
    ("cam_", _O.mjOBJ_CAMERA),
    ("light_", _O.mjOBJ_LIGHT),
    ("actuator_", _O.mjOBJ_ACTUATOR),
    ("sensor_", _O.mjOBJ_SENSOR),
    ("eq_", _O.mjOBJ_EQUALITY),
    ("tendon_", _O.mjOBJ_TENDON),
    ("ten_", _O.mjOBJ_TENDON),
    ("mat_", _O.mjOBJ_MATERIAL),
    ("mesh_", _O.mjOBJ_MESH),
    ("numeric_", _O.mjOBJ_NUMERIC),
    ("hfield_", _O.mjOBJ_HFIELD),
    ("tex_", _O.mjOBJ_TEXTURE),
    ("key_", _O.mjOBJ_KEY),
)
_QPOS_WIDTH = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
_DOF_WIDTH = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}


def _rows(model: mujoco.MjModel, field: str, in_data: bool):
    """``index(name)`` of ``field``'s rows: an int, or a slice for a joint's or a sensor's several
    values."""

    def object_id(kind, name: str) -> int:
        i = mujoco.mj_name2id(model, kind, name)
        if i < 0:
            raise KeyError(f"{field}: the model has no {kind.name[6:].lower()} named {name!r}")
        return i

    def joint_values(name: str, adr, widths) -> int | slice:
        j = object_id(_O.mjOBJ_JOINT, name)
        start, width = int(adr[j]), widths.get(int(model.jnt_type[j]), 1)
        return start if width == 1 else slice(start, start + width)

    if field in ("qpos", "qpos0", "qpos_spring"):
        return lambda name: joint_values(name, model.jnt_qposadr, _QPOS_WIDTH)
    if field in _DOF_FIELDS or field.startswith(("qfrc_", "dof_")):
        return lambda name: joint_values(name, model.jnt_dofadr, _DOF_WIDTH)
    if field == "sensordata":

        def sensor(name: str) -> int | slice:
            s = object_id(_O.mjOBJ_SENSOR, name)
            start, dim = int(model.sensor_adr[s]), int(model.sensor_dim[s])
            return start if dim == 1 else slice(start, start + dim)

        return sensor
    if field.startswith("mocap_"):

        def mocap(name: str) -> int:
            i = int(model.body_mocapid[object_id(_O.mjOBJ_BODY, name)])
            if i < 0:
                raise KeyError(f"{field}: body {name!r} is not a mocap body")
            return i

        return mocap
    kind = _DATA_OBJECTS.get(field) if in_data else None
    if kind is None and in_data and (field in _BODY_FIELDS):
        kind = _O.mjOBJ_BODY
    if kind is None and in_data and field.startswith("actuator_"):
        kind = _O.mjOBJ_ACTUATOR
    if kind is None:
        kind = next((k for prefix, k in _PREFIXES if field.startswith(prefix)), None)
    if kind is None:
        return None
    return lambda name: object_id(kind, name)


class NamedArray:
    """One field of MjModel or MjData, indexed by names (see the module notes); ``array`` is the
    field itself."""

    __slots__ = ("array", "field", "_index")

    def __init__(self, array: np.ndarray, field: str, index):
        self.array, self.field, self._index = array, field, index

    def index(self, key):
        """What ``key`` (a name, a list of names, or a positional index) selects in
        :attr:`array`."""
        if isinstance(key, str):
            if self._index is None:
                raise KeyError(f"{self.field} has no names")
            return self._index(key)
        if isinstance(key, (list, tuple)) and key and all(isinstance(k, str) for k in key):
            parts = [self.index(k) for k in key]
            if all(isinstance(p, int) for p in parts):
                return np.array(parts, dtype=np.intp)
            return np.concatenate(
                [np.arange(p.start, p.stop) if isinstance(p, slice) else [p] for p in parts]
            )
        return key

    def __getitem__(self, key):
        return self.array[self.index(key)]

    def __setitem__(self, key, value) -> None:
        self.array[self.index(key)] = value

    def addresses(self, key) -> list[int]:
        """Where the values ``self[key]`` lie, in their order: byte addresses of float64s (a C row
        keeper's)."""
        if self.array.dtype != np.float64 or not self.array.flags.c_contiguous:
            raise TypeError(f"{self.field}: addresses of float64 C arrays only")
        flat = np.arange(self.array.size).reshape(self.array.shape)[self.index(key)]
        base = address(self.array)
        return [base + 8 * int(i) for i in np.ravel(flat)]


class _Struct:
    """``named.data`` or ``named.model``: a :class:`NamedArray` per array field, made at first
    use."""

    def __init__(self, struct, model: mujoco.MjModel, in_data: bool):
        self._struct, self._model, self._in_data, self._fields = struct, model, in_data, {}

    def __getattr__(self, field: str) -> NamedArray:
        if field.startswith("_"):
            raise AttributeError(field)
        named = self._fields.get(field)
        if named is None:
            array = getattr(self._struct, field)
            if not isinstance(array, np.ndarray):
                raise AttributeError(f"{field} is not an array field")
            named = self._fields[field] = NamedArray(
                array, field, _rows(self._model, field, self._in_data)
            )
        return named


class NamedIndex:
    """``named.model`` and ``named.data`` of one model and its data (``Physics.named``)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        self.model = _Struct(model, model, in_data=False)
        self.data = _Struct(data, model, in_data=True)

    @staticmethod
    def value_rows(named_arrays: list[tuple[NamedArray, object]], native: bool = True) -> GridRows:
        """A grid sampler (:class:`~amr_twin.sim.grid_rows.GridRows`) keeping at each grid instant
        the values ``array[key]`` of each ``(array, key)`` in ``named_arrays``, in order: gathered
        in C where they lie when the loop runs its grid there and (one ctypes call) in Python too,
        or read from the arrays without the helper or with ``native=False``: the same values."""
        pointers = [p for array, key in named_arrays for p in array.addresses(key)]
        c_row = gather(pointers) if native else None
        if c_row is not None:
            row = _calling(c_row, len(pointers))
        else:
            views = [(array.array, array.index(key)) for array, key in named_arrays]

            def row() -> list[float]:
                return np.concatenate([np.ravel(a[i]) for a, i in views]).tolist()

        return GridRows(len(pointers), 1, row, c_row)


def _calling(c_row: tuple, width: int):
    """A Python row function calling the C form ``c_row`` (:func:`amr_twin.sim.grid_rows.gather`'s)
    itself."""
    import ctypes

    fn, *args = c_row
    call = ctypes.cast(fn, ctypes.CFUNCTYPE(None, *[ctypes.c_void_p] * 4))
    a0, a1, a2 = (arg if isinstance(arg, int) else ctypes.addressof(arg) for arg in args)
    values = np.zeros(width)
    out = address(values)

    def row() -> list[float]:
        call(a0, a1, a2, out)
        return values.tolist()

    row.keep = (c_row, values)  # what the addresses point into outlives the function
    return row
